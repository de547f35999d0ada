"""Inertia of a symmetric matrix by a MUMPS LDLᵀ factorisation (Sylvester's law), and the
proof it gives that a symmetric pencil has no eigenvalue σ ≥ 0.

For a symmetric pencil (A, B) with B SPD, the number of eigenvalues σ ≥ 0 equals the number
of nonnegative eigenvalues of A: a factorisation *proves* that none exists, which an
eigensolver that only looks near a target cannot.  A proof must survive rounding.  The LDLᵀ
(Cholesky) factorisation of a definite matrix is backward stable relative to its diagonal:
the computed inertia is exact for a matrix within about ``c·eps·sqrt(|a_ii·a_jj|)`` of it,
entry by entry.  So the proof factors ``A + η·D`` with ``D = diag(|a_ii|)`` and ``η`` above
that level (:func:`rounding_margin`): negative definite means ``D^-½ A D^-½ ≺ −η·I`` as
computed, hence A ≺ 0 — whatever the scaling of A's rows (a layer 10¹⁵ times softer keeps its
proof).  When ``A + ηD`` is not negative definite but ``A − ηD`` is, the largest eigenvalue of
the diagonally scaled A lies within rounding of 0: undecided, never "stable".  Collective on
the matrices' communicator.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..core.comm import mpi_comm
from ..core.matrix import is_petsc_mat
from ..core.validation import is_symmetric
from . import import_petsc
from .mat import mat_from_scipy, symmetric_part
from .options import INERTIA, OptionsScope

PREFIX = INERTIA
#: the rounding margin of a definiteness proof, in units of ``sqrt(n)·eps`` relative to the
#: diagonal: above the backward error of the factorisation of a definite matrix (``eps``
#: times a factor growing slowly with n) and the rounding of assembling it
ROUNDING = 16.0


#: MUMPS settings under which PETSc asks it for the inertia: ICNTL(13) = 1 (no ScaLAPACK
#: root) and ICNTL(24) = 1 (null pivot detection), required in parallel
INERTIA_OPTIONS = {"mat_mumps_icntl_13": 1, "mat_mumps_icntl_24": 1}


def inertia(A) -> tuple[int, int, int]:
    """``(negative, zero, positive)`` eigenvalue counts of the symmetric PETSc matrix A."""
    PETSc = import_petsc()
    ksp = PETSc.KSP().create(comm=A.getComm())
    try:
        ksp.setOperators(A)
        defaults = {"ksp_type": "preonly", "pc_type": "cholesky",
                    "pc_factor_mat_solver_type": "mumps", **INERTIA_OPTIONS}
        with OptionsScope(PREFIX, defaults) as scope:
            scope.configure(ksp)
            ksp.setUp()
        nneg, nzero, npos = ksp.getPC().getFactorMatrix().getInertia()
        return int(nneg), int(nzero), int(npos)
    finally:
        ksp.destroy()


@dataclass(frozen=True)
class SignProof:
    """Whether every eigenvalue of a symmetric pencil (A, B) is proved negative.

    proved: True (B ≻ 0 and A ≺ 0 with a margin above rounding: no σ ≥ 0), None (the
    largest eigenvalue of A lies within ``margin`` of 0: undecided), False (A has an
    eigenvalue above the margin, or B is not positive definite: the bound proves nothing).
    reason: one sentence saying which.  margin: the rounding margin η used.  above: the
    eigenvalues of A proved above the margin (0 unless ``proved`` is False with B ≻ 0).
    b_definite: whether B ≻ 0 was proved (False: no Rayleigh-quotient bound holds at all).
    """

    proved: bool | None
    reason: str
    margin: float
    above: int = 0
    b_definite: bool = True


def rounding_margin(n: int) -> float:
    """``ROUNDING·sqrt(n)·eps``: a shift by more than this times the diagonal survives the
    rounding of an LDLᵀ factorisation of an n×n matrix."""
    return ROUNDING * math.sqrt(max(n, 1)) * np.finfo(float).eps


def pencil_is_negative(A, B, *, symmetric: bool = False) -> SignProof | None:
    """For a symmetric pencil (A, B): a proof that no eigenvalue σ ≥ 0 exists (see
    :class:`SignProof`), or None when the pencil is not symmetric.  A, B: SciPy (factored
    on this process) or PETSc Mats (collective).  ``symmetric=True``: the caller built both
    symmetric, the check (a transpose of each) is skipped."""
    if not symmetric and (not _symmetric(A) or not _symmetric(B)):
        return None
    return _negative_with_margin(A, B, "A")


def rayleigh_bound(A, B, tau: float = 0.0, *, decisive: bool = True) -> SignProof:
    """Whether ``sym(A) − τ·sym(B) ≺ 0`` with ``sym(B) ≻ 0``, both with a margin above rounding.

    For every MEiCP solution (x real, xᵀw = 0) ``σ·xᵀBx = xᵀAx``, i.e.
    ``σ = xᵀsym(A)x / xᵀsym(B)x``: proved, no solution has σ ≥ τ (τ = 0: no divergence mode
    at all).  Holds for a nonsymmetric pencil, a frictional interface's non-diagonal B
    included.  A, B: SciPy or PETSc (collective).  ``decisive=False`` spares the second
    factorisation that tells a borderline case (None) from a clear failure (False): a caller
    that only acts on ``proved is True`` gets False for both, with ``above`` the eigenvalues
    not proved below the margin."""
    SA, SB = symmetric_part(A), symmetric_part(B)
    try:
        if tau != 0.0:
            if is_petsc_mat(SA):
                PETSc = import_petsc()
                SA.axpy(-float(tau), SB, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
            else:
                SA = (SA - float(tau) * SB).tocsr()
        return _negative_with_margin(SA, SB, "sym(A)" if tau == 0.0 else f"sym(A) − {tau:.6g}·sym(B)", decisive)
    finally:
        for M in (SA, SB):
            if is_petsc_mat(M):
                M.destroy()


def symmetric_part_definite(B) -> tuple[bool, str]:
    """Whether ``sym(B) ≻ 0`` (exactly for a diagonal B, else by an LDLᵀ inertia with a
    margin above rounding) and the sentence saying how.  SciPy or PETSc (collective)."""
    SB = symmetric_part(B)
    try:
        return _positive_definite(SB)
    finally:
        if is_petsc_mat(SB):
            SB.destroy()


def _negative_with_margin(A, B, name: str, decisive: bool = True) -> SignProof:
    b_ok, b_text = _positive_definite(B)
    if not b_ok:
        return SignProof(False, b_text, 0.0, b_definite=False)
    eta = rounding_margin(_size(A))
    above = nonnegative_count(A, eta)          # eigenvalues of D^-½ A D^-½ ≥ −η
    if above == 0:
        return SignProof(True, f"{name} + η·diag|·| is negative definite (η = {eta:.1e}, above rounding) and "
                               f"{b_text}", eta)
    if not decisive:
        return SignProof(False, f"{name} + η·diag|·| is not negative definite ({above} eigenvalue(s) of the diagonally "
                                f"scaled {name} ≥ −η, η = {eta:.1e}): the bound excludes nothing", eta, above)
    clearly = nonnegative_count(A, -eta)       # ... ≥ +η
    if clearly == 0:
        return SignProof(None, f"{above} eigenvalue(s) of {name} lie within rounding of 0 ({name} − η·diag|·| is "
                               f"negative definite, {name} + η·diag|·| is not; η = {eta:.1e}): undecided", eta)
    return SignProof(False, f"{name} has {clearly} eigenvalue(s) above rounding ({name} − η·diag|·| is not "
                            f"negative definite, η = {eta:.1e}): the bound excludes nothing", eta, clearly)


def _size(M) -> int:
    return M.getSize()[0] if is_petsc_mat(M) else M.shape[0]


def _symmetric(M) -> bool:
    if is_petsc_mat(M):
        return bool(M.isSymmetric(1e-12 * max(abs(M.norm()), 1e-300)))
    return is_symmetric(M, 1e-12)


def nonnegative_count(A, eta: float) -> int:
    """Eigenvalues ≥ 0 (zero and positive pivots) of ``A + eta·D``, ``D = diag(|a_ii|)``
    (a zero diagonal entry shifted by eta times its row's largest entry)."""
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
        C = mat_from_scipy(None, (A + sp.diags(eta * _diagonal_scale(A.diagonal(), rowmax))).tocsr())
    try:
        _, zero, positive = inertia(C)
    finally:
        C.destroy()
    return zero + positive


def _row_maxima(indptr: np.ndarray, data: np.ndarray) -> np.ndarray:
    """The largest |entry| of each CSR row (0 for an empty row), by one ``reduceat``
    (``np.maximum.at`` took 0.3 s per call at 10⁶ rows)."""
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


def _positive_definite(B) -> tuple[bool, str]:
    """Whether B ≻ 0: exactly for a diagonal B (every mass positive), else by the inertia of
    ``B − η·diag|B|``."""
    diagonal, smallest = diagonal_minimum(B)
    if diagonal:
        if smallest > 0:
            return True, f"B is diagonal with positive entries (smallest {smallest:.3g})"
        return False, f"B is diagonal with an entry {smallest:.3g} ≤ 0: the Rayleigh-quotient bound does not apply"
    n = _size(B)
    eta = rounding_margin(n)
    if n - nonnegative_count(B, -eta) == 0:  # every pivot of B − η·diag|B| positive
        return True, f"B − η·diag|B| is positive definite (η = {eta:.1e})"
    return False, "B is not proved positive definite: the Rayleigh-quotient bound does not apply"

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
