"""Stiffness K and lumped mass M of the lattice, in natural DOF numbering.

The rows of K are built directly in CSR form, a chunk of node rows at a time, from the
9-point stencil of the lattice (every node is bonded to at most its 8 neighbours): for a
node with ``b`` bonds each of its 2 DOF rows holds ``2(b + 1)`` entries, in increasing
column order, so row lengths are known before any value is computed and the CSR arrays
are allocated once, exactly, and filled in place.  No COO, no per-entry Python loop, and
the temporaries are bounded by the chunk size (about 2^16 nodes), not by the lattice.

Element matrix of a bond of stiffness ``k`` and unit direction ``e`` (docs/design.md §5, errata
of seed 000 in §12 applied): ``k [[A, −A], [−A, A]]`` with ``A = e eᵀ``, each bond with its own
direction.  Mass: ``ρ a³`` on both DOFs of every node.

Damping C (docs/damping.md) is assembled exactly like K with each bond's viscosity η in
place of k (:func:`damping_block`, :func:`damping_matrix_scipy`), plus ``α·M`` on the
diagonal for ``[damping] mass = α``; it has K's sparsity pattern (explicit zeros where η = 0).

Serial and plain SciPy: :func:`assemble_scipy` gives CSR matrices.  The distributed PETSc
assembly (:mod:`meicp.petsc.assembly`) builds its rows from the same blocks
(:func:`stiffness_block`, :func:`mass_diagonal`) and hosts :func:`meicp.assemble`, which picks
one or the other by communicator; nothing here knows of PETSc.
(An independent, bond-by-bond reference for arbitrary node positions is the tests' own:
``tests/helpers.py``.)
"""

from __future__ import annotations

import functools

import numpy as np
import scipy.sparse as sp

from ..core.errors import ProblemError
from ..scene import Scene
from .model import SELF, SLOTS, LatticeModel

#: nodes per chunk, at most: bounds the temporaries (about 700 bytes per node of a chunk)
CHUNK_NODES = 1 << 16
#: ... and at least, so that small problems do not pay per-chunk overhead many times
MIN_CHUNK_NODES = 1 << 10


def as_model(scene) -> LatticeModel:
    """A :class:`LatticeModel` from a model or a :class:`~meicp.scene.Scene` (a scene file is
    read by :func:`meicp.load_scene` first)."""
    if isinstance(scene, LatticeModel):
        return scene
    if not isinstance(scene, Scene):
        raise ProblemError(f"scene must be a Scene or a LatticeModel, got {type(scene).__name__} "
                           "(read a scene file with meicp.load_scene)")
    return LatticeModel(scene)


def index_dtype(model: LatticeModel):
    """int32 while every index and the nnz bound fit, else int64."""
    return np.int32 if 18 * model.n_dofs < 2**31 - 1 else np.int64


def chunks(model: LatticeModel, j0: int, j1: int, chunk_nodes: int | None = None):
    """Consecutive row ranges ``[a, b)`` covering ``[j0, j1)`` of about ``chunk_nodes`` nodes
    (default: an eighth of the band, between 2^10 and 2^16 nodes, so that the temporaries
    stay a small fraction of the matrix whatever its size)."""
    if chunk_nodes is None:
        chunk_nodes = min(CHUNK_NODES, max(MIN_CHUNK_NODES, (j1 - j0) * model.nx // 8))
    step = max(1, chunk_nodes // model.nx)
    for a in range(j0, j1, step):
        yield a, min(a + step, j1)


def _slot_offsets(model: LatticeModel) -> np.ndarray:
    return np.array([di + dj * model.nx for di, dj in SLOTS], dtype=np.int64)


def neighbour_exists(model: LatticeModel, j0: int, j1: int) -> np.ndarray:
    """(n, 9) bool: which neighbours of the nodes of rows ``[j0, j1)`` are bonded to them
    (the node itself counts as present).  Geometry and cuts only, no materials."""
    nx, rows = model.nx, j1 - j0
    i = np.arange(nx)
    j = np.arange(j0, j1)
    cut = np.concatenate([[False], model.cut_above, [False]])
    out = np.empty((rows, nx, 9), dtype=bool)
    for s, (di, dj) in enumerate(SLOTS):
        col_ok = (i + di >= 0) & (i + di < nx)
        row_ok = (j + dj >= 0) & (j + dj < model.ny)
        if dj == 1:
            row_ok &= ~cut[j + 1]
        elif dj == -1:
            row_ok &= ~cut[j]
        out[:, :, s] = row_ok[:, None] & col_ok[None, :]
    return out.reshape(rows * nx, 9)


def row_lengths(model: LatticeModel, j0: int, j1: int) -> np.ndarray:
    """Entries in each DOF row of rows ``[j0, j1)`` (2 per present slot), shape (2n,)."""
    per_node = 2 * neighbour_exists(model, j0, j1).sum(axis=1)
    return np.repeat(per_node, 2)


def stiffness_block(model: LatticeModel, j0: int, j1: int, dtype=np.int32):
    """The DOF rows of K for node rows ``[j0, j1)`` as CSR pieces
    ``(indptr (starting at 0), global column indices, values)``, columns sorted in each row."""
    kk = model.neighbour_stiffness(j0, j1)  # (m, 9), zero where no bond
    return _bond_block(model, j0, j1, dtype, kk, kk > 0)


def damping_block(model: LatticeModel, j0: int, j1: int, dtype=np.int32, *, table: np.ndarray | None = None,
                  mass: float | None = None):
    """The DOF rows of C for node rows ``[j0, j1)``, as :func:`stiffness_block` gives K's: the
    same entries (an explicit 0 where a bond has no viscosity), each bond's η in place of its
    k, and ``α ρ a³`` added on the diagonal (``[damping] mass = α``).  ``table`` and ``mass``:
    another per-pair coefficient in place of the viscosities and another α."""
    present = model.neighbour_stiffness(j0, j1) > 0
    eta = model.neighbour_stiffness(j0, j1, model.cmat if table is None else table)
    alpha = model.damping_mass if mass is None else mass
    diagonal = alpha * model.mass(j0, j1) if alpha else None
    return _bond_block(model, j0, j1, dtype, eta, present, diagonal)


def _bond_block(model: LatticeModel, j0: int, j1: int, dtype, kk: np.ndarray, present: np.ndarray,
                diagonal: np.ndarray | None = None):
    """CSR rows of ``Σ_bonds c [[A, −A], [−A, A]]`` with the coefficient ``c`` of each bond in
    ``kk`` (m, 9), entries where ``present`` (m, 9), plus ``diagonal`` (per node) on both DOFs."""
    m = kk.shape[0]
    A = model.slot_matrices()  # (9, 2, 2), zero for SELF
    present = present.copy()
    present[:, SELF] = True
    vals = np.multiply(kk[:, None, :, None], -A.transpose(1, 0, 2)[None])  # (m, c, s, d)
    vals[:, :, SELF, :] = (kk @ A.reshape(9, 4)).reshape(m, 2, 2)
    if diagonal is not None:
        vals[:, 0, SELF, 0] += diagonal
        vals[:, 1, SELF, 1] += diagonal
    nodes = np.arange(j0 * model.nx, j1 * model.nx, dtype=np.int64)
    cols = 2 * (nodes[:, None, None] + _slot_offsets(model)[None, :, None]) + np.arange(2)[None, None, :]
    cols = cols.astype(dtype, copy=False)  # (m, s, d); masked-out entries may be out of range
    # select whole (x, y) column pairs: a (m, 2, 9) mask over 16-byte blocks
    mask = np.broadcast_to(present[:, None, :], (m, 2, 9))
    data = vals[mask].reshape(-1)
    indices = np.broadcast_to(cols[:, None, :, :], vals.shape)[mask].reshape(-1)
    lengths = np.repeat(2 * present.sum(axis=1), 2)
    indptr = np.zeros(2 * m + 1, dtype=dtype)
    np.cumsum(lengths, out=indptr[1:])
    return indptr, indices, data


def assemble_scipy(model: LatticeModel, chunk_nodes: int | None = None):
    """``(K, M)`` as SciPy CSR, built chunk by chunk into exactly allocated arrays."""
    return _stencil_csr(model, stiffness_block, chunk_nodes), mass_matrix_scipy(model)


def damping_matrix_scipy(model: LatticeModel, chunk_nodes: int | None = None, *, table: np.ndarray | None = None,
                         mass: float | None = None) -> sp.csr_matrix:
    """C as SciPy CSR (K's pattern; all zero for a scene without damping); ``table``, ``mass``
    as :func:`damping_block`'s."""
    if table is None and mass is None:
        return _stencil_csr(model, damping_block, chunk_nodes)
    return _stencil_csr(model, functools.partial(damping_block, table=table, mass=mass), chunk_nodes)


def _stencil_csr(model: LatticeModel, block, chunk_nodes: int | None) -> sp.csr_matrix:
    """The matrix whose rows ``block(model, a, b, index dtype)`` gives, chunk by chunk."""
    n = model.n_dofs
    idx = index_dtype(model)
    indptr = np.zeros(n + 1, dtype=np.int64 if idx == np.int64 else np.int32)
    for a, b in chunks(model, 0, model.ny, chunk_nodes):
        ra, rb = model.dof_range(a, b)
        indptr[ra + 1:rb + 1] = row_lengths(model, a, b)
    np.cumsum(indptr, out=indptr)
    nnz = int(indptr[-1])
    indices = np.empty(nnz, dtype=idx)
    data = np.empty(nnz)
    for a, b in chunks(model, 0, model.ny, chunk_nodes):
        ra, _ = model.dof_range(a, b)
        bp, bi, bv = block(model, a, b, idx)
        start = int(indptr[ra])
        indices[start:start + bi.size] = bi
        data[start:start + bv.size] = bv
        del bp, bi, bv
    K = sp.csr_matrix((data, indices, indptr), shape=(n, n), copy=False)
    K.has_sorted_indices = True
    K.has_canonical_format = True
    return K


def mass_diagonal(model: LatticeModel, j0: int = 0, j1: int | None = None) -> np.ndarray:
    """Diagonal of M for the DOFs of rows ``[j0, j1)``: ``ρ a³`` twice per node."""
    return np.repeat(model.mass(j0, j1), 2)


def mass_matrix_scipy(model: LatticeModel) -> sp.csr_matrix:
    n = model.n_dofs
    idx = np.int32 if n < 2**31 - 1 else np.int64
    return sp.csr_matrix((mass_diagonal(model), np.arange(n, dtype=idx), np.arange(n + 1, dtype=idx)),
                         shape=(n, n), copy=False)
