"""PETSc Mats: built from per-rank CSR rows, gathered back, and registered as a matrix kind.

Distributed matrices are built from per-rank CSR rows: each rank's rows with NumPy/SciPy
handed to ``createAIJ(csr=...)`` (a Python ``setValues`` loop is far slower: docs/design.md §11),
and gathered back into SciPy.  Importing this module registers the PETSc Mat's
implementations of the operations of :mod:`meicp.core.matrix` (``matvec``, ``to_dense``,
``max_abs_entry``...), through :class:`PetscMat`, which recognises petsc4py's ``Mat`` by
name so that registering does not start PETSc.  Collective on the matrix's (or ``comm``'s)
communicator.
"""

from __future__ import annotations

import abc
from contextlib import contextmanager

import numpy as np
import scipy.sparse as sp

from ..core import matrix
from ..core.comm import mpi_comm
from ..core.errors import ProblemError
from . import import_petsc
from .comm import to_petsc_comm


def ownership(n: int, rank: int, size: int) -> tuple[int, int]:
    """PETSc's default contiguous split of ``n`` rows: ``[start, end)`` of ``rank``."""
    base, extra = divmod(n, size)
    start = rank * base + min(rank, extra)
    return start, start + base + (1 if rank < extra else 0)


def mat_from_local_csr(comm, local_rows: sp.csr_matrix, n_global: int | None = None):
    """A square MPIAIJ (or SeqAIJ on one rank) whose local rows are ``local_rows``.

    ``local_rows`` has this rank's rows and all global columns.  Collective.
    """
    PETSc = import_petsc()
    pcomm = to_petsc_comm(comm)
    local_rows = sp.csr_matrix(local_rows, dtype=PETSc.ScalarType)
    local_rows.sort_indices()
    n_local, n_cols = local_rows.shape
    n_global = n_cols if n_global is None else n_global
    A = PETSc.Mat().createAIJ(
        size=((n_local, n_global), (n_local, n_global)),
        csr=(local_rows.indptr.astype(PETSc.IntType), local_rows.indices.astype(PETSc.IntType),
             local_rows.data),
        comm=pcomm)
    A.assemble()
    return A


def mat_from_scipy(comm, A: sp.spmatrix):
    """Distribute a matrix every rank holds (small problems, tests) by PETSc's default split."""
    pcomm = to_petsc_comm(comm)
    A = sp.csr_matrix(A)
    start, end = ownership(A.shape[0], pcomm.getRank(), pcomm.getSize())
    return mat_from_local_csr(pcomm, A[start:end], A.shape[0])


@contextmanager
def distributed(comm, *mats):
    """``with distributed(comm, A, B) as (A, B):`` — the matrices as PETSc Mats: a PETSc one as
    it is, a SciPy one (every rank holding it) distributed here (:func:`mat_from_scipy`) and
    destroyed on exit (collective)."""
    made = [None if matrix.is_petsc_mat(M) else mat_from_scipy(comm, M) for M in mats]
    try:
        yield tuple(M if m is None else m for M, m in zip(mats, made))
    finally:
        for m in made:
            if m is not None:
                m.destroy()


def mat_to_scipy(A) -> sp.csr_matrix:
    """Gather a PETSc AIJ matrix into a SciPy CSR matrix on every rank.  Collective."""
    indptr, indices, data = A.getValuesCSR()
    start, _ = A.getOwnershipRange()
    local = sp.csr_matrix((data, indices, indptr), shape=(A.getLocalSize()[0], A.getSize()[1]))
    comm = mpi_comm(A.getComm())
    if comm is None:
        return local.tocsr()
    coo = local.tocoo()
    rows = comm.allgather(coo.row + start)
    cols = comm.allgather(coo.col)
    vals = comm.allgather(coo.data)
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                         shape=A.getSize())


def vec_to_numpy(v) -> np.ndarray:
    """Gather a PETSc Vec into a NumPy array on every rank.  Collective."""
    comm = mpi_comm(v.getComm())
    local = v.getArray(readonly=True).copy()
    if comm is None:
        return local
    return np.concatenate(comm.allgather(local))


def mat_from_rows(comm, local_rows: sp.csr_matrix, shape: tuple[int, int], local_cols: int):
    """A rectangular AIJ matrix: this rank's rows ``local_rows`` (all global columns) and
    ``local_cols`` columns in the column layout (the row layout of the matrix it multiplies
    from the right).  Collective."""
    PETSc = import_petsc()
    pcomm = to_petsc_comm(comm)
    local_rows = sp.csr_matrix(local_rows, dtype=PETSc.ScalarType)
    local_rows.sort_indices()
    A = PETSc.Mat().createAIJ(
        size=((local_rows.shape[0], shape[0]), (local_cols, shape[1])),
        csr=(local_rows.indptr.astype(PETSc.IntType), local_rows.indices.astype(PETSc.IntType),
             local_rows.data),
        comm=pcomm)
    A.assemble()
    return A


def nonzeros(A, *, total: bool = True) -> dict:
    """PETSc's nonzero bookkeeping of an AIJ matrix, as ints: ``nz_used``, ``nz_allocated``,
    ``mallocs`` — summed over the ranks (``total``, collective) or this rank's part."""
    PETSc = import_petsc()
    info = A.getInfo(PETSc.Mat.InfoType.GLOBAL_SUM if total else PETSc.Mat.InfoType.LOCAL)
    return {k: int(info[k]) for k in ("nz_used", "nz_allocated", "mallocs")}


def storage_bytes(A) -> int:
    """Bytes of this rank's part of an AIJ matrix: values, column indices and row starts."""
    PETSc = import_petsc()
    nnz = nonzeros(A, total=False)["nz_allocated"]
    m = A.getLocalSize()[0]
    isz = np.dtype(PETSc.IntType).itemsize
    return nnz * (np.dtype(PETSc.ScalarType).itemsize + isz) + (m + 1) * isz


def diagonal(A):
    """The diagonal of A as a PETSc Vec distributed like A's rows (the caller destroys it)."""
    return A.getDiagonal()


def symmetric_part(M):
    """``(M + Mᵀ)/2``: SciPy in, SciPy out; a PETSc Mat in, a new PETSc Mat out (collective;
    the caller destroys it)."""
    if not matrix.is_petsc_mat(M):
        M = sp.csr_matrix(M)
        return ((M + M.T) * 0.5).tocsr()
    PETSc = import_petsc()
    MT = M.transpose(PETSc.Mat())  # a new matrix: petsc4py's transpose() with no argument works in place
    S = M.duplicate(copy=True)
    S.axpy(1.0, MT, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
    S.scale(0.5)
    MT.destroy()
    return S


def combination(X, alpha: float, Y):
    """``X + α·Y`` as a new matrix: SciPy in, SciPy out; PETSc Mats in, a new PETSc Mat out
    (collective; the caller destroys it)."""
    if not matrix.is_petsc_mat(X):
        return (X + float(alpha) * Y).tocsr()
    PETSc = import_petsc()
    S = X.duplicate(copy=True)
    S.axpy(float(alpha), Y, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
    return S


@contextmanager
def destroying(*objects):
    """``with destroying(K, M) as (K, M):`` — the objects, and on exit ``destroy()`` (collective)
    of those that are PETSc objects; NumPy / SciPy ones and None pass through untouched."""
    try:
        yield objects
    finally:
        for obj in objects:
            if type(obj).__module__.startswith("petsc4py"):
                obj.destroy()


class PetscMat(abc.ABC):
    """petsc4py's ``PETSc.Mat`` (and its subclasses), recognised by module and name: the
    dispatch functions of :mod:`meicp.core.matrix` are registered against this class, so
    that registering needs no petsc4py import (which would start PETSc before
    :func:`~meicp.petsc.init` has the command line's options)."""

    @classmethod
    def __subclasshook__(cls, C):
        if any(k.__name__ == "Mat" and k.__module__ == "petsc4py.PETSc" for k in C.__mro__):
            return True
        return NotImplemented


# -- the PETSc Mat's implementations of meicp.core.matrix, collective on its communicator --

@matrix.is_petsc_mat.register(PetscMat)
def _is_petsc_mat(M) -> bool:
    return True


@matrix.matrix_shape.register(PetscMat)
def _shape(M) -> tuple[int, int]:
    return M.getSize()


@matrix.matrix_comm.register(PetscMat)
def _comm(M):
    return mpi_comm(M.getComm())


@matrix.checked_matrix.register(PetscMat)
def _checked(M, name: str = "M"):
    """Square, non-empty and finite (a norm: collective); the Mat itself, not a copy."""
    m, n = M.getSize()
    if m != n or m == 0:
        raise ProblemError(f"{name} must be square and non-empty, got shape {(m, n)}")
    if not np.isfinite(M.norm(import_petsc().NormType.FROBENIUS)):
        raise ProblemError(f"{name} contains NaN or Inf")
    return M


@matrix.to_dense.register(PetscMat)
def _to_dense(M) -> np.ndarray:
    return mat_to_scipy(M).toarray()


matrix.to_scipy.register(PetscMat, mat_to_scipy)


@matrix.matvec.register(PetscMat)
def _matvec(M, x: np.ndarray) -> np.ndarray:
    X = M.createVecRight()
    lo, hi = X.getOwnershipRange()
    X.setArray(x[lo:hi])
    Y = M.createVecLeft()
    M.mult(X, Y)
    out = vec_to_numpy(Y)
    X.destroy()
    Y.destroy()
    return out


@matrix.max_abs_entry.register(PetscMat)
def _max_abs_entry(M) -> float:
    _, _, data = M.getValuesCSR()
    local = float(np.max(np.abs(data))) if data.size else 0.0
    comm = mpi_comm(M.getComm())
    return local if comm is None else max(comm.allgather(local))


@matrix.row_max_abs.register(PetscMat)
def _row_max_abs(M) -> np.ndarray:
    indptr, _, data = M.getValuesCSR()
    local = np.zeros(len(indptr) - 1)
    rows = np.repeat(np.arange(local.size), np.diff(indptr))
    np.maximum.at(local, rows, np.abs(data))
    return np.concatenate(M.getComm().tompi4py().allgather(local))


@matrix.is_symmetric.register(PetscMat)
def _is_symmetric(M, rtol: float = 1e-12) -> bool:
    """PETSc's own test, with its absolute tolerance made relative to max|M|."""
    return bool(M.isSymmetric(rtol * _max_abs_entry(M)))


@matrix.ldexp.register(PetscMat)
def _ldexp(M, exponent: int):
    out = M.duplicate(copy=True)
    out.scale(2.0 ** exponent)
    return out


@matrix.release.register(PetscMat)
def _release(M) -> None:
    M.destroy()
