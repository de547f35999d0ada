"""Lemke's complementary pivoting with lexicographic degeneracy resolution (dense).

Works on ``w − Mx − d z₀ = q`` with covering vector ``d = 1``, keeping the basis inverse
explicitly (``n × n``) rather than the full ``n × 2n`` tableau: one pivot is a column
solve and a rank-one update.  The lexicographic ratio test over the rows of
``[B⁻¹q, B⁻¹]`` makes every pivot strictly improve a lexicographic order, so the method
cannot cycle on degenerate problems.

Rank-one updates accumulate rounding over many pivots, enough to end on a false secondary
ray on a ~10³-unknown friction LCP; a ray is therefore re-checked by a second pass that
refreshes the basis inverse by LU every ``REINVERT_EVERY`` pivots.

Termination: z₀ leaves the basis (a solution), or the entering column has no positive
entry (a secondary ray).  On a ray, the message says what it implies: if M is
copositive-plus (e.g. PSD), the LCP has no solution; otherwise nothing is proved.
"""

from __future__ import annotations

import time
import warnings

import numpy as np
import scipy.linalg

from ..core.progress import Progress
from .problem import DEFAULT_TOL, LCPProblem, LCPResult, best_of, certify, refine_on_support


#: pivots between refreshes of the basis inverse in the re-checking pass (an O(n³) LU each)
REINVERT_EVERY = 100


def _lexicographic_min(rows: np.ndarray, b: np.ndarray, col: np.ndarray, Binv: np.ndarray,
                       rtol: float) -> int:
    """Row of the lexicographic minimum of ``[b, B⁻¹] / col`` over ``rows``."""
    ratios = b[rows] / col[rows]
    best = ratios.min()
    tied = rows[ratios <= best + rtol * max(1.0, abs(best))]
    k = 0
    while tied.size > 1 and k < Binv.shape[1]:
        vals = Binv[tied, k] / col[tied]
        m = vals.min()
        tied = tied[vals <= m + rtol * max(1.0, abs(m))]
        k += 1
    return int(tied[0])


def lemke(problem: LCPProblem, *, tol: float = DEFAULT_TOL, max_iter: int | None = None,
          pivot_tol: float = 1e-12, **_ignored) -> LCPResult:
    """Solve the LCP by Lemke's method.  ``max_iter`` bounds the pivots of each pass
    (default 50 n + 1000).

    A secondary ray is re-checked by a second pass that refreshes the basis inverse every
    ``REINVERT_EVERY`` pivots: on a 1264-unknown friction LCP rank-one updates alone ended
    on a false ray, while re-inverting from the start breaks nearly singular bases (Siconos'
    tobenna, rcond 1e-25) that the plain pass solves.
    """
    t0 = time.perf_counter()
    M = problem.dense()
    q = problem.q.astype(np.float64)
    n = problem.n
    max_iter = max_iter or 50 * n + 1000
    result = LCPResult(method="lemke")
    if np.all(q >= 0):
        result.message = "q ≥ 0: x = 0 is a solution"
        return certify(problem, result, np.zeros(n))
    status, message, iterations, x = _pivot(M, q, max_iter, pivot_tol, reinvert_every=None)
    if status == "ray_termination":
        status, message, more, x = _pivot(M, q, max_iter, pivot_tol, reinvert_every=REINVERT_EVERY)
        iterations += more
        if status == "solved":
            result.message = "the first pass ended on a ray; the re-inverting pass solved it"
        elif status != "ray_termination":
            message = f"the first pass ended on a secondary ray; the re-inverting pass: {message}"
    result.iterations = iterations
    result.timings["solve"] = time.perf_counter() - t0
    if status != "solved":
        result.status, result.message = status, message
        return result
    return certify(problem, result, best_of(problem, x, refine_on_support(problem, x)), tol=tol)


def _pivot(M: np.ndarray, q: np.ndarray, max_iter: int, pivot_tol: float, reinvert_every: int | None):
    """One run of complementary pivoting: (status, message, pivots, x or None)."""
    n = q.size
    # variable k: w_k for k < n, x_{k-n} for n ≤ k < 2n, z0 for k = 2n
    Z0 = 2 * n
    basis = np.arange(n)            # basic variable of each row
    Binv = np.eye(n)
    b = q.copy()                    # values of the basic variables, B⁻¹q

    def column(k: int) -> np.ndarray:  # B⁻¹ times the constraint column of variable k
        if k < n:
            return Binv[:, k].copy()
        if k < Z0:
            return -(Binv @ M[:, k - n])
        return -Binv.sum(axis=1)

    def reinvert() -> None:
        """Replace B⁻¹ and B⁻¹q by a fresh LU inverse of the basis columns of [I, −M, −d]
        when its residual ‖B·B⁻¹ − I‖ is smaller than the updated one's."""
        B = np.zeros((n, n))
        for r, k in enumerate(basis):
            if k < n:
                B[k, r] = 1.0
            elif k < Z0:
                B[:, r] = -M[:, k - n]
            else:
                B[:, r] = -1.0
        eye = np.eye(n)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", scipy.linalg.LinAlgWarning)
            fresh = scipy.linalg.solve(B, eye)
        if np.abs(B @ fresh - eye).max() < np.abs(B @ Binv - eye).max():
            Binv[:] = fresh
            b[:] = fresh @ q

    def pivot(row: int, col: np.ndarray, entering: int) -> None:
        p = col[row]
        Binv[row] /= p
        b[row] /= p
        other = col.copy()
        other[row] = 0.0
        Binv[:] -= np.outer(other, Binv[row])
        b[:] -= other * b[row]
        basis[row] = entering

    # first pivot: z0 enters and rises until the most negative w reaches 0.  Among ties the
    # lexicographic rule on the rows of [q, I] picks the largest index.
    col = column(Z0)
    ties = np.flatnonzero(q <= q.min() + 1e-12 * max(1.0, abs(q.min())))
    row = int(ties[-1])
    leaving = basis[row]
    pivot(row, col, Z0)
    iterations = 1
    status, message = "max_iterations", f"no termination within {max_iter} pivots"
    progress = Progress(f"Lemke on {n} unknowns", unit="pivots")  # a pivot is O(n²): minutes at n = 8,000
    while iterations < max_iter:
        progress.update(iterations)
        entering = leaving + n if leaving < n else leaving - n  # complement of the leaving one
        if reinvert_every and iterations % reinvert_every == 0:
            reinvert()
        col = column(entering)
        scale = max(1.0, float(np.max(np.abs(col))))
        candidates = np.flatnonzero(col > pivot_tol * scale)
        if candidates.size == 0:
            status = "ray_termination"
            message = ("Lemke terminated on a secondary ray: no solution found. If M is "
                       "copositive-plus (e.g. positive semidefinite) this proves LCP(q, M) has "
                       "no solution; for other matrices it proves nothing (Lemke can fail on "
                       "solvable problems that are not copositive-plus or P)")
            return status, message, iterations, None
        # z0 leaves whenever it ties for the minimum ratio: then we are done
        z0_row = int(np.flatnonzero(basis == Z0)[0])
        ratios = b[candidates] / col[candidates]
        best = ratios.min()
        if z0_row in candidates and b[z0_row] / col[z0_row] <= best + 1e-12 * max(1.0, abs(best)):
            row = z0_row
        else:
            row = _lexicographic_min(candidates, b, col, Binv, 1e-12)
        leaving = basis[row]
        pivot(row, col, entering)
        iterations += 1
        if leaving == Z0:
            status, message = "solved", ""
            break
    if status != "solved":
        return status, message, iterations, None
    x = np.zeros(n)
    is_x = (basis >= n) & (basis < Z0)
    x[basis[is_x] - n] = np.maximum(b[is_x], 0.0)
    return status, message, iterations, x
