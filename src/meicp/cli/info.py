"""``meicp info [--check] [--json]``."""

from __future__ import annotations

from ..core.log import rank0_print
from ..info import collect, format_report
from ..petsc.selfcheck import ghep_selfcheck
from .arguments import verbosity
from .exit import Exit
from .output import json_header, print_json


def register(sub) -> None:
    p = sub.add_parser("info", help="versions of Python, NumPy, PETSc, SLEPc, MPI, h5py; MPI ranks")
    p.add_argument("--check", action="store_true",
                   help="also solve a small distributed eigenproblem and compare it with SciPy")
    p.add_argument("--json", action="store_true",
                   help="one JSON document (format meicp-info): the report's keys with _ for spaces, "
                        "and the self-check's numbers under 'check'")
    verbosity(p)
    p.set_defaults(run=run)


def run(args) -> int:
    report = collect()
    code, check = Exit.OK, None
    if not args.json:
        rank0_print(format_report(report))
    if args.check:
        from mpi4py import MPI

        r = ghep_selfcheck(MPI.COMM_WORLD)
        ok = r["max_rel_error"] < 1e-10 and r["max_residual"] < 1e-8
        code = Exit.OK if ok else Exit.FAILED
        check = {**r, "ok": ok}
        if not args.json:
            rank0_print(
                f"\nself-check: {len(r['slepc'])} smallest eigenvalues of a "
                f"{r['n']}-DOF pencil, SLEPc on {r['ranks']} rank(s) vs SciPy eigh: "
                f"max relative error {r['max_rel_error']:.2e}, SLEPc residual {r['max_residual']:.2e}, "
                f"solve {r['solve_s'] * 1e3:.1f} ms -> {'OK' if ok else 'FAILED'}")
    if args.json:
        print_json({**json_header("info"), **{key.replace(" ", "_"): value for key, value in report.items()},
                    "check": check})
    return code
