"""The data both static formulations start from, assembled once: :class:`StaticData`.

Loads (prescribed displacements, gravity), the contact sets and their linear functionals,
the free/prescribed split of the DOFs and the rigid-body modes the Dirichlet boundary does
not remove (docs/static-equilibrium.md, "Contact sets and sign conventions" and "Floating
components").
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.csgraph as csgraph

from ...core.errors import ProblemError
from ...lattice.model import LatticeModel
from ...petsc.assembly import assemble
from ...scene import Scene
from ..lines import contact_lines

#: rank tolerance (relative) of the rigid-mode and contact-restraint tests
RANK_RTOL = 1e-9


# --------------------------------------------------------------------------- loads

def prescribed_displacements(model, load) -> tuple[np.ndarray, np.ndarray, list]:
    """``(dofs, values, notes)``: the Dirichlet DOFs (``model.constrained_dofs()``) and the
    displacement the load prescribes on each.

    Priority per DOF where a row meets a side: top row > bottom row > side columns.  Sides
    ``fixed``/``fixed_x`` take ``side_displacement`` in x (else 0) and 0 in y; a fixed
    bottom row stays at 0; the top row takes ``top_displacement`` on the components its
    boundary prescribes.  A nonzero side value on a side that is not fixed in x is a
    :class:`ProblemError` naming ``load.side_displacement``.
    """
    b = model.boundary
    values = np.zeros(model.n_dofs)
    notes = []
    if load is not None and load.side_displacement is not None:
        for k, side in enumerate(("left", "right")):
            ux = float(load.side_displacement[k])
            fx = b.fixed_components(side)[0]
            if ux != 0.0 and not fx:
                raise ProblemError(f"load.side_displacement prescribes x = {ux:g} on the {side} side, "
                                   f"which needs boundary.{side} = \"fixed\" or \"fixed_x\" "
                                   f"(it is {getattr(b, side)!r})")
            if fx:
                values[2 * model.side_nodes(side)] = ux
    fx, fy = b.fixed_components("bottom")
    bottom = model.side_nodes("bottom")
    if fx:
        values[2 * bottom] = 0.0
    if fy:
        values[2 * bottom + 1] = 0.0
    if load is not None and load.top_displacement is not None:
        ux, uy = (float(v) for v in load.top_displacement)
        fx, fy = b.fixed_components("top")
        top = model.side_nodes("top")
        if fx:
            values[2 * top] = ux
        elif ux != 0.0:
            notes.append(f"load.top_displacement x = {ux:g} ignored: boundary.top = {b.top!r} "
                         "does not prescribe x")
        if fy:
            values[2 * top + 1] = uy
        elif uy != 0.0:
            notes.append(f"load.top_displacement y = {uy:g} ignored: boundary.top = {b.top!r} "
                         "does not prescribe y")
    dofs = model.constrained_dofs()
    return dofs, values[dofs], notes


def body_force(model, load) -> np.ndarray:
    """Gravity: ``f_y = −gravity·ρa³`` on every node (the model's lumped masses)."""
    f = np.zeros(model.n_dofs)
    if load is not None and load.gravity:
        f[1::2] = -float(load.gravity) * model.mass()
    return f


# --------------------------------------------------------------------------- contacts

@dataclass(frozen=True)
class LineSpan:
    """Where one contact line's contacts sit in the static problem's contact order:
    ``start`` to ``end`` (exclusive), all with friction ``friction``."""

    name: str
    start: int
    end: int
    friction: float


@dataclass
class Contacts:
    """Every contact of the scene, the base's first, then each frictional interface's: the
    scene's contact lines (:func:`~meicp.contact.lines.contact_lines`) as linear functionals."""

    labels: list          # (line name, column) per contact
    spans: list           # LineSpan per contact line, in order
    mu: np.ndarray
    A_n: sp.csr_matrix    # normal functional per contact (nc × ndof)
    A_t: sp.csr_matrix


def contact_functionals(lines, model) -> Contacts:
    """The normal and tangential functionals of every contact of ``lines``: ``u_n`` (``u_t``)
    of the contact node, or of the upper minus the lower node on a frictional interface."""
    rows_n, cols_n, vals, labels, spans, mu = [], [], [], [], [], []
    cols_t = []
    for line in lines:
        c0 = len(labels)
        upper, lower = line.upper, line.lower
        for i in range(line.size):
            c = len(labels)
            labels.append((line.name, i))
            mu.append(line.friction)
            if lower is None:
                rows_n.append([c]); cols_n.append([2 * upper[i] + 1]); cols_t.append([2 * upper[i]])
                vals.append([1.0])
            else:
                rows_n.append([c, c]); cols_n.append([2 * upper[i] + 1, 2 * lower[i] + 1])
                cols_t.append([2 * upper[i], 2 * lower[i]])
                vals.append([1.0, -1.0])
        spans.append(LineSpan(line.name, c0, len(labels), float(line.friction)))
    nc = len(labels)
    r = np.concatenate(rows_n) if nc else np.zeros(0, int)
    v = np.concatenate(vals) if nc else np.zeros(0)
    A_n = sp.csr_matrix((v, (r, np.concatenate(cols_n) if nc else r)), shape=(nc, model.n_dofs))
    A_t = sp.csr_matrix((v, (r, np.concatenate(cols_t) if nc else r)), shape=(nc, model.n_dofs))
    return Contacts(labels, spans, np.asarray(mu, dtype=float), A_n, A_t)


# --------------------------------------------------------------------------- rigid modes

def _layers_of_nodes(model, nodes) -> list[str]:
    rows = np.unique(np.asarray(nodes) // model.nx)
    idx = np.unique(model.row_material[rows])
    return [model.materials[int(k)].name for k in idx]


def _floating_modes(model, free, constrained):
    """Rigid-body modes of the free DOFs: per connected component of the bond graph, the
    combinations of (x, y translation, rotation about its centroid) that vanish on every
    Dirichlet DOF.  Returns ``(N (nf × k) with orthonormal columns per component,
    component id per column, node lists per component)``."""
    ends, _, _ = model.bonds()
    n = model.n_nodes
    graph = sp.coo_matrix((np.ones(len(ends)), (ends[:, 0], ends[:, 1])), shape=(n, n))
    ncomp, labels = csgraph.connected_components(graph, directed=False)
    pos = model.positions()
    is_con = np.zeros(model.n_dofs, dtype=bool)
    is_con[constrained] = True
    free_index = np.full(model.n_dofs, -1, dtype=np.int64)
    free_index[free] = np.arange(free.size)
    blocks, owner, comp_nodes = [], [], []
    order = np.argsort(labels, kind="stable")
    bounds = np.searchsorted(labels[order], np.arange(ncomp + 1))
    for c in range(ncomp):
        nodes = order[bounds[c]:bounds[c + 1]]
        comp_nodes.append(nodes)
        p = pos[nodes]
        ctr = p.mean(axis=0)
        L = max(float(np.ptp(p[:, 0])), float(np.ptp(p[:, 1])), model.spacing)
        R = np.zeros((2 * nodes.size, 3))
        R[0::2, 0] = 1.0
        R[1::2, 1] = 1.0
        R[0::2, 2] = -(p[:, 1] - ctr[1]) / L
        R[1::2, 2] = (p[:, 0] - ctr[0]) / L
        dofs = (2 * nodes[:, None] + np.arange(2)).ravel()
        cmask = is_con[dofs]
        if np.ptp(nodes // model.nx) == 0 and not cmask[1::2].all():
            raise ProblemError(
                f"static equilibrium: layers {', '.join(map(repr, _layers_of_nodes(model, nodes)))} form "
                "a component of one row (only horizontal bonds; frictional interfaces cut the others): "
                "a mechanism whose nodes move freely in y, so the stiffness on the free DOFs is singular")
        if cmask.any():
            # the (≤ 3 × 3) triangular factor has the same singular values and null space
            _, s, vt = np.linalg.svd(np.linalg.qr(R[cmask], mode="r"), full_matrices=True)
            s = np.concatenate([s, np.zeros(3 - s.size)])
            rank = int(np.sum(s > RANK_RTOL * max(s[0], 1.0)))
            Z = vt[rank:].T
        else:
            Z = np.eye(3)
        if Z.shape[1] == 0:
            continue
        modes = R[~cmask] @ Z
        q, _ = np.linalg.qr(modes)
        full = np.zeros((free.size, q.shape[1]))
        full[free_index[dofs[~cmask]]] = q
        blocks.append(full)
        owner.extend([c] * q.shape[1])
    N = np.hstack(blocks) if blocks else np.zeros((free.size, 0))
    return N, np.asarray(owner, dtype=np.int64), comp_nodes


def _describe_modes(model, N, owner, comp_nodes, free, cols) -> str:
    parts = []
    for c in sorted(set(owner[cols].tolist())):
        parts.append("layers " + ", ".join(map(repr, _layers_of_nodes(model, comp_nodes[c]))))
    return "; ".join(parts)


def singular_message(model, x, free_r, detail) -> str:
    where = ""
    if x is not None:
        nodes = free_r[np.abs(x) > 0.1 * np.max(np.abs(x))] // 2
        where = f" (its zero-energy mode lives in layers {', '.join(map(repr, _layers_of_nodes(model, nodes)))})"
    return ("static equilibrium: the stiffness on the free DOFs is singular" + where + f": {detail}. "
            "The condensed formulation needs the lattice held by its Dirichlet boundary, or rigid "
            "components whose rigid-body modes the contacts hold; a layer of one row between "
            "frictional interfaces (or a one-row lattice) is a mechanism.")




# --------------------------------------------------------------------------- the data

@dataclass
class StaticData:
    """The static problem of one scene under its load, in the notation of
    docs/static-equilibrium.md: ``u`` split into free DOFs ``free`` and prescribed ones
    ``presc`` (values ``u_p``), ``K_ff u_f = b0 + C r`` with ``b0 = f_f − K_fp u_p``, the
    contact functionals split likewise (``A_nf``, ``A_np``, ``A_tf``, ``A_tp``), and the
    rigid-body modes ``N`` of the free DOFs (pinned where ``keep`` is False)."""

    scene: Scene
    model: LatticeModel
    contacts: Contacts
    free: np.ndarray           # free DOFs, natural numbering
    presc: np.ndarray          # prescribed (Dirichlet) DOFs
    u_p: np.ndarray            # their prescribed values
    K_ff: sp.csr_matrix
    b0: np.ndarray
    A_nf: sp.csr_matrix
    A_tf: sp.csr_matrix
    A_np: sp.csr_matrix
    A_tp: sp.csr_matrix
    held_n: np.ndarray         # contacts whose normal functional the boundary prescribes
    held_t: np.ndarray         # ... whose tangential functional it prescribes
    active: np.ndarray         # the normal set: contacts not held
    fric: np.ndarray           # the friction set: neither held, μ > 0
    C_f: sp.csr_matrix         # force map on the free DOFs, columns [normal set, friction set]
    N: np.ndarray              # rigid-body modes of the free DOFs (nf × k)
    H: np.ndarray              # C_fᵀ N: how the contact rows see each rigid mode
    keep: np.ndarray           # free DOFs kept when the rigid modes are pinned
    tol: float                 # the classification tolerance
    notes: list                # remarks for the result (ignored load components, ...)

    @property
    def n_contacts(self) -> int:
        return len(self.contacts.labels)

    @property
    def rigid_modes(self) -> int:
        return self.N.shape[1]

    def friction(self) -> dict:
        """μ per contact set."""
        return {s.name: s.friction for s in self.contacts.spans}

    def describe_friction(self) -> str:
        return ", ".join(f"{s.name}: μ = {s.friction:g}" for s in self.contacts.spans)


def static_data(scene: Scene, model: LatticeModel, *, tol: float, allow_floating: bool,
                timings: dict, lines=None, stiffness=None) -> StaticData:
    """Assemble :class:`StaticData`; ProblemError for a bad load, a mechanism, or a rigid
    mode that neither the boundary nor a contact holds (``timings``: ``assemble`` and the
    rigid-mode part of ``factor``).  ``lines``: the scene's contact lines when the caller has
    them; ``stiffness``: a function giving its SciPy K (an analysis assembles once), else
    assembled here; K itself is dropped on return, only its blocks are kept."""
    t0 = time.perf_counter()
    presc, u_p, notes = prescribed_displacements(model, scene.load)
    f = body_force(model, scene.load)
    K = (assemble(model)[0] if stiffness is None else stiffness()).tocsr()
    free = model.free_dofs()
    cts = contact_functionals(contact_lines(scene, model) if lines is None else lines, model)
    A_nf = cts.A_n[:, free].tocsr()
    A_tf = cts.A_t[:, free].tocsr()
    held_n = np.diff(A_nf.indptr) == 0
    held_t = np.diff(A_tf.indptr) == 0
    active = np.flatnonzero(~held_n)
    fric = np.flatnonzero(~held_n & ~held_t & (cts.mu > 0))
    K_ff = K[free][:, free].tocsr()
    K_fp = K[free][:, presc].tocsr()
    timings["assemble"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    N, owner, comp_nodes = _floating_modes(model, free, presc)
    k = N.shape[1]
    if k and not allow_floating:
        raise ProblemError(singular_message(model, None, free, "rigid-body modes not removed by the "
                                             "Dirichlet boundary, in " + _describe_modes(
                                                 model, N, owner, comp_nodes, free, np.arange(k))
                                             + " (allow_floating=False)"))
    keep = np.ones(free.size, dtype=bool)
    C_f = sp.hstack([A_nf[active].T, A_tf[fric].T]).tocsr()
    H = C_f.T @ N
    if k:
        _, _, piv = sla.qr(N.T, mode="economic", pivoting=True)
        keep[piv[:k]] = False
        cols = _unheld_modes(H, k)
        if cols is not None:
            raise ProblemError(
                "static equilibrium: a rigid-body mode of " + _describe_modes(model, N, owner, comp_nodes,
                                                                             free, cols)
                + " is held neither by the Dirichlet boundary nor by any contact law (a component "
                "touching no contact, or sliding on a frictionless contact); the static problem needs "
                "the lattice held by its Dirichlet boundary or by its contacts")
    timings["factor"] = time.perf_counter() - t0
    return StaticData(scene=scene, model=model, contacts=cts, free=free, presc=presc, u_p=u_p, K_ff=K_ff,
                      b0=f[free] - K_fp @ u_p, A_nf=A_nf, A_tf=A_tf, A_np=cts.A_n[:, presc].tocsr(),
                      A_tp=cts.A_t[:, presc].tocsr(), held_n=held_n, held_t=held_t, active=active,
                      fric=fric, C_f=C_f, N=N, H=H, keep=keep, tol=tol, notes=notes)


def _unheld_modes(H, k):
    """Columns (rigid modes) that the contact rows H do not restrain, or None when H has
    full column rank k."""
    sv = np.linalg.svd(H, compute_uv=False) if H.size else np.zeros(0)
    smax = sv[0] if sv.size else 0.0
    if sv.size >= k and sv[-1] > RANK_RTOL * max(smax, 1.0):
        return None
    _, _, vt = np.linalg.svd(H, full_matrices=True) if H.size else (None, None, np.eye(k))
    bad = vt[-1] if H.size else np.ones(k)
    return np.flatnonzero(np.abs(bad) > 1e-3 * np.abs(bad).max())
