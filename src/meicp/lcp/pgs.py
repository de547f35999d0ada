"""Projected Gauss–Seidel / SOR for sparse symmetric positive (semi)definite M.

The sweep is ordered by a graph colouring of M's pattern: unknowns of one colour do not
couple, so each colour's update is one vectorized sparse product, and a sweep is a true
Gauss–Seidel sweep in the colour order (not a Jacobi one).  Convergence for symmetric PSD
M with positive diagonal and 0 < ω < 2 is classical (Cryer 1971); the stopping test is
the relative natural residual ``‖min(x, w)‖∞``, then the certificate decides.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from ..core.errors import ProblemError
from ..core.validation import is_symmetric
from .problem import DEFAULT_TOL, LCPProblem, LCPResult, best_of, certify, refine_on_support


#: above this fraction of nonzeros M is treated as dense (one unknown per colour)
DENSE_FRACTION = 0.25


def greedy_colouring(A: sp.csr_matrix, seed: int = 0) -> np.ndarray:
    """Colours such that no two coupled unknowns share one (Jones–Plassmann, vectorized):
    each round, every uncoloured vertex whose random weight beats all its uncoloured
    neighbours' takes the smallest colour none of its neighbours has."""
    n = A.shape[0]
    G = sp.csr_matrix((np.ones(A.nnz), A.indices, A.indptr), shape=A.shape)
    G = ((G + G.T) > 0).astype(np.int8).tocsr()
    G.setdiag(0)
    G.eliminate_zeros()
    weight = np.random.default_rng(seed).permutation(n).astype(np.float64) + 1.0
    colour = np.full(n, -1, dtype=np.int64)
    rows = np.repeat(np.arange(n), np.diff(G.indptr))
    cols = G.indices
    while (colour < 0).any():
        active = colour < 0
        w = np.where(active, weight, 0.0)
        # max weight among uncoloured neighbours
        neigh_max = np.zeros(n)
        np.maximum.at(neigh_max, rows, w[cols])
        winners = np.flatnonzero(active & (w > neigh_max))
        # smallest colour not used by a coloured neighbour, per winner
        ncol = int(colour.max()) + 2
        used = np.zeros((n, ncol), dtype=bool)
        has = colour[cols] >= 0
        used[rows[has], colour[cols[has]]] = True
        colour[winners] = np.argmin(used[winners], axis=1)
    return colour


def pgs(problem: LCPProblem, *, tol: float = DEFAULT_TOL, max_iter: int = 100000,
        omega: float = 1.0, x0=None, check_every: int = 10, **_ignored) -> LCPResult:
    """Projected SOR sweeps ``x_i ← max(0, x_i − ω w_i / M_ii)`` in colour order."""
    M = sp.csr_matrix(problem.M)
    q = problem.q
    if not is_symmetric(M, 1e-12):
        raise ProblemError("pgs needs a symmetric M (use lemke or newton for nonsymmetric M)")
    d = M.diagonal()
    if np.any(d <= 0):
        raise ProblemError(f"pgs needs a positive diagonal; M[{int(np.argmin(d))}, {int(np.argmin(d))}] = {d.min():.3g}")
    if not 0 < omega < 2:
        raise ProblemError(f"pgs needs 0 < omega < 2, got {omega}")
    t0 = time.perf_counter()
    if M.nnz > DENSE_FRACTION * problem.n ** 2:
        # dense coupling: every unknown is its own colour; rows as dense arrays are cheaper
        Md = problem.dense()
        blocks = [(np.array([i]), Md[i:i + 1], d[i:i + 1]) for i in range(problem.n)]
    else:
        colour = greedy_colouring(M)
        blocks = [(idx, M[idx], d[idx]) for idx in (np.flatnonzero(colour == c) for c in range(colour.max() + 1))]
    t1 = time.perf_counter()
    x = np.zeros(problem.n) if x0 is None else np.maximum(np.asarray(x0, float), 0.0)
    scale_w = max(float(np.abs(q).max()), 1e-300)
    # stop a hundredfold below tol, but never below rounding (tol = 1e-14 would otherwise
    # sweep to max_iter); the polish on the support and the certificate do the rest
    stop = max(tol * 1e-2, 100 * np.finfo(float).eps)
    result = LCPResult(method="pgs")
    status = "max_iterations"
    sweep = 0
    with np.errstate(over="ignore", invalid="ignore"):  # divergence is caught below
        for sweep in range(1, max_iter + 1):
            for idx, rows, diag in blocks:
                x[idx] = np.maximum(0.0, x[idx] - omega * (rows @ x + q[idx]) / diag)
            if sweep % check_every == 0:
                natural = np.abs(np.minimum(x, M @ x + q)).max()
                if not np.isfinite(natural):  # e.g. an LCP with no solution: x grows without bound
                    status = "diverged"
                    break
                if natural <= stop * max(scale_w, problem.matrix_scale * np.abs(x).max()):
                    status = "solved"
                    break
    result.iterations = sweep
    result.timings.update(colouring=t1 - t0, solve=time.perf_counter() - t1)
    if status != "solved":
        result.message = (f"the sweeps diverged (|x| overflowed after {sweep} sweeps)" if status == "diverged"
                          else f"no convergence in {max_iter} sweeps")
        return certify(problem, result, x, tol=tol, failure_status=status)
    return certify(problem, result, best_of(problem, x, refine_on_support(problem, x)), tol=tol)
