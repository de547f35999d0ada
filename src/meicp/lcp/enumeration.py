"""All solutions of a small LCP by support enumeration.

For each support ``S ⊆ {1..n}`` (``x_i > 0`` allowed only on S, ``w_S = 0``) the candidate
solves ``M_SS x_S = −q_S``; it is a solution iff ``x_S ≥ 0`` and ``w = Mx + q ≥ 0`` off S.
A singular block ``M_SS`` has an affine set of candidates, so it is decided exactly by a
feasibility LP (HiGHS).  Every support is visited, so an empty list proves that
LCP(q, M) has no solution — up to the stated tolerance, which the message quotes, and
provided no support came within rounding of its conditions (then the result is
``undecided``).  The supports are solved on the problem equilibrated by powers of two
(exact scalings), so the decision does not depend on the scale of M's rows and columns or
of q.  Cost ``2ⁿ`` small solves: the default limit is n ≤ 18.
"""

from __future__ import annotations

import itertools
import time

import numpy as np
from scipy.optimize import linprog

from ..core.errors import ProblemError
from ..core.progress import Progress
from .problem import DEFAULT_TOL, LCPProblem, LCPResult, certify, relative_residual

MAX_N = 18


#: a support whose candidate misses the certificate by less than this many times
#: cond(M_SS)·eps is within rounding of feasibility: it can be neither accepted nor excluded
ROUNDING_FACTOR = 100.0
#: candidates violating their conditions by more than this (relative) are excluded at once
CLEAR_MISS = 1e-2
#: HiGHS' feasibility tolerance is 1e-7: an LP point missing the certificate by less than
#: this is within the LP's own rounding
LP_NEAR = 1e-6


def _exponent(v) -> np.ndarray:
    """Integer exponents e with 2^e nearest v (v > 0)."""
    return np.round(np.log2(v)).astype(np.int64)


def equilibrate(M: np.ndarray, q: np.ndarray, sweeps: int = 20):
    """Exponents ``er, ec, eg`` of row and column scalings and of q's scale, powers of two
    (so scaling is exact, never rounded): Ruiz's iteration on ``|M|`` makes the rows and
    columns of ``M̂ = 2^er M 2^ec`` have largest entry ≈ 1, and ``q̂ = 2^(er − eg) q`` has
    largest entry ≈ 1.  LCP(q̂, M̂) has the solutions ``x̂ = 2^−(ec + eg) x`` of LCP(q, M)
    (positive scalings keep signs and complementarity).  Computed on exponents, so M·1e300
    with q·1e-300 neither overflows nor underflows on the way."""
    absM = np.abs(M)
    er, ec = np.zeros(M.shape[0], dtype=np.int64), np.zeros(M.shape[1], dtype=np.int64)
    for _ in range(sweeps):
        S = np.ldexp(absM, er[:, None] + ec[None, :])
        r, c = S.max(axis=1), S.max(axis=0)
        r[r == 0] = 1.0
        c[c == 0] = 1.0
        if max(np.abs(np.log2(r)).max(), np.abs(np.log2(c)).max()) <= 1.0:
            break
        er -= _exponent(np.sqrt(r))
        ec -= _exponent(np.sqrt(c))
    # q̂'s exponent from q's own exponents, not from 2^er·q (that may underflow to 0)
    nz = q != 0
    eg = int((np.log2(np.abs(q[nz])) + er[nz]).max().round()) if nz.any() else 0
    return er, ec, eg


def _solve_support(M: np.ndarray, q: np.ndarray, S: np.ndarray):
    """A point of the candidate set of support S, or None if it has none; and whether it
    came from a direct solve (so that cond(M_SS) bounds its error)."""
    n = q.size
    MSS = M[np.ix_(S, S)]
    try:
        xs = np.linalg.solve(MSS, -q[S])
        # accept the direct solve unless the block is numerically singular
        if np.all(np.isfinite(xs)) and (np.linalg.norm(xs, np.inf) * np.abs(MSS).max() < 1e10 * max(
                np.abs(q[S]).max(), np.finfo(float).tiny) or np.linalg.cond(MSS) < 1e12):
            x = np.zeros(n)
            x[S] = xs
            return x, True
    except np.linalg.LinAlgError:
        pass
    # singular block: feasibility LP over x_S ≥ 0, M_SS x_S = −q_S, M_{S̄S} x_S ≥ −q_S̄
    out = np.setdiff1d(np.arange(n), S)
    res = linprog(np.zeros(S.size), A_ub=-M[np.ix_(out, S)] if out.size else None,
                  b_ub=q[out] if out.size else None, A_eq=MSS, b_eq=-q[S],
                  bounds=[(0, None)] * S.size, method="highs")
    if res.status != 0:
        return None, False
    x = np.zeros(n)
    x[S] = res.x
    return x, False


def enumerate_lcp(problem: LCPProblem, *, tol: float = DEFAULT_TOL, max_n: int = MAX_N,
                  **_ignored) -> LCPResult:
    """Every solution of LCP(q, M) for ``n ≤ max_n``; ``solutions`` lists them all.

    The supports are solved on the equilibrated problem (:func:`equilibrate`), so the
    decision does not depend on how M's rows and columns or q are scaled (M·1e300 with
    q·1e-300 is the same LCP).  ``x`` is the first solution found (smallest support first).
    Status ``infeasible`` when there is none: a proof, since all ``2ⁿ`` supports were
    examined and each missed its conditions by more than rounding (``ROUNDING_FACTOR``·
    cond(M_SS)·eps).  ``undecided`` when none was certified but some support came within
    rounding; ``out_of_range`` when a solution exists but is not representable in double
    precision once scaled back (e.g. x ≈ 1e-600).
    """
    n = problem.n
    if n > max_n:
        raise ProblemError(f"enumerate visits 2^n supports: n = {n} > max_n = {max_n}")
    t0 = time.perf_counter()
    M, q = problem.dense(), problem.q
    er, ec, eg = equilibrate(M, q)
    Ms = np.ldexp(M, er[:, None] + ec[None, :])
    scaled = LCPProblem(Ms, np.ldexp(q, er - eg))
    found: list[np.ndarray] = []
    visited = unresolved = 0
    worst_cond = 0.0
    eps = np.finfo(float).eps
    progress = Progress("LCP enumeration", total=2 ** n, unit="supports")
    for size in range(n + 1):
        for S in itertools.combinations(range(n), size):
            visited += 1
            progress.update(visited, detail=f"support size {size} of {n}, {len(found)} solution(s) so far")
            S = np.array(S, dtype=np.int64)
            x, direct = (np.zeros(n), True) if size == 0 else _solve_support(Ms, scaled.q, S)
            if x is None:
                continue
            big = max(np.abs(x).max(), np.finfo(float).tiny)
            if x.min() < -CLEAR_MISS * big:
                continue  # cheap rejection; the certificate below decides the rest
            clipped = np.where((x < 0) & (x > -tol * big), 0.0, x)
            r, _ = relative_residual(scaled, clipped)
            if r <= tol:
                if not any(np.allclose(clipped, y, rtol=1e-9, atol=1e-12 * max(1.0, np.abs(y).max()))
                           for y in found):
                    found.append(clipped)
                continue
            if r <= CLEAR_MISS and size:
                cond = np.linalg.cond(Ms[np.ix_(S, S)])
                if r <= ROUNDING_FACTOR * cond * eps or (not direct and r <= LP_NEAR):
                    unresolved += 1
                    worst_cond = max(worst_cond, cond)
    result = LCPResult(method="enumerate", iterations=visited)
    result.timings["solve"] = time.perf_counter() - t0
    if not found:
        if unresolved:
            result.status = "undecided"
            result.message = (f"no certified solution, but {unresolved} of the {visited} supports came within "
                              f"rounding of x ≥ 0, w ≥ 0 (condition numbers up to {worst_cond:.1e} on the "
                              f"equilibrated problem): the enumeration proves neither a solution nor that "
                              f"there is none")
            return result
        result.status = "infeasible"
        result.message = (f"no solution: all {visited} supports examined on the equilibrated problem, none gives "
                          f"x ≥ 0, w ≥ 0 within relative tolerance {tol:.0e}; LCP(q, M) has no solution")
        return result
    with np.errstate(over="ignore", under="ignore"):
        mapped = [np.ldexp(y, ec + eg) for y in found]
    result.solutions = mapped
    result.message = f"{len(found)} solution(s) among {visited} supports"
    if unresolved:
        result.message += f" ({unresolved} more support(s) within rounding of feasibility: the list may be incomplete)"
    result = certify(problem, result, mapped[0], tol=tol, failure_status="out_of_range")
    if not result.success:
        result.solutions = []
        result.message = (f"LCP(q, M) has a solution (found on the equilibrated problem, support "
                          f"{np.flatnonzero(found[0] > 0).tolist()}), but scaled back by 2^{int((ec + eg).min())} to "
                          f"2^{int((ec + eg).max())} it is not representable in double precision: "
                          f"{result.message}")
    return result
