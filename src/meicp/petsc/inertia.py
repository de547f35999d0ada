"""Inertia of a symmetric matrix by a MUMPS LDLᵀ factorisation (Sylvester's law).

For a symmetric pencil (A, B) with B SPD, the number of eigenvalues λ > τ equals the
number of positive eigenvalues of ``A − τB``: a factorisation *proves* that no
eigenvalue reaches τ, which an eigensolver that only looks near a target cannot.
Collective on the matrix's communicator.
"""

from __future__ import annotations

from ..core.validation import is_symmetric
from . import import_petsc
from .mat import is_petsc_mat, mat_from_scipy
from .options import INERTIA, OptionsScope

PREFIX = INERTIA


def inertia(A) -> tuple[int, int, int]:
    """``(negative, zero, positive)`` eigenvalue counts of the symmetric PETSc matrix A."""
    PETSc = import_petsc()
    ksp = PETSc.KSP().create(comm=A.getComm())
    try:
        ksp.setOperators(A)
        # PETSc asks MUMPS for the inertia only with ICNTL(13) = 1 (no ScaLAPACK root) and
        # ICNTL(24) = 1 (null pivot detection), required in parallel
        defaults = {"ksp_type": "preonly", "pc_type": "cholesky",
                    "pc_factor_mat_solver_type": "mumps", "mat_mumps_icntl_13": 1,
                    "mat_mumps_icntl_24": 1}
        with OptionsScope(PREFIX, defaults) as scope:
            scope.configure(ksp)
            ksp.setUp()
        nneg, nzero, npos = ksp.getPC().getFactorMatrix().getInertia()
        return int(nneg), int(nzero), int(npos)
    finally:
        ksp.destroy()


def eigenvalues_at_or_above(A, B, lam_min: float):
    """How many eigenvalues of the pencil (A, B) are ≥ lam_min when it is symmetric with B SPD
    (Sylvester's inertia of ``A − lam_min·B``); None for a nonsymmetric pencil.  A, B: SciPy
    (factored on this process) or PETSc Mats (collective)."""
    if is_petsc_mat(A):
        a = max(abs(A.norm()), 1e-300)
        if not (A.isSymmetric(1e-12 * a) and B.isSymmetric(1e-12 * a)):
            return None
        C = A.duplicate(copy=True)
        C.axpy(-lam_min, B)
    else:
        if not (is_symmetric(A, 1e-12) and is_symmetric(B, 1e-12)):
            return None
        C = mat_from_scipy(None, (A - lam_min * B).tocsr())
    try:
        _, zero, positive = inertia(C)
    finally:
        C.destroy()
    return zero + positive
