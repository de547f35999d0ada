"""Distributed assembly of the lattice's K and M as PETSc AIJ matrices, and
:func:`assemble`, which chooses between it and the serial SciPy assembly.

The serial assembly (:mod:`meicp.lattice.assembly`) knows nothing of PETSc; this module
builds on it, one way (as DOLFINx's ``fem/petsc.py`` builds on ``fem/assemble.py``).

Layout: the ranks split the lattice into contiguous bands of node rows
(:meth:`LatticeModel.row_band`); since nodes are numbered row by row, a band's DOFs are a
contiguous range of the natural numbering, so the PETSc ownership ranges *are* the natural
numbering and nothing is permuted on the way in or out.  Each rank computes only its own
rows, in chunks, with the vectorised stencil of :mod:`meicp.lattice.assembly`; the
matrix is preallocated exactly from the stencil (diagonal/off-diagonal counts per row)
and each chunk is inserted with one ``MatSetValues`` per row from C
(``setValuesIJV`` with a row map), so peak memory is the matrix plus one chunk.

All functions taking ``comm`` or a matrix are collective on that communicator.  The caller
owns every returned PETSc object and destroys it (collectively) when done.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..core.comm import mpi_comm
from ..core.errors import ProblemError
from ..lattice.assembly import (as_model, assemble_scipy, chunks, damping_block, damping_matrix_scipy, index_dtype,
                                mass_diagonal, neighbour_exists, stiffness_block)
from ..lattice.model import SLOTS, LatticeModel
from . import import_petsc
from .comm import to_petsc_comm


def assemble(scene, comm=None):
    """``(K, M)`` of a scene in natural DOF numbering (DOFs ``2n``, ``2n+1`` of node ``n = j·nx + i``).

    ``comm=None``: SciPy CSR matrices (canonical: sorted, no duplicates).  ``comm`` an mpi4py
    or PETSc communicator: PETSc AIJ matrices (MPIAIJ on several ranks) distributed by
    contiguous bands of node rows, each rank building only its own rows; this is collective
    on ``comm``, and the caller owns the matrices and destroys them (``K.destroy()``,
    ``M.destroy()``, collective) when done.  Every node of the lattice has its 2 DOFs,
    Dirichlet ones included (see ``LatticeModel.constrained_dofs``); frictional interfaces
    have no bonds.  ``scene``: a :class:`~meicp.scene.Scene` or a :class:`LatticeModel`
    (:func:`meicp.assemble` also reads a scene file).
    """
    model = as_model(scene)
    if comm is None:
        return assemble_scipy(model)
    return assemble_petsc(model, comm)


def assemble_damping(scene, comm=None):
    """The damping matrix C of a scene (docs/damping.md), in natural DOF numbering: assembled
    exactly like K with each bond's viscosity η in place of its stiffness k (a bond joining
    two materials: the mean, or its bonded interface's own ``viscosity``), plus
    ``[damping] mass`` · M; K's sparsity pattern, all zero without damping.  ``comm`` as for
    :func:`assemble`: None gives SciPy CSR, a communicator a PETSc AIJ matrix on K's row
    bands (collective; the caller destroys it)."""
    model = as_model(scene)
    if comm is None:
        return damping_matrix_scipy(model)
    return _stencil_mat(model, to_petsc_comm(comm), damping_block)


class LatticeMatrices:
    """K and M of one lattice, assembled once for one analysis and owned by it.

    ``LatticeMatrices(model, comm)``: SciPy CSR when ``comm`` is serial (None or one rank),
    PETSc AIJ on ``comm``'s row bands otherwise (:func:`assemble`).  Every step of the
    analysis reads these (the static equilibrium, each contact state's pencil, the
    condensation, the friction range, flutter), so the lattice is assembled once per run (and,
    distributed, once more serially on every rank only where a consumer reads it whole).
    They are assembled at their first use (:meth:`assemble`, or reading ``K`` or ``M``:
    collective then), so that a consumer reading the lattice whole before any pencil exists
    (the static equilibrium, on several ranks) does not hold its serial copy beside the
    distributed one.  :meth:`whole` gives SciPy K, M on every rank to the consumers that need
    them whole; :meth:`destroy` (or leaving a ``with`` block) frees the PETSc matrices,
    collectively."""

    def __init__(self, model: LatticeModel, comm=None):
        self.model = model
        self.comm = mpi_comm(comm)
        self._K = self._M = None
        self._destroyed = False

    @classmethod
    def wrapping(cls, model: LatticeModel, K, M, comm=None) -> "LatticeMatrices":
        """K and M the caller assembled already (e.g. a benchmark that times the assembly on
        its own; SciPy, or PETSc on ``comm``), destroyed by :meth:`destroy` or by the caller."""
        obj = cls(model, comm)
        obj._K, obj._M = K, M
        return obj

    def assemble(self) -> "LatticeMatrices":
        """K and M assembled, if they are not yet (collective on ``comm`` when distributed)."""
        if self._destroyed:
            raise RuntimeError("the lattice's K and M were destroyed")
        if self._K is None:
            self._K, self._M = assemble(self.model, self.comm)
        return self

    @property
    def K(self):
        return self.assemble()._K

    @property
    def M(self):
        return self.assemble()._M

    @property
    def distributed(self) -> bool:
        return self.comm is not None

    def whole(self) -> tuple[sp.csr_matrix, sp.csr_matrix]:
        """``(K, M)`` as SciPy CSR on every rank, for the consumers that read the lattice whole
        (the static equilibrium, the condensation): the matrices themselves when serial; when
        distributed, the serial assembly on every rank, as those consumers always had (cheaper
        in time and memory than gathering the PETSc rows: docs/benchmarks-notes.md).  Not
        kept: the caller drops them when done."""
        if not self.distributed:
            return self.K, self.M
        return assemble_scipy(self.model)

    def damping(self) -> sp.csr_matrix:
        """C (:func:`assemble_damping`) as SciPy CSR on every rank, for the damped paths, which
        are dense and small (docs/damping.md); assembled at each call, not kept."""
        return damping_matrix_scipy(self.model)

    def damping_in_layout(self):
        """C in K's layout: SciPy CSR when serial, PETSc AIJ on the row bands when distributed
        (the damped flutter search at scale); assembled at each call, the caller destroys a
        PETSc one.  Collective when distributed."""
        return assemble_damping(self.model, self.comm)

    def destroy(self) -> None:
        """Free the PETSc matrices (collective); nothing to do for SciPy ones."""
        if self.distributed:
            for A in (self._K, self._M):
                if A is not None:
                    A.destroy()
        self._K = self._M = None
        self._destroyed = True

    def __enter__(self) -> "LatticeMatrices":
        return self

    def __exit__(self, *exc) -> None:
        self.destroy()


def row_band(model: LatticeModel, comm) -> tuple[int, int]:
    """Node rows ``[j0, j1)`` owned by this rank of ``comm``."""
    pcomm = to_petsc_comm(comm)
    return model.row_band(pcomm.getRank(), pcomm.getSize())


def preallocation(model: LatticeModel, j0: int, j1: int) -> tuple[np.ndarray, np.ndarray]:
    """Exact (diagonal-block, off-diagonal-block) nonzeros per DOF row of rows ``[j0, j1)``."""
    PETSc = import_petsc()
    d_nnz = np.empty(2 * (j1 - j0) * model.nx, dtype=PETSc.IntType)
    o_nnz = np.empty_like(d_nnz)
    dj = np.array([s[1] for s in SLOTS])
    for a, b in chunks(model, j0, j1):
        ex = neighbour_exists(model, a, b)
        j = np.repeat(np.arange(a, b), model.nx)
        other_row = j[:, None] + dj[None, :]
        inside = (other_row >= j0) & (other_row < j1)
        r0 = 2 * (a - j0) * model.nx
        r1 = 2 * (b - j0) * model.nx
        d_nnz[r0:r1] = np.repeat(2 * (ex & inside).sum(axis=1), 2)
        o_nnz[r0:r1] = np.repeat(2 * (ex & ~inside).sum(axis=1), 2)
    return d_nnz, o_nnz


def assemble_petsc(model: LatticeModel, comm, chunk_nodes: int | None = None):
    """``(K, M)`` as PETSc AIJ matrices on ``comm`` in natural numbering (collective).

    Rank r owns the DOFs of node rows ``model.row_band(r, size)``.  K is flagged symmetric.
    Raises :class:`ProblemError` when the lattice needs 64-bit indices and this PETSc has
    32-bit ones.
    """
    PETSc = import_petsc()
    pcomm = to_petsc_comm(comm)
    K = _stencil_mat(model, pcomm, stiffness_block, chunk_nodes)
    j0, j1 = model.row_band(pcomm.getRank(), pcomm.getSize())
    r0, r1 = model.dof_range(j0, j1)
    n, m = model.n_dofs, r1 - r0
    idx = PETSc.IntType

    M = PETSc.Mat().createAIJ(size=((m, n), (m, n)), nnz=(1, 0), comm=pcomm)
    M.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, True)
    M.setOption(PETSc.Mat.Option.NO_OFF_PROC_ENTRIES, True)
    rows = np.arange(r0, r1, dtype=idx)
    M.setValuesIJV(np.arange(m + 1, dtype=idx), rows, mass_diagonal(model, j0, j1), rowmap=rows)
    M.assemble()
    M.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    return K, M


def _stencil_mat(model: LatticeModel, pcomm, block, chunk_nodes: int | None = None):
    """The symmetric matrix whose rows ``block(model, a, b, index dtype)`` gives (K's
    stencil), as a PETSc AIJ matrix on ``pcomm``'s row bands, preallocated exactly."""
    PETSc = import_petsc()
    idx = PETSc.IntType
    if np.dtype(index_dtype(model)).itemsize > np.dtype(idx).itemsize:
        raise ProblemError(f"the lattice has {model.n_dofs} DOFs: too many for this PETSc build "
                           f"({np.dtype(idx).itemsize * 8}-bit indices)")
    j0, j1 = model.row_band(pcomm.getRank(), pcomm.getSize())
    r0, r1 = model.dof_range(j0, j1)
    n, m = model.n_dofs, r1 - r0
    d_nnz, o_nnz = preallocation(model, j0, j1)
    K = PETSc.Mat().createAIJ(size=((m, n), (m, n)), nnz=(d_nnz, o_nnz), comm=pcomm)
    del d_nnz, o_nnz
    K.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, True)
    K.setOption(PETSc.Mat.Option.NO_OFF_PROC_ENTRIES, True)
    for a, b in chunks(model, j0, j1, chunk_nodes):
        ra, rb = model.dof_range(a, b)
        indptr, indices, data = block(model, a, b, idx)
        K.setValuesIJV(indptr, indices, data, rowmap=np.arange(ra, rb, dtype=idx))
        del indptr, indices, data
    K.assemble()
    K.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    return K


def principal_submatrix(A, keep):
    """``A[keep, keep]`` as a new distributed matrix (collective).

    ``keep``: sorted global indices (every rank may pass the whole array; each uses the part
    in its ownership range, which it then owns in the result).  E.g. the free DOFs of a
    lattice (``LatticeModel.free_dofs()``) to remove Dirichlet DOFs.  Caller destroys it.
    """
    PETSc = import_petsc()
    r0, r1 = A.getOwnershipRange()
    keep = np.asarray(keep)
    local = keep[(keep >= r0) & (keep < r1)].astype(PETSc.IntType)
    iset = PETSc.IS().createGeneral(local, comm=A.getComm())
    try:
        return A.createSubMatrix(iset, iset)
    finally:
        iset.destroy()

