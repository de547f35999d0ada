"""``meicp eicp FILE``: an (M)EiCP from HDF5 or ``.mat`` (datasets ``A``, ``B``, optional ``J``);
``--json``: one document of format ``meicp-eicp`` (:mod:`meicp.cli.output`)."""

from __future__ import annotations

import numpy as np

from ..core.log import rank0_print
from ..eicp.solve import available_methods, solve_eicp
from ..io.problem_files import read_problem
from .arguments import cli_spelling, finite, tolerance, verbosity
from .exit import Exit
from .output import json_header, print_json


def register(sub) -> None:
    p = sub.add_parser("eicp", help="solve the (mixed) eigenvalue complementarity problem (A, B, J) from a file")
    p.add_argument("file", help="HDF5 (.h5) or MATLAB (.mat) with A, B and optional J (0-based indices)")
    p.add_argument("--method", default="auto", choices=available_methods())
    p.add_argument("--all", action="store_true", help="every solution (support enumeration, small |J|)")
    p.add_argument("--lam-min", type=finite, default=None, help="only solutions with λ ≥ this (finite)")
    p.add_argument("--target", type=finite, default=0.0, help="shift for the SLEPc solves (active-set)")
    p.add_argument("--tol", type=tolerance, default=1e-10, help="relative certificate tolerance, in (0, 1e-2]")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    verbosity(p)
    p.set_defaults(run=run)


def run(args) -> int:
    from mpi4py import MPI

    data = read_problem(args.file, names=("A", "B", "J"))
    J = data.get("J")  # checked by read_problem: integer indices in range (1.7 is an error)
    kwargs = {"target": args.target} if args.method in ("active-set", "auto") else {}
    r = solve_eicp(data["A"], data["B"], J=J, method=args.method, all_solutions=args.all,
                   lam_min=args.lam_min, tol=args.tol, comm=MPI.COMM_WORLD, **kwargs)
    if args.json:
        print_json({**json_header("eicp"),
                    "file": args.file, "method": r.method, "status": r.status, "success": r.success,
                    "message": cli_spelling(r.message), "iterations": r.iterations, "timings": r.timings,
                    "solutions": [{"lam": s.lam, "residual": s.residual, "support": s.support, "x": s.x}
                                  for s in r.solutions],
                    "attempts": [[name, status, cli_spelling(message)] for name, status, message in r.attempts]})
        return Exit.OK if r.success or r.status == "no_solution" else Exit.FAILED
    n = np.shape(data["A"])[0]
    rank0_print(f"EiCP from {args.file}: n = {n}, |J| = {n if J is None else J.size}")
    for name, status, message in (r.attempts if len(r.attempts) > 1 else []):
        rank0_print(f"  tried {name}: {status}" + (f" ({cli_spelling(message)})" if message and status != "solved" else ""))
    rank0_print(cli_spelling(r.summary()))
    if r.solutions:
        rank0_print(f"{'λ':>22}  {'residual':>9}  {'|support|':>9}  support")
        for s in r.solutions[:50]:
            sup = s.support.tolist()
            rank0_print(f"{s.lam:22.14g}  {s.residual:9.2e}  {len(sup):9d}  {sup[:12]}{' ...' if len(sup) > 12 else ''}")
        if len(r.solutions) > 50:
            rank0_print(f"... {len(r.solutions) - 50} more (use --json)")
    return Exit.OK if r.success or r.status == "no_solution" else Exit.FAILED
