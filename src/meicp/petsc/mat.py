"""Distributed matrices from per-rank CSR rows, and back to SciPy.

Build each rank's rows with NumPy/SciPy and hand them to ``createAIJ(csr=...)``
(DESIGN §6: a Python ``setValues`` loop is 40× slower).  Collective on ``comm``.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from . import import_petsc, to_petsc_comm


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


def mat_to_scipy(A) -> sp.csr_matrix:
    """Gather a PETSc AIJ matrix into a SciPy CSR matrix on every rank.  Collective."""
    indptr, indices, data = A.getValuesCSR()
    start, _ = A.getOwnershipRange()
    local = sp.csr_matrix((data, indices, indptr), shape=(A.getLocalSize()[0], A.getSize()[1]))
    comm = A.getComm().tompi4py()
    if comm.Get_size() == 1:
        return local.tocsr()
    coo = local.tocoo()
    rows = comm.allgather(coo.row + start)
    cols = comm.allgather(coo.col)
    vals = comm.allgather(coo.data)
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                         shape=A.getSize())


def vec_to_numpy(v) -> np.ndarray:
    """Gather a PETSc Vec into a NumPy array on every rank.  Collective."""
    comm = v.getComm().tompi4py()
    local = v.getArray(readonly=True).copy()
    if comm.Get_size() == 1:
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
