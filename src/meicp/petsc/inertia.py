"""Inertia of a symmetric matrix by a MUMPS LDLᵀ factorisation (Sylvester's law), with the
rounding information a proof needs — the adapter only; what an inertia proves about an
MEiCP's σ is :mod:`meicp.contact.rayleigh`.

The LDLᵀ (Cholesky) factorisation of a definite matrix is backward stable relative to its
diagonal: the computed inertia is exact for a matrix within about ``c·eps·sqrt(|a_ii·a_jj|)``
of it, entry by entry.  So :func:`nonnegative_count` factors ``A + η·D`` with
``D = diag(|a_ii|)``, and :func:`rounding_margin` gives an ``η`` above that level.
Collective on the matrices' communicator.
"""

from __future__ import annotations

import math
from contextlib import contextmanager

import numpy as np
import scipy.sparse as sp

from ..core.comm import mpi_comm
from ..core.matrix import is_petsc_mat
from ..core.validation import is_symmetric
from ..lattice.node_blocks import NodeBlocks
from . import import_petsc
from .mat import destroying, mat_from_scipy, symmetric_part
from .options import INERTIA, OptionsScope, require_mumps_factor

PREFIX = INERTIA
#: the rounding margin of a definiteness proof, in units of ``sqrt(n)·eps`` relative to the
#: diagonal: above the backward error of the factorisation of a definite matrix (``eps``
#: times a factor growing slowly with n) and the rounding of assembling it
ROUNDING = 16.0


#: MUMPS settings under which PETSc asks it for the inertia: ICNTL(13) = 1 (no ScaLAPACK
#: root) and ICNTL(24) = 1 (null pivot detection), required in parallel
INERTIA_OPTIONS = {"mat_mumps_icntl_13": 1, "mat_mumps_icntl_24": 1}
#: the ordering: AMF (ICNTL(7) = 2; no METIS in Debian's MUMPS), and PORD (4, nested
#: dissection) from PORD_FROM rows.  AMF was 1.1–1.4 s faster on the shipped 10⁶-DOF scenes
#: but took 64 s where PORD takes 2.6 s on a 6-row, 83,333-column lattice (10⁶ DOFs, 2 ranks):
#: a local ordering of a long strip builds a deep, narrow elimination tree
#: (docs/benchmarks-notes.md, "inertia ordering").  PORD ends the process (exit, no error
#: returned) on small or dense matrices ("no valid number of stages in multisector": every
#: dense n ≤ 50 tried, a 2-column lattice's pencil), hence AMF below PORD_FROM
ORDERING = {"mat_mumps_icntl_7": 2}
PORD_ORDERING = {"mat_mumps_icntl_7": 4}
PORD_FROM = 100_000


def inertia(A) -> tuple[int, int, int]:
    """``(negative, zero, positive)`` eigenvalue counts of the symmetric PETSc matrix A."""
    PETSc = import_petsc()
    n = A.getSize()[0]
    if A.norm(PETSc.NormType.INFINITY) == 0.0:  # MUMPS factors no zero matrix (a mechanism's pencil)
        return 0, n, 0
    ksp = PETSc.KSP().create(comm=A.getComm())
    try:
        ksp.setOperators(A)
        ordering = PORD_ORDERING if n >= PORD_FROM else ORDERING
        defaults = {"ksp_type": "preonly", "pc_type": "cholesky",
                    "pc_factor_mat_solver_type": "mumps", **ordering, **INERTIA_OPTIONS}
        with OptionsScope(PREFIX, defaults) as scope:
            scope.configure(ksp)
            require_mumps_factor(ksp, PREFIX, ("cholesky",), "the inertia proof")
            ksp.setUp()
        nneg, nzero, npos = ksp.getPC().getFactorMatrix().getInertia()
        return int(nneg), int(nzero), int(npos)
    finally:
        ksp.destroy()


def rounding_margin(n: int) -> float:
    """``ROUNDING·sqrt(n)·eps``: a shift by more than this times the diagonal survives the
    rounding of an LDLᵀ factorisation of an n×n matrix."""
    return ROUNDING * math.sqrt(max(n, 1)) * np.finfo(float).eps


@contextmanager
def shifted_symmetric_parts(A, B, tau: float = 0.0):
    """``with shifted_symmetric_parts(A, B, τ) as (S, SB):`` ``S = sym(A) − τ·sym(B)`` and
    ``SB = sym(B)``, of A's kind (SciPy, or new PETSc Mats destroyed on exit; collective)."""
    SA, SB = symmetric_part(A), symmetric_part(B)
    with destroying(SA, SB):
        if tau != 0.0:
            if is_petsc_mat(SA):
                PETSc = import_petsc()
                SA.axpy(-float(tau), SB, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
            else:
                SA = (SA - float(tau) * SB).tocsr()
        yield SA, SB


@contextmanager
def symmetric_part_of(B):
    """``with symmetric_part_of(B) as SB:`` ``sym(B)``, of B's kind (destroyed on exit)."""
    SB = symmetric_part(B)
    with destroying(SB):
        yield SB


def order(M) -> int:
    """The number of rows of a square SciPy or PETSc matrix."""
    return M.getSize()[0] if is_petsc_mat(M) else M.shape[0]


def is_symmetric_matrix(M) -> bool:
    """Whether M equals its transpose to 1e-12 of its norm (SciPy or PETSc, collective)."""
    if is_petsc_mat(M):
        return bool(M.isSymmetric(1e-12 * max(abs(M.norm()), 1e-300)))
    return is_symmetric(M, 1e-12)


def nonnegative_count(A, eta: float, comm=None, groups=None) -> int:
    """Eigenvalues ≥ 0 (zero and positive pivots) of ``A + eta·D``, ``D = diag(|a_ii|)``
    (a zero diagonal entry shifted by eta times its row's largest entry).  A SciPy A (every
    rank holding it) is factored over ``comm`` (None: this process alone; collective), padded
    with explicit zeros to whole ``groups`` (the lattice node of each row,
    :class:`~meicp.lattice.node_blocks.NodeBlocks`) when given: SciPy's products drop the
    zeros of a node block, and the LDLᵀ of a 10⁶-DOF pencil took 21–26 s without them,
    12–16 s with them (docs/benchmarks-notes.md, "floor inertias")."""
    if is_petsc_mat(A):
        C = A.duplicate(copy=True)
        d = C.getDiagonal()
        lo, hi = C.getOwnershipRange()
        indptr, _, data = C.getValuesCSR()
        rowmax = _row_maxima(indptr, data)
        d.setArray(eta * _diagonal_scale(d.getArray(), rowmax))
        C.setDiagonal(d, addv=True)
        d.destroy()
    else:
        A = sp.csr_matrix(A)
        rowmax = abs(A).max(axis=1).toarray().ravel()
        C = (A + sp.diags(eta * _diagonal_scale(A.diagonal(), rowmax))).tocsr()
        C = mat_from_scipy(comm, C if groups is None else NodeBlocks(groups).pad(C))
    try:
        _, zero, positive = inertia(C)
    finally:
        C.destroy()
    return zero + positive


def _row_maxima(indptr: np.ndarray, data: np.ndarray) -> np.ndarray:
    """The largest |entry| of each CSR row (0 for an empty row), by one ``reduceat``
    (``np.maximum.at`` is far slower at 10⁶ rows: docs/benchmarks-notes.md, "row maxima")."""
    counts = np.diff(indptr)
    out = np.zeros(counts.size)
    nonempty = counts > 0
    if data.size:
        out[nonempty] = np.maximum.reduceat(np.abs(data), indptr[:-1][nonempty])
    return out


def _diagonal_scale(diag: np.ndarray, rowmax: np.ndarray) -> np.ndarray:
    return np.where(diag != 0, np.abs(diag), rowmax)


def diagonal_scale(A: sp.spmatrix) -> np.ndarray:
    """``D`` of the rounding margin ``η·D`` for a SciPy matrix: |a_ii|, or the row's largest
    |entry| where a_ii = 0."""
    A = sp.csr_matrix(A)
    return _diagonal_scale(A.diagonal(), _row_maxima(A.indptr, A.data))


def diagonal_minimum(B) -> tuple[bool, float]:
    """(B has no off-diagonal entry, its smallest diagonal entry); collective for PETSc."""
    if is_petsc_mat(B):
        lo, _ = B.getOwnershipRange()
        indptr, indices, data = B.getValuesCSR()
        rows = lo + np.repeat(np.arange(len(indptr) - 1), np.diff(indptr))
        off = (indices != rows) & (data != 0)
        diag = np.zeros(len(indptr) - 1)
        on = indices == rows
        diag[rows[on] - lo] = data[on]
        local = (not off.any(), float(diag.min()) if diag.size else math.inf)
        comm = mpi_comm(B.getComm())
        parts = [local] if comm is None else comm.allgather(local)
        return all(p[0] for p in parts), min(p[1] for p in parts)
    B = sp.csr_matrix(B)
    d = B.diagonal()
    off = B - sp.diags(d)
    return off.count_nonzero() == 0, float(d.min()) if d.size else math.inf
