"""The few operations every problem class needs, on any kind of matrix.

``lcp`` and ``eicp`` take NumPy arrays, SciPy sparse matrices or PETSc Mats and treat them
alike through these functions.  Each is a :func:`functools.singledispatch` function whose
base implementation here is the NumPy / SciPy one; :mod:`meicp.petsc.mat` registers the
PETSc Mat's (collective on its communicator) when it is imported, as DOLFINx's
``fem/petsc.py`` builds on ``fem/assemble.py``.  So nothing below ``meicp.petsc`` names
PETSc, and importing meicp does not start it.  ``meicp/__init__`` imports
:mod:`meicp.petsc`, so a PETSc Mat never meets an unregistered function.
"""

from __future__ import annotations

from functools import singledispatch

import numpy as np
import scipy.sparse as sp

from . import validation


@singledispatch
def is_petsc_mat(M) -> bool:
    """True for a PETSc Mat: products and reductions on it are collective."""
    return False


@singledispatch
def matrix_shape(M) -> tuple[int, int]:
    """``(rows, columns)``, global for a distributed matrix."""
    return M.shape


@singledispatch
def matrix_comm(M):
    """The mpi4py communicator ``M`` is distributed over, None when one rank holds it all
    (:func:`meicp.core.comm.mpi_comm`'s canonical form)."""
    return None


@singledispatch
def checked_matrix(M, name: str = "M"):
    """``M`` checked square, non-empty and finite: a NumPy / SciPy one as a float64 ndarray
    or CSR (:func:`~meicp.core.validation.as_matrix`); ProblemError naming ``name``."""
    return validation.as_matrix(M, name)


@singledispatch
def to_dense(M) -> np.ndarray:
    """A dense ndarray (gathered on every rank for a distributed matrix)."""
    return M.toarray() if sp.issparse(M) else np.asarray(M)


@singledispatch
def to_scipy(M) -> sp.csr_matrix:
    """A SciPy CSR matrix (gathered on every rank for a distributed matrix)."""
    return sp.csr_matrix(M)


@singledispatch
def matvec(M, x: np.ndarray) -> np.ndarray:
    """``M @ x`` for a full-length x (on every rank for a distributed matrix)."""
    return M @ x


@singledispatch
def max_abs_entry(M) -> float:
    """``max |m_ij|`` (0 for an empty or zero matrix)."""
    data = M.data if sp.issparse(M) else np.asarray(M)
    return float(np.max(np.abs(data))) if data.size else 0.0


@singledispatch
def row_max_abs(M) -> np.ndarray:
    """``max_j |m_ij|`` for every row i (on every rank for a distributed matrix)."""
    return validation.row_max_abs(M)


@singledispatch
def is_symmetric(M, rtol: float = 1e-12) -> bool:
    """``max|M − Mᵀ| ≤ rtol·max|M|``."""
    return validation.is_symmetric(M, rtol)


@singledispatch
def ldexp(M, exponent: int):
    """``M·2^exponent`` as a new matrix of the same kind: exact, powers of two scale without
    rounding (the caller :func:`release` s it)."""
    if sp.issparse(M):
        out = M.tocsr(copy=True)
        out.data = np.ldexp(out.data, exponent)
        return out
    return np.ldexp(M, exponent)


@singledispatch
def release(M) -> None:
    """Free what the matrix holds outside Python (a PETSc Mat's memory: collective); nothing
    for NumPy and SciPy, which the garbage collector frees."""

