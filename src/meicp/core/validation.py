"""Input checks that raise :class:`~meicp.core.errors.ProblemError` naming the argument.

Plain NumPy/SciPy: PETSc matrices are checked where they are used (collectively).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .errors import ProblemError


def as_matrix(M, name: str = "M", *, square: bool = True, allow_sparse: bool = True):
    """Return ``M`` as a float64 ndarray or SciPy CSR matrix after checking it.

    Rejects empty, non-2-D, non-square (when ``square``), non-numeric and non-finite input.
    """
    if sp.issparse(M):
        if not allow_sparse:
            M = M.toarray()
        else:
            M = sp.csr_matrix(M, dtype=np.float64)
            data = M.data
    if not sp.issparse(M):
        try:
            M = np.array(M, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise ProblemError(f"{name} is not a numeric matrix: {exc}") from None
        data = M
    if M.ndim != 2:
        raise ProblemError(f"{name} must be 2-D, got {M.ndim}-D with shape {M.shape}")
    if M.shape[0] == 0 or M.shape[1] == 0:
        raise ProblemError(f"{name} is empty (shape {M.shape})")
    if square and M.shape[0] != M.shape[1]:
        raise ProblemError(f"{name} must be square, got shape {M.shape}")
    if not np.all(np.isfinite(data)):
        raise ProblemError(f"{name} contains NaN or Inf")
    return M


def as_vector(q, n: int, name: str = "q") -> np.ndarray:
    """Return ``q`` as a finite float64 vector of length ``n``."""
    try:
        q = np.array(q, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ProblemError(f"{name} is not a numeric vector: {exc}") from None
    if q.ndim == 2 and 1 in q.shape:
        q = q.ravel()
    if q.ndim != 1:
        raise ProblemError(f"{name} must be a vector, got shape {q.shape}")
    if q.shape[0] != n:
        raise ProblemError(f"{name} has length {q.shape[0]}, expected {n}")
    if not np.all(np.isfinite(q)):
        raise ProblemError(f"{name} contains NaN or Inf")
    return q


def scale(M) -> float:
    """A matrix scale for relative tolerances: the largest absolute entry (1 for zero)."""
    data = M.data if sp.issparse(M) else np.asarray(M)
    s = float(np.max(np.abs(data))) if data.size else 0.0
    return s if s > 0 else 1.0


def symmetry_error(M) -> float:
    """``max|M - Mᵀ|`` relative to the scale of ``M``."""
    D = M - M.T
    d = abs(D).max() if sp.issparse(D) else np.max(np.abs(D))
    return float(d) / scale(M)


def is_symmetric(M, rtol: float = 1e-12) -> bool:
    return symmetry_error(M) <= rtol


def check_symmetric(M, name: str = "M", rtol: float = 1e-12) -> None:
    err = symmetry_error(M)
    if err > rtol:
        raise ProblemError(f"{name} must be symmetric: max|{name} - {name}ᵀ| / max|{name}| = {err:.3g} > {rtol:g}")


def check_spd(M, name: str = "B", rtol: float = 1e-12) -> None:
    """Symmetric and positive definite, by a Cholesky factorisation (dense) or LDLᵀ-free test.

    Sparse diagonal matrices are checked by their diagonal; other sparse matrices by a
    sparse LU's pivots only when small, otherwise densified up to a size limit.
    """
    check_symmetric(M, name, rtol)
    if sp.issparse(M):
        offdiag = M - sp.diags(M.diagonal())
        if offdiag.count_nonzero() == 0:
            d = M.diagonal()
            if np.all(d > 0):
                return
            i = int(np.argmin(d))
            raise ProblemError(f"{name} must be positive definite: diagonal entry {i} is {d[i]:.3g}")
        M = M.toarray()
    try:
        np.linalg.cholesky(0.5 * (M + M.T))
    except np.linalg.LinAlgError:
        w = np.linalg.eigvalsh(0.5 * (M + M.T))
        raise ProblemError(
            f"{name} must be positive definite: smallest eigenvalue {w[0]:.3g}") from None


def as_index_set(J, n: int, name: str = "J") -> np.ndarray:
    """Return a sorted int array of distinct indices in ``[0, n)``; ``None`` means all."""
    if J is None:
        return np.arange(n)
    J = np.asarray(J)
    if J.dtype == bool:
        if J.shape != (n,):
            raise ProblemError(f"{name} as a mask must have length {n}, got shape {J.shape}")
        return np.flatnonzero(J)
    if J.size == 0:
        return np.zeros(0, dtype=np.int64)
    if J.ndim != 1 or not np.issubdtype(J.dtype, np.integer):
        raise ProblemError(f"{name} must be a 1-D array of integer indices, got {J.dtype} shape {J.shape}")
    bad = J[(J < 0) | (J >= n)]
    if bad.size:
        raise ProblemError(f"{name} has index {int(bad[0])} out of range [0, {n})")
    uniq, counts = np.unique(J, return_counts=True)
    if np.any(counts > 1):
        raise ProblemError(f"{name} repeats index {int(uniq[np.argmax(counts > 1)])}")
    return uniq.astype(np.int64)
