"""Dense Schur complements of a distributed sparse matrix by MUMPS, and MUMPS solves with
blocks of right-hand sides: the factorisations behind the condensation of a pencil onto its
contact DOFs (:mod:`meicp.contact.condensation`).

:func:`schur_complement` asks MUMPS for the Schur complement (ICNTL(19)) through PETSc's
``MatFactorSetSchurIS`` / ``MatFactorCreateSchurComplement``, which petsc4py 3.18 does not
wrap: they are called through ctypes on the petsc4py handles (libpetsc is already loaded, as
for :func:`meicp.petsc.options.options_used`).  PETSc 3.18's MUMPS interface supports this in
parallel only when the whole Schur index set is given on rank 0 ("MUMPS distributed parallel
Schur complements not yet supported from PETSc" otherwise): MUMPS then returns the Schur
complement centralised on the host, a SeqDense on rank 0, which is broadcast.  The Schur
complement comes without a residual: its error is measured by the caller
(:func:`meicp.contact.divergence.condensed.prove_no_divergence` probes it with :class:`MumpsFactor`).

:class:`MumpsFactor` is the fallback and the solver of the probes and lifts: one MUMPS
factorisation, ``Mat.matSolve`` on dense blocks.  Options under ``-meicp_schur_``.
Collective on ``comm``.
"""
from __future__ import annotations

import ctypes

import numpy as np
import scipy.sparse as sp

from ..core.comm import mpi_comm
from . import import_petsc, mumps_c
from .comm import to_petsc_comm
from .mat import mat_from_local_csr, ownership
from .options import SCHUR, OptionsScope, mumps_controls, require_mumps_factor

_C = None
_MUMPS = {"pc_factor_mat_solver_type": "mumps", "mat_mumps_icntl_7": 2}  # AMF ordering (no METIS in Debian's MUMPS)
#: MUMPS' block-low-rank factorisation for the Schur complements, dropping at this relative
#: threshold (ICNTL(35) = 2, CNTL(7)): faster than full rank and as accurate — it differed
#: from the full-rank complement by 1.6e-16 relative, rounding.  1e-12 was faster still but
#: 4e-15 off — relative to the largest entry, which is of the ill-conditioned block Z: the
#: measured error of G rose from 1.2e-12 to 4.1e-12 and the critical friction's exact
#: bracket at 10⁶ DOFs widened to 2e-5 (the timings: docs/benchmarks-notes.md).  Only where the error is
#: measured (:func:`schur_complement`'s callers probe it); the factors whose inertia is a
#: proof (:class:`MumpsFactor`) stay full rank
SCHUR_LOW_RANK = 1e-14


def _lib():
    global _C
    if _C is None:
        import_petsc()
        try:
            lib = ctypes.CDLL(None)
            lib.MatFactorSetSchurIS
        except AttributeError:
            lib = ctypes.CDLL("libpetsc_real.so.3.18")
        vp = ctypes.c_void_p
        dp = ctypes.POINTER(ctypes.POINTER(ctypes.c_double))
        lib.MatFactorSetSchurIS.argtypes = [vp, vp]
        lib.MatFactorCreateSchurComplement.argtypes = [vp, ctypes.POINTER(vp), vp]
        lib.MatDenseGetArrayRead.argtypes = [vp, dp]
        lib.MatDenseRestoreArrayRead.argtypes = [vp, dp]
        lib.MatGetSize.argtypes = [vp, ctypes.POINTER(ctypes.c_int), ctypes.POINTER(ctypes.c_int)]
        lib.MatDestroy.argtypes = [ctypes.POINTER(vp)]
        for f in ("MatFactorSetSchurIS", "MatFactorCreateSchurComplement", "MatDenseGetArrayRead",
                  "MatDenseRestoreArrayRead", "MatGetSize", "MatDestroy"):
            getattr(lib, f).restype = ctypes.c_int
        _C = lib
    return _C


def _check(code: int, what: str) -> None:
    if code != 0:
        raise RuntimeError(f"{what} returned PETSc error {code}")


def _distribute(comm, H: sp.spmatrix):
    """H (every rank holds it) as a PETSc Mat in PETSc's default row split."""
    pcomm = to_petsc_comm(comm)
    H = sp.csr_matrix(H)
    s, e = ownership(H.shape[0], pcomm.getRank(), pcomm.getSize())
    return mat_from_local_csr(pcomm, H[s:e], H.shape[0])


def schur_complement(A, rows: np.ndarray, *, symmetric: bool, options: dict | None = None) -> np.ndarray:
    """``A_SS − A_SF A_FF⁻¹ A_FS`` (S = the global indices ``rows``, in their order) of the
    PETSc matrix A, dense, on every rank.  ``symmetric``: MUMPS LDLᵀ (indefinite allowed;
    A_FF must factor without pivoting into S, which holds when A_FF is definite), else LU.
    Block low-rank (:data:`SCHUR_LOW_RANK`) unless ``options`` say otherwise: an error the
    caller measures.  Collective."""
    PETSc = import_petsc()
    lib = _lib()
    pcomm = A.getComm()
    rank = pcomm.getRank()
    ksp = PETSc.KSP().create(comm=pcomm)
    pc = F = None
    try:
        ksp.setOperators(A)
        defaults = {"ksp_type": "preonly", "pc_type": "cholesky" if symmetric else "lu", **_MUMPS,
                    "mat_mumps_icntl_35": 2, "mat_mumps_cntl_7": SCHUR_LOW_RANK}
        with OptionsScope(SCHUR, defaults, options) as scope:
            scope.configure(ksp)
            require_mumps_factor(ksp, SCHUR, ("cholesky", "lu"), "the condensation onto the contact DOFs")
            pc = ksp.getPC()
            pc.setFactorSetUpSolverType()
            F = pc.getFactorMatrix()
            idx = np.asarray(rows, dtype=PETSc.IntType) if rank == 0 else np.zeros(0, dtype=PETSc.IntType)
            iset = PETSc.IS().createGeneral(idx, comm=pcomm)
            try:
                _check(lib.MatFactorSetSchurIS(F.handle, iset.handle), "MatFactorSetSchurIS")
                ksp.setUp()
            finally:
                iset.destroy()
        raw = ctypes.c_void_p()
        _check(lib.MatFactorCreateSchurComplement(F.handle, ctypes.byref(raw), None), "MatFactorCreateSchurComplement")
        m, n = ctypes.c_int(), ctypes.c_int()
        _check(lib.MatGetSize(raw, ctypes.byref(m), ctypes.byref(n)), "MatGetSize")
        X = None
        if rank == 0:
            ptr = ctypes.POINTER(ctypes.c_double)()
            _check(lib.MatDenseGetArrayRead(raw, ctypes.byref(ptr)), "MatDenseGetArrayRead")
            X = np.ctypeslib.as_array(ptr, shape=(n.value, m.value)).T.copy()  # PETSc dense is column-major
            _check(lib.MatDenseRestoreArrayRead(raw, ctypes.byref(ptr)), "MatDenseRestoreArrayRead")
        _check(lib.MatDestroy(ctypes.byref(raw)), "MatDestroy")
    finally:
        # the Python handles of the PC and its factor hold references of their own: drop
        # them first, or the factor (a whole MUMPS factorisation) outlives the KSP
        for handle in (F, pc):
            if handle is not None:
                handle.destroy()
        ksp.destroy()
    if pcomm.getSize() > 1:
        X = pcomm.tompi4py().bcast(X, root=0)
    return X


def dense_schur(comm, H: sp.spmatrix, rows: np.ndarray, *, symmetric: bool, options: dict | None = None) -> np.ndarray:
    """:func:`schur_complement` of a SciPy matrix every rank holds (distributed by rows for
    MUMPS).  Collective."""
    A = _distribute(comm, H)
    try:
        return schur_complement(A, rows, symmetric=symmetric, options=options)
    finally:
        A.destroy()


def schur_series(comm, H0: sp.spmatrix, H1: sp.spmatrix, rows: np.ndarray, H2: sp.spmatrix | None = None):
    """σ ↦ :func:`dense_schur` of the symmetric H₀ + σH₁ (+ σ²H₂ with ``H2``; one pattern, every
    rank holds them)
    onto ``rows``, with one MUMPS analysis for every σ (:class:`~meicp.petsc.mumps_c.SchurSeries`,
    DMUMPS through its C interface: PETSc's interface analyses again at each σ (a quarter of
    each complement's time, docs/benchmarks-notes.md), and its refactorisation returned a wrong Schur complement on 2 ranks); block
    low-rank (:data:`SCHUR_LOW_RANK`) unless ``-meicp_schur_mat_mumps_*`` say otherwise.  Where
    no DMUMPS of a known version loads (:func:`~meicp.petsc.mumps_c.load` checks the version),
    one PETSc factorisation per σ.  The result has
    ``destroy()`` (collective) and is a context manager."""
    if mumps_c.load("d")[0] is None:
        return _SchurByPetsc(comm, H0, H1, rows, H2)
    icntl, cntl = mumps_controls(SCHUR + "mat_mumps_")
    return mumps_c.SchurSeries(mpi_comm(comm), H0, H1, rows, defaults={35: 2}, icntl=icntl,
                               cntl={7: SCHUR_LOW_RANK, **cntl}, H2=H2)


def schur_factor(comm, H: sp.spmatrix, rows: np.ndarray, *, prefix: str, what: str) -> "mumps_c.SchurSeries":
    """One DMUMPS LDLᵀ factorisation of the symmetric ``H`` (SciPy, every rank holds it) with
    the dense Schur complement onto ``rows``: the returned, factored
    :class:`~meicp.petsc.mumps_c.SchurSeries` gives it (``schur_complement()``, every rank) and
    solves with the interior block (``solve(rhs)``, on rank 0) — one factor for both, where
    PETSc's ``MatSolve`` on a factor with a Schur set solves the Schur-expanded system instead.
    Controls: ``-<prefix>mat_mumps_icntl_<k>`` / ``cntl_<k>`` (full rank unless they say
    otherwise).  A :class:`MumpsError` (a
    ProblemError) when no usable DMUMPS loads or MUMPS fails.  Collective; call ``destroy()``."""
    entry, why = mumps_c.load("d")
    if entry is None:
        raise mumps_c.MumpsError(why)
    icntl, cntl = mumps_controls(prefix + "mat_mumps_")
    series = mumps_c.SchurSeries(mpi_comm(comm), H, None, rows, icntl=icntl, cntl=cntl, what=what,
                                 option=f"-{prefix}mat_mumps_")
    try:
        series.factor(0.0)
    except Exception:
        series.destroy()
        raise
    return series


class _SchurByPetsc:
    interior = False  # no interior solves or inertias (mumps_c.SchurSeries has them)

    def __init__(self, comm, H0, H1, rows, H2=None):
        self.comm, self.H0, self.H1, self.rows = comm, sp.csr_matrix(H0), sp.csr_matrix(H1), rows
        self.H2 = None if H2 is None else sp.csr_matrix(H2)

    def __call__(self, sigma: float) -> np.ndarray:
        values = self.H0.data + sigma * self.H1.data
        if self.H2 is not None:
            values = values + (sigma * sigma) * self.H2.data
        H = sp.csr_matrix((values, self.H0.indices, self.H0.indptr), shape=self.H0.shape)
        return dense_schur(self.comm, H, self.rows, symmetric=True)

    def destroy(self) -> None:
        pass

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        pass


class MumpsFactor:
    """One MUMPS factorisation of a SciPy matrix every rank holds; :meth:`solve` takes a
    dense vector or block (every rank the whole of it) and returns the whole solution on
    every rank.  A context manager (collective ``destroy`` on leaving)::

        with MumpsFactor(comm, H_FF, symmetric=True) as solve:
            X = solve(B)
    """

    def __init__(self, comm, H: sp.spmatrix, *, symmetric: bool, options: dict | None = None):
        PETSc = import_petsc()
        self.A = _distribute(comm, H)
        self.pcomm = self.A.getComm()
        self.ksp = PETSc.KSP().create(comm=self.pcomm)
        self.ksp.setOperators(self.A)
        defaults = {"ksp_type": "preonly", "pc_type": "cholesky" if symmetric else "lu", **_MUMPS}
        with OptionsScope(SCHUR, defaults, options) as scope:
            scope.configure(self.ksp)
            require_mumps_factor(self.ksp, SCHUR, ("cholesky", "lu"), "the condensation onto the contact DOFs")
            self.ksp.setUp()
        self.lo, self.hi = self.A.getOwnershipRange()
        self.n = self.A.getSize()[0]

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        PETSc = import_petsc()
        vector = rhs.ndim == 1
        Bl = np.asfortranarray(rhs.reshape(self.n, -1)[self.lo:self.hi], dtype=float)
        k = Bl.shape[1]
        nloc = self.hi - self.lo
        B = PETSc.Mat().createDense(((nloc, self.n), (PETSc.DECIDE, k)), array=Bl, comm=self.pcomm)
        X = PETSc.Mat().createDense(((nloc, self.n), (PETSc.DECIDE, k)), comm=self.pcomm)
        X.setUp()
        try:
            self.ksp.getPC().getFactorMatrix().matSolve(B, X)
            local = X.getDenseArray().copy()
        finally:
            B.destroy()
            X.destroy()
        if self.pcomm.getSize() > 1:
            local = np.vstack(self.pcomm.tompi4py().allgather(local))
        return local[:, 0] if vector else local

    __call__ = solve

    def inertia(self) -> tuple[int, int, int]:
        """``(negative, zero, positive)`` pivots of the factor (Sylvester: the factored matrix's
        eigenvalue counts); a factor made with :data:`~meicp.petsc.inertia.INERTIA_OPTIONS`."""
        return tuple(int(c) for c in self.ksp.getPC().getFactorMatrix().getInertia())

    def __enter__(self):
        return self.solve

    def __exit__(self, *exc) -> None:
        self.destroy()

    def destroy(self) -> None:
        if self.ksp is not None:
            self.ksp.destroy()
            self.A.destroy()
            self.ksp = self.A = None


def mumps_factor(comm, *, symmetric: bool = True, options: dict | None = None):
    """A factor for :func:`meicp.contact.condensation.condense`: ``factor(H)`` is a
    :class:`MumpsFactor` of H (a context manager giving the solve)."""
    return lambda H: MumpsFactor(comm, H, symmetric=symmetric, options=options)
