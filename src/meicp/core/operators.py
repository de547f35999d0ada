"""Matrices as the solvers meet them: NumPy, SciPy sparse, or a distributed PETSc Mat.

One dispatch for the few operations every problem class needs; PETSc is imported only
when a PETSc matrix is actually given (the calls are then collective).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp


def is_petsc_mat(M) -> bool:
    return type(M).__module__.startswith("petsc4py") and hasattr(M, "getSize")


def max_abs_entry(M) -> float:
    """``max |m_ij|`` (0 for an empty or zero matrix)."""
    if is_petsc_mat(M):
        from ..petsc.lcp import max_abs_entry as petsc_max_abs_entry

        return petsc_max_abs_entry(M)
    data = M.data if sp.issparse(M) else np.asarray(M)
    return float(np.max(np.abs(data))) if data.size else 0.0


def to_dense(M) -> np.ndarray:
    """A dense ndarray (gathered on every rank for a PETSc Mat)."""
    if is_petsc_mat(M):
        from ..petsc.mat import mat_to_scipy

        return mat_to_scipy(M).toarray()
    return M.toarray() if sp.issparse(M) else np.asarray(M)


def matvec(M, x: np.ndarray) -> np.ndarray:
    """``M @ x`` for a full-length x (held on every rank for a PETSc Mat)."""
    if is_petsc_mat(M):
        from ..petsc.lcp import matvec as petsc_matvec

        return petsc_matvec(M, x)
    return M @ x
