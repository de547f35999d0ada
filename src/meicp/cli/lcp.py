"""``meicp lcp FILE`` and ``meicp classify FILE``: Siconos ``.dat`` or HDF5 (``M``, ``q``)."""

from __future__ import annotations

import json

import numpy as np

from ..contact.result import json_number
from ..core.log import rank0_print
from ..io.problem_files import read_problem
from ..lcp.classes import MAX_EXACT_LIMIT, classify
from ..lcp.solve import available_methods, solve_lcp
from .arguments import integer, tolerance, verbosity
from .exit import Exit


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


def _vector(x):
    """A vector for JSON as ``meicp solve --json`` writes numbers (:func:`json_number`): ±inf as
    "inf"/"-inf", NaN (unknown) as None."""
    return None if x is None else [json_number(v) for v in x]


def json_plain(v):
    """A JSON-ready value with every float through :func:`json_number` (``json.dumps``
    would write NaN/Infinity, which is not JSON); dicts, lists and tuples walked."""
    if isinstance(v, dict):
        return {k: json_plain(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [json_plain(x) for x in v]
    if isinstance(v, np.ndarray):
        return json_plain(v.tolist())
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, (int, np.integer)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        return json_number(v)
    return v


def run_lcp(args) -> int:
    data = read_problem(args.file)
    method = "enumerate" if args.all else args.method
    r = solve_lcp(data["M"], data["q"], method=method, tol=args.tol)
    if args.json:
        rank0_print(json.dumps({
            "file": args.file, "n": int(np.size(data["q"])), "method": r.method, "status": r.status,
            "success": r.success, "message": r.message, "iterations": r.iterations,
            "residual": json_number(r.residual), "min_x": json_number(r.min_x), "min_w": json_number(r.min_w),
            "complementarity": json_number(r.complementarity), "x": _vector(r.x), "w": _vector(r.w),
            "solutions": [_vector(s) for s in r.solutions], "attempts": r.attempts,
            "timings": json_plain(r.timings)}, indent=2))
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
    rank0_print(json.dumps(json_plain(c.to_dict()), indent=2, default=float) if args.json else c.report())
    return Exit.OK
