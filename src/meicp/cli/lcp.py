"""``meicp lcp FILE`` and ``meicp classify FILE``: Siconos ``.dat`` or HDF5 (``M``, ``q``).
``--json``: one document (:mod:`meicp.cli.output`), formats ``meicp-lcp`` and
``meicp-classify``."""

from __future__ import annotations

import numpy as np

from ..core.log import rank0_print
from ..io.problem_files import read_problem
from ..lcp.classes import MAX_EXACT_LIMIT, classify
from ..lcp.solve import available_methods, solve_lcp
from .arguments import integer, tolerance, verbosity
from .exit import Exit
from .output import json_header, print_json


def register(sub) -> None:
    p = sub.add_parser("lcp", help="solve LCP(q, M) from a Siconos .dat or an HDF5 file (M, q)")
    p.add_argument("file")
    p.add_argument("--method", default="auto", choices=available_methods())
    p.add_argument("--tol", type=tolerance, default=1e-10, help="relative certificate tolerance, in (0, 1e-2]")
    p.add_argument("--all", action="store_true", help="every solution (support enumeration, small n)")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    verbosity(p)
    p.set_defaults(run=run_lcp)

    p = sub.add_parser("classify", help="matrix classes of M (P, Q, R0, Z, copositive, ...) and game value")
    p.add_argument("file")
    p.add_argument("--exact-limit", type=integer(0, MAX_EXACT_LIMIT), default=12,
                   help=f"largest n for the exponential exact tests (0 to {MAX_EXACT_LIMIT})")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    verbosity(p)
    p.set_defaults(run=run_classify)


def run_lcp(args) -> int:
    data = read_problem(args.file)
    method = "enumerate" if args.all else args.method
    r = solve_lcp(data["M"], data["q"], method=method, tol=args.tol)
    if args.json:
        print_json({**json_header("lcp"),
                    "file": args.file, "n": int(np.size(data["q"])), "method": r.method, "status": r.status,
                    "success": r.success, "message": r.message, "iterations": r.iterations,
                    "residual": r.residual, "min_x": r.min_x, "min_w": r.min_w,
                    "complementarity": r.complementarity, "x": r.x, "w": r.w,
                    "solutions": list(r.solutions), "attempts": r.attempts, "timings": r.timings})
    else:
        rank0_print(f"LCP from {args.file}: n = {np.size(data['q'])}")
        for name, status, message in (r.attempts if len(r.attempts) > 1 else []):
            rank0_print(f"  tried {name}: {status}" + (f" ({message})" if message and status != "solved" else ""))
        rank0_print(r.summary())
        if r.success:
            with np.printoptions(precision=6, suppress=True, linewidth=100):
                for k, s in enumerate(r.solutions):
                    rank0_print(f"x{'' if len(r.solutions) == 1 else f'[{k}]'} = {s}")
                rank0_print(f"w = {r.w}")
    return Exit.OK if r.success or r.status == "infeasible" else Exit.FAILED


def run_classify(args) -> int:
    data = read_problem(args.file, names=("M",))
    c = classify(data["M"], exact_limit=args.exact_limit)
    if args.json:
        print_json({**json_header("classify"), "file": args.file, **c.to_dict()})
    else:
        rank0_print(c.report())
    return Exit.OK
