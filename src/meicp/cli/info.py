"""``meicp info [--check]``."""

from __future__ import annotations

from ..core.log import rank0_print
from ..info import collect, format_report
from ..petsc.selfcheck import ghep_selfcheck
from .arguments import verbosity
from .exit import Exit


def register(sub) -> None:
    p = sub.add_parser("info", help="versions of Python, NumPy, PETSc, SLEPc, MPI, h5py; MPI ranks")
    p.add_argument("--check", action="store_true",
                   help="also solve a small distributed eigenproblem and compare it with SciPy")
    verbosity(p)
    p.set_defaults(run=run)


def run(args) -> int:
    report = collect()
    rank0_print(format_report(report))
    if args.check:
        from mpi4py import MPI

        r = ghep_selfcheck(MPI.COMM_WORLD)
        ok = r["max_rel_error"] < 1e-10 and r["max_residual"] < 1e-8
        rank0_print(
            f"\nself-check: {len(r['slepc'])} smallest eigenvalues of a "
            f"{r['n']}-DOF pencil, SLEPc on {r['ranks']} rank(s) vs SciPy eigh: "
            f"max relative error {r['max_rel_error']:.2e}, SLEPc residual {r['max_residual']:.2e}, "
            f"solve {r['solve_s'] * 1e3:.1f} ms -> {'OK' if ok else 'FAILED'}")
        return Exit.OK if ok else Exit.FAILED
    return Exit.OK


