"""Siconos (``siconos.numerics``, Debian ``python3-siconos``) as the peer LCP solver.

Used by the tests and ``scripts/bench_lcp.py`` to compare side by side; the result is
certified with meicp's own certificate so that both are judged alike.
"""

from __future__ import annotations

import time

import numpy as np

from .problem import DEFAULT_TOL, LCPProblem, LCPResult, certify

#: Siconos solver ids by the names used in benchmarks
SICONOS_SOLVERS = {"lemke": "SICONOS_LCP_LEMKE", "enum": "SICONOS_LCP_ENUM",
                   "newton-fb": "SICONOS_LCP_NEWTON_FB_FBLSA", "pgs": "SICONOS_LCP_PGS"}


def siconos_solve(M, q, solver: str = "lemke", *, tol: float = DEFAULT_TOL,
                  max_iter: int | None = None) -> LCPResult:
    """Solve with Siconos' ``linearComplementarity_driver``; status from meicp's certificate."""
    import siconos.numerics as sn

    problem = LCPProblem.from_data(M, q)
    Md = np.ascontiguousarray(problem.dense())
    options = sn.SolverOptions(getattr(sn, SICONOS_SOLVERS[solver]))
    if max_iter is not None:
        options.iparam[0] = max_iter
    if solver != "enum":
        options.dparam[0] = tol
    z, w = np.zeros(problem.n), np.zeros(problem.n)
    t0 = time.perf_counter()
    info = sn.linearComplementarity_driver(sn.LCP(Md, problem.q), z, w, options)
    result = LCPResult(method=f"siconos-{solver}", iterations=int(options.iparam[1]),
                       message=f"siconos info {info}")
    result.timings["solve"] = time.perf_counter() - t0
    if info != 0:
        result.status = "failed"
        return result
    return certify(problem, result, z, tol=tol)
