"""All solutions of a small LCP by support enumeration.

For each support ``S ⊆ {1..n}`` (``x_i > 0`` allowed only on S, ``w_S = 0``) the candidate
solves ``M_SS x_S = −q_S``; it is a solution iff ``x_S ≥ 0`` and ``w = Mx + q ≥ 0`` off S.
A singular block ``M_SS`` has an affine set of candidates, so it is decided exactly by a
feasibility LP (HiGHS).  Every support is visited, so an empty list proves that
LCP(q, M) has no solution — up to the stated tolerance, which the message quotes.
Cost ``2ⁿ`` small solves: the default limit is n ≤ 18.
"""

from __future__ import annotations

import itertools
import time

import numpy as np
from scipy.optimize import linprog

from ..core.errors import ProblemError
from .problem import DEFAULT_TOL, LCPProblem, LCPResult, certify, relative_residual

MAX_N = 18


def _well_conditioned(A: np.ndarray) -> bool:
    return np.linalg.cond(A) < 1e12


def _solve_support(M: np.ndarray, q: np.ndarray, S: np.ndarray, feas_tol: float):
    """A point of the candidate set of support S, or None if it has none."""
    n = q.size
    MSS = M[np.ix_(S, S)]
    try:
        xs = np.linalg.solve(MSS, -q[S])
        # accept the direct solve unless the block is numerically singular
        if np.all(np.isfinite(xs)) and np.linalg.norm(xs, np.inf) * np.abs(MSS).max() < 1e10 * max(
                np.abs(q[S]).max(), np.finfo(float).tiny) or _well_conditioned(MSS):
            x = np.zeros(n)
            x[S] = xs
            return x
    except np.linalg.LinAlgError:
        pass
    # singular block: feasibility LP over x_S ≥ 0, M_SS x_S = −q_S, M_{S̄S} x_S ≥ −q_S̄
    out = np.setdiff1d(np.arange(n), S)
    res = linprog(np.zeros(S.size), A_ub=-M[np.ix_(out, S)] if out.size else None,
                  b_ub=q[out] if out.size else None, A_eq=MSS, b_eq=-q[S],
                  bounds=[(0, None)] * S.size, method="highs")
    if res.status != 0:
        return None
    x = np.zeros(n)
    x[S] = res.x
    return x


def enumerate_lcp(problem: LCPProblem, *, tol: float = DEFAULT_TOL, max_n: int = MAX_N,
                  **_ignored) -> LCPResult:
    """Every solution of LCP(q, M) for ``n ≤ max_n``; ``solutions`` lists them all.

    ``x`` is the first solution found (smallest support first).  Status ``infeasible``
    when there is none: that is a proof, since all ``2ⁿ`` supports were examined.
    """
    n = problem.n
    if n > max_n:
        raise ProblemError(f"enumerate visits 2^n supports: n = {n} > max_n = {max_n}")
    t0 = time.perf_counter()
    M, q = problem.dense(), problem.q
    found: list[np.ndarray] = []
    visited = 0
    feas_tol = tol
    for size in range(n + 1):
        for S in itertools.combinations(range(n), size):
            visited += 1
            S = np.array(S, dtype=np.int64)
            x = np.zeros(n) if size == 0 else _solve_support(M, q, S, feas_tol)
            if x is None or x.min() < -1e-6 * max(1.0, np.abs(x).max()):
                continue  # cheap rejection; the certificate below decides the rest
            x[x < 0] = np.where(x[x < 0] > -tol * max(1.0, np.abs(x).max()), 0.0, x[x < 0])
            r, _ = relative_residual(problem, x)
            if r > tol:
                continue
            if not any(np.allclose(x, y, rtol=1e-9, atol=1e-12 * max(1.0, np.abs(y).max())) for y in found):
                found.append(x)
    result = LCPResult(method="enumerate", iterations=visited)
    result.timings["solve"] = time.perf_counter() - t0
    if not found:
        result.status = "infeasible"
        result.message = (f"no solution: all {visited} supports examined, none gives x ≥ 0, "
                          f"w ≥ 0 within relative tolerance {tol:.0e}; LCP(q, M) has no solution")
        return result
    result.solutions = found
    result.message = f"{len(found)} solution(s) among {visited} supports"
    return certify(problem, result, found[0], tol=tol)
