"""The layered lattice of docs/design.md §5 as plain arrays: geometry, materials, bonds' stiffness
rules and boundary DOFs.  No PETSc here.

Nodes ``(i, j)``, ``i = 0..nx-1`` left to right, ``j = 0..ny-1`` bottom to top, node number
``n = j·nx + i``, DOFs ``2n`` (x) and ``2n+1`` (y): the *natural numbering* used at every API
boundary.  Reference position ``(a·i + shear·a·j, a·j)``.

Materials are numbered layers first (bottom to top), then embedded bands in scene order.
A bond joining two nodes of one material has that material's stiffness; a bond joining two
materials has the pair's interface stiffness (``LatticeModel.kmat``).  Its dashpot (damping,
docs/damping.md) follows the same rule with the viscosities (``LatticeModel.cmat``: the mean
of the two materials', or a bonded interface's own ``viscosity``).  Bonds crossing a
frictional interface do not exist.  Every quantity is computed for the nodes asked for
(a row band, a chunk), never for the whole lattice unless asked: a rank holding rows
``j0..j1`` touches only those rows and their two neighbour rows.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..core.errors import ProblemError
from ..scene import Scene

#: the 8 neighbour offsets (di, dj) plus the node itself, in increasing natural column order
SLOTS = ((-1, -1), (0, -1), (1, -1), (-1, 0), (0, 0), (1, 0), (-1, 1), (0, 1), (1, 1))
SELF = 4
#: the 4 bond kinds, each stored once from its lower-numbered end ``(i, j)`` (HDF5 ``bonds/kind``)
BOND_KINDS = ("horizontal", "vertical", "diagonal", "antidiagonal")
#: for each kind: offset of the first end from (i, j) and of the second end from (i, j)
BOND_ENDS = (((0, 0), (1, 0)), ((0, 0), (0, 1)), ((0, 0), (1, 1)), ((1, 0), (0, 1)))


@dataclass(frozen=True)
class Material:
    name: str
    stiffness: float
    density: float
    kind: str  # "layer" | "embedded"
    host: int | None = None  # the host layer of an embedded band
    viscosity: float = 0.0


@dataclass(frozen=True)
class Region:
    """A rectangle of rows ``j0..j1-1`` and columns ``i0..i1-1`` made of material ``material``."""

    material: int
    j0: int
    j1: int
    i0: int
    i1: int


class LatticeModel:
    """Everything the assembly and the output need, derived once from a :class:`Scene`.

    Attributes: ``nx, ny, spacing, shear``; ``materials`` (tuple of :class:`Material`);
    ``kmat`` (n_mat × n_mat bond stiffness, diagonal = own stiffness); ``cmat`` (the same for
    the bonds' viscosity) and ``damping_mass`` (α of ``[damping] mass``); ``row_material``
    (layer index of each row); ``layer_rows`` ((first, end) rows of each layer);
    ``regions`` (embedded rectangles); ``cut_above`` (bool per row: no bonds between row j
    and j+1, a frictional interface); ``boundary``; ``scene``.
    """

    def __init__(self, scene):
        if not isinstance(scene, Scene):
            raise ProblemError(f"expected a Scene, got {type(scene).__name__}")
        self.scene = scene
        self.nx = scene.nx
        self.ny = scene.ny
        self.spacing = scene.lattice.spacing
        self.shear = scene.lattice.shear
        self.boundary = scene.boundary
        layers = scene.layers
        mats = [Material(layer.name, layer.stiffness, layer.density, "layer", None, layer.viscosity or 0.0)
                for layer in layers]
        mats += [Material(e.name, e.stiffness, e.density, "embedded", scene.layer_index(e.host), e.viscosity or 0.0)
                 for e in scene.embedded]
        self.materials = tuple(mats)
        nm = len(mats)
        k = np.array([m.stiffness for m in mats])
        kmat = np.empty((nm, nm))
        for a in range(nm):
            for b in range(nm):
                kmat[a, b] = k[a] if a == b else scene.lattice.pair_stiffness(k[a], k[b])
        for itf in scene.interfaces:
            if itf.bonded:
                kmat[itf.index, itf.index + 1] = kmat[itf.index + 1, itf.index] = itf.stiffness
        starts = np.cumsum([0] + [layer.rows for layer in layers])
        self.layer_rows = np.stack([starts[:-1], starts[1:]], axis=1)
        regions = []
        for e_id, e in enumerate(scene.embedded, start=len(layers)):
            h = scene.layer_index(e.host)
            kmat[e_id, h] = kmat[h, e_id] = e.interface_stiffness
            j0 = int(starts[h]) + e.row
            regions.append(Region(e_id, j0, j0 + e.rows, e.column, e.column + e.columns))
        self.kmat = kmat
        self.kmat.setflags(write=False)
        self.cmat = _viscosity_table(scene, mats)
        self.damping_mass = scene.damping.mass if scene.damping is not None else 0.0
        self.regions = tuple(regions)
        self.row_material = np.repeat(np.arange(len(layers)), [layer.rows for layer in layers])
        self.cut_above = np.zeros(self.ny, dtype=bool)
        for itf in scene.interfaces:
            if not itf.bonded:
                self.cut_above[starts[itf.index + 1] - 1] = True
        self.mass_per_material = np.array([m.density for m in mats]) * self.spacing ** 3

    @property
    def damped(self) -> bool:
        """Whether C is not zero (:attr:`meicp.scene.Scene.damped`)."""
        return self.scene.damped

    # ------------------------------------------------------------------ sizes, numbering
    @property
    def n_nodes(self) -> int:
        return self.scene.n_nodes

    @property
    def n_dofs(self) -> int:
        return self.scene.n_dofs

    def row_band(self, rank: int, size: int) -> tuple[int, int]:
        """Rows ``[j0, j1)`` of ``rank`` when ``size`` ranks split the rows contiguously and
        as evenly as possible (the first ``ny % size`` ranks get one row more)."""
        base, extra = divmod(self.ny, size)
        j0 = rank * base + min(rank, extra)
        return j0, j0 + base + (1 if rank < extra else 0)

    def node_range(self, j0: int, j1: int) -> tuple[int, int]:
        return j0 * self.nx, j1 * self.nx

    def dof_range(self, j0: int, j1: int) -> tuple[int, int]:
        return 2 * j0 * self.nx, 2 * j1 * self.nx

    # ------------------------------------------------------------------ geometry
    def positions(self, j0: int = 0, j1: int | None = None) -> np.ndarray:
        """Reference positions ``(n, 2)`` of the nodes of rows ``[j0, j1)``."""
        j1 = self.ny if j1 is None else j1
        j, i = np.divmod(np.arange(j0 * self.nx, j1 * self.nx), self.nx)
        a = self.spacing
        return np.stack([a * i + self.shear * a * j, a * j], axis=1).astype(float)

    def bond_vector(self, di: int, dj: int) -> np.ndarray:
        """Reference vector of a bond from ``(i, j)`` to ``(i+di, j+dj)`` (the same for every
        node: the reference configuration is an affine image of the grid)."""
        a = self.spacing
        return np.array([a * (di + self.shear * dj), a * dj], dtype=float)

    def bond_matrix(self, di: int, dj: int) -> np.ndarray:
        """``A = e eᵀ`` of the bond direction ``e`` (docs/design.md §5)."""
        d = self.bond_vector(di, dj)
        e = d / np.linalg.norm(d)
        return np.outer(e, e)

    def slot_matrices(self) -> np.ndarray:
        """``A`` of each of the 9 :data:`SLOTS` (zero for the node itself), shape (9, 2, 2)."""
        out = np.zeros((9, 2, 2))
        for s, (di, dj) in enumerate(SLOTS):
            if s != SELF:
                out[s] = self.bond_matrix(di, dj)
        return out

    # ------------------------------------------------------------------ materials
    def material_grid(self, j0: int, j1: int, pad: int = 0) -> np.ndarray:
        """Material index of rows ``[j0-pad, j1+pad)`` × columns ``[-pad, nx+pad)`` as a 2-D
        int array, ``-1`` where the node is outside the lattice."""
        rows = np.arange(j0 - pad, j1 + pad)
        out = np.full((rows.size, self.nx + 2 * pad), -1, dtype=np.int32)
        inside = (rows >= 0) & (rows < self.ny)
        out[inside, pad:pad + self.nx] = self.row_material[rows[inside]][:, None]
        for r in self.regions:
            a, b = max(r.j0, j0 - pad), min(r.j1, j1 + pad)
            if a < b:
                out[a - (j0 - pad):b - (j0 - pad), pad + r.i0:pad + r.i1] = r.material
        return out

    def material(self, j0: int = 0, j1: int | None = None) -> np.ndarray:
        """Material index of each node of rows ``[j0, j1)``, natural order."""
        j1 = self.ny if j1 is None else j1
        return self.material_grid(j0, j1).ravel()

    def mass(self, j0: int = 0, j1: int | None = None) -> np.ndarray:
        """Lumped mass ``ρ a³`` of each node of rows ``[j0, j1)``."""
        return self.mass_per_material[self.material(j0, j1)]

    def total_mass(self) -> float:
        """``Σ ρ a³`` over all nodes, from the layer and band sizes (no per-node arrays)."""
        m = sum(self.mass_per_material[k] * (b - a) * self.nx
                for k, (a, b) in enumerate(self.layer_rows))
        for r in self.regions:
            host = self.materials[r.material].host
            m += (self.mass_per_material[r.material] - self.mass_per_material[host]) \
                * (r.j1 - r.j0) * (r.i1 - r.i0)
        return float(m)

    # ------------------------------------------------------------------ boundary
    def side_nodes(self, side: str) -> np.ndarray:
        nx, ny = self.nx, self.ny
        if side == "bottom":
            return np.arange(nx)
        if side == "top":
            return np.arange((ny - 1) * nx, ny * nx)
        if side == "left":
            return np.arange(ny) * nx
        if side == "right":
            return np.arange(ny) * nx + nx - 1
        raise ValueError(side)

    def fixed_mask(self, j0: int = 0, j1: int | None = None) -> np.ndarray:
        """``(n, 2)`` bool: which components of the nodes of rows ``[j0, j1)`` are prescribed
        (Dirichlet) by ``[boundary]``.  A corner takes the union of its two sides.
        ``bottom = "contact"`` prescribes nothing here (the contact module handles it)."""
        j1 = self.ny if j1 is None else j1
        j, i = np.divmod(np.arange(j0 * self.nx, j1 * self.nx), self.nx)
        out = np.zeros((j.size, 2), dtype=bool)
        for side, on in (("bottom", j == 0), ("top", j == self.ny - 1),
                         ("left", i == 0), ("right", i == self.nx - 1)):
            fx, fy = self.boundary.fixed_components(side)
            out[on, 0] |= fx
            out[on, 1] |= fy
        return out

    def constrained_dofs(self) -> np.ndarray:
        """Sorted natural DOF numbers prescribed by the boundary (Dirichlet)."""
        nodes = np.concatenate([self.side_nodes(s) for s in ("bottom", "top", "left", "right")
                                if any(self.boundary.fixed_components(s))] or [np.zeros(0, int)])
        nodes = np.unique(nodes)
        mask = np.zeros((nodes.size, 2), dtype=bool)
        i, j = nodes % self.nx, nodes // self.nx
        for side, on in (("bottom", j == 0), ("top", j == self.ny - 1),
                         ("left", i == 0), ("right", i == self.nx - 1)):
            fx, fy = self.boundary.fixed_components(side)
            mask[on, 0] |= fx
            mask[on, 1] |= fy
        dofs = (2 * nodes[:, None] + np.array([0, 1]))[mask]
        return np.sort(dofs).astype(np.int64)

    def free_dofs(self) -> np.ndarray:
        """Sorted natural DOF numbers not prescribed by the boundary."""
        keep = np.ones(self.n_dofs, dtype=bool)
        keep[self.constrained_dofs()] = False
        return np.flatnonzero(keep)

    def contact_nodes(self) -> np.ndarray:
        """Bottom-row nodes on the rigid base (empty unless ``bottom = "contact"``), left to right."""
        return np.arange(self.nx) if self.boundary.bottom == "contact" else np.zeros(0, dtype=np.int64)

    def interface_node_pairs(self, index: int) -> tuple[np.ndarray, np.ndarray]:
        """Interface ``index`` (between layers index and index+1): (top-row nodes of the lower
        layer, bottom-row nodes of the upper layer), column by column, left to right."""
        r = int(self.layer_rows[index][1])
        return np.arange((r - 1) * self.nx, r * self.nx), np.arange(r * self.nx, (r + 1) * self.nx)

    # ------------------------------------------------------------------ bonds
    @cached_property
    def bonded_materials(self) -> tuple[tuple[int, int], ...]:
        """The pairs ``(a, b)`` of material indices some bond of the lattice joins (a bond a
        frictional interface cuts does not count), each ordered pair the bonds hold; read once
        (a pass over every node: 0.24 s at 10⁶ DOFs)."""
        nm = len(self.materials)
        codes = (np.arange(nm)[:, None] * nm + np.arange(nm)[None, :] + 1).astype(float)
        used = np.unique(self.neighbour_stiffness(0, self.ny, codes))
        return tuple(divmod(int(code) - 1, nm) for code in used if code > 0)

    def neighbour_stiffness(self, j0: int, j1: int, table: np.ndarray | None = None) -> np.ndarray:
        """Stiffness of the bond from each node of rows ``[j0, j1)`` to each of its 9
        :data:`SLOTS`, shape (n, 9); 0 where there is no bond (outside the lattice, across a
        frictional interface, and the node itself).  ``table``: another per-pair coefficient
        in place of ``kmat`` (``cmat``: the bonds' viscosity)."""
        grid = self.material_grid(j0, j1, pad=1)
        nm = len(self.materials)
        kext = np.zeros((nm + 1, nm + 1))  # index -1 (outside) reads the zero last row/column
        kext[:nm, :nm] = self.kmat if table is None else table
        rows, nx = j1 - j0, self.nx
        me = grid[1:1 + rows, 1:1 + nx]
        out = np.zeros((rows, nx, 9))
        rows_j = np.arange(j0, j1)
        cut = np.concatenate([[False], self.cut_above, [False]])  # cut[j + 1] = cut_above[j]
        for s, (di, dj) in enumerate(SLOTS):
            if s == SELF:
                continue
            other = grid[1 + dj:1 + dj + rows, 1 + di:1 + di + nx]
            k = kext[me, other]
            if dj == 1:
                k[cut[rows_j + 1]] = 0.0
            elif dj == -1:
                k[cut[rows_j]] = 0.0  # cut_above[j - 1]
            out[:, :, s] = k
        return out.reshape(rows * nx, 9)

    def bonds(self, j0: int = 0, j1: int | None = None, *, viscosity: bool = False):
        """The bonds stored from rows ``[j0, j1)`` (each bond once, from its lower-numbered
        end), ordered by (first node, kind).  Returns ``(ends (m, 2) int64, kind (m,) int8,
        stiffness (m,))``, and the bonds' viscosity (m,) fourth with ``viscosity``.
        Concatenating the results of consecutive row bands gives the result for the whole
        lattice."""
        j1 = self.ny if j1 is None else j1
        grid = self.material_grid(j0, j1, pad=1)
        nm = len(self.materials)
        kext = np.zeros((nm + 1, nm + 1))
        kext[:nm, :nm] = self.kmat
        cext = np.zeros((nm + 1, nm + 1))
        cext[:nm, :nm] = self.cmat
        rows, nx = j1 - j0, self.nx
        jj, ii = np.divmod(np.arange(rows * nx), nx)
        jj = jj + j0
        ends, kinds, ks, cs = [], [], [], []
        for kind, ((ai, aj), (bi, bj)) in enumerate(BOND_ENDS):
            ia, ja, ib, jb = ii + ai, jj + aj, ii + bi, jj + bj
            ok = (np.maximum(ia, ib) < nx) & (np.maximum(ja, jb) < self.ny)
            ma = grid.ravel()[((ja - j0 + 1) * (nx + 2) + ia + 1)[ok]]
            mb = grid.ravel()[((jb - j0 + 1) * (nx + 2) + ib + 1)[ok]]
            k = kext[ma, mb]
            if aj != bj:
                k[self.cut_above[np.minimum(ja, jb)[ok]]] = 0.0
            keep = k > 0
            a = (ja * nx + ia)[ok][keep]
            b = (jb * nx + ib)[ok][keep]
            ends.append(np.stack([a, b], axis=1))
            kinds.append(np.full(a.size, kind, dtype=np.int8))
            ks.append(k[keep])
            cs.append(cext[ma, mb][keep])  # a bond cut by a frictional interface has no k: not kept
        ends = np.concatenate(ends).astype(np.int64)
        kinds = np.concatenate(kinds)
        order = np.lexsort((kinds, ends[:, 0]))
        out = ends[order], kinds[order], np.concatenate(ks)[order]
        return (*out, np.concatenate(cs)[order]) if viscosity else out

    def describe(self) -> str:
        """A few lines for a person: size, layers, bands, interfaces, boundary."""
        s = self.scene
        lines = [f"lattice {self.nx} x {self.ny} nodes, {self.n_dofs} DOFs, spacing {self.spacing:g}, "
                 f"shear {self.shear:g}"]
        for k, layer in enumerate(s.layers):
            a, b = self.layer_rows[k]
            lines.append(f"  layer {layer.name!r}: rows {a}..{b - 1}, k = {layer.stiffness:g}, "
                         f"rho = {layer.density:g}" + _eta(layer.viscosity))
        for e in s.embedded:
            lines.append(f"  embedded {e.name!r} in {e.host!r}: rows +{e.row}..+{e.row + e.rows - 1}, "
                         f"columns {e.column}..{e.column + e.columns - 1}, k = {e.stiffness:g}, "
                         f"rho = {e.density:g}, k to host = {e.interface_stiffness:g}" + _eta(e.viscosity))
        for itf in s.interfaces:
            if itf.bonded:
                lines.append(f"  interface above {itf.below!r}: bonded, k_AB = {itf.stiffness:g}")
            else:
                lines.append(f"  interface above {itf.below!r}: frictional, mu = {itf.friction:g}")
        b = self.boundary
        lines.append(f"  boundary: top {b.top}, bottom {b.bottom}, left {b.left}, right {b.right}")
        if self.damping_mass:
            lines.append(f"  damping: C += {self.damping_mass:g} M")
        return "\n".join(lines)


def _eta(viscosity) -> str:
    return f", eta = {viscosity:g}" if viscosity else ""


def _viscosity_table(scene, mats) -> np.ndarray:
    """The bonds' viscosity per pair of materials: its own inside a material, the mean of the
    two across materials, a bonded interface's own ``viscosity`` where it gives one."""
    eta = np.array([m.viscosity for m in mats])
    cmat = 0.5 * eta[:, None] + 0.5 * eta[None, :]  # halves first: two huge values do not overflow
    for itf in scene.interfaces:
        if itf.bonded and itf.viscosity is not None:
            cmat[itf.index, itf.index + 1] = cmat[itf.index + 1, itf.index] = itf.viscosity
    cmat.setflags(write=False)
    return cmat
