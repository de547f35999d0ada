"""Static frictional equilibrium: the contact states behind ``states = "solve"`` (DESIGN §4,
seed 002 §2).

One load increment from the unloaded reference configuration: the scene's ``[load]``
(prescribed top-row displacement, prescribed x displacement of the side columns — the
lateral shortening — and gravity) is applied at once, and the contact reactions are found
from the linear complementarity problem (LCP) of Signorini contact with Coulomb friction.
The result gives every contact node a state (``stick``, ``slip+``, ``slip-``,
``separated``, ``grazing``), the LCP's matrix classes and what they guarantee (seed 002 §7).

Serial SciPy; no communicator.  Under MPI every rank may call :func:`static_equilibrium`
redundantly and gets the same answer (the computation is deterministic: no random state
other than a fixed seed, no rank-dependent input).

Contact sets and sign conventions
---------------------------------
Normal ``n = +y``, tangent ``t = +x`` for every contact (DESIGN §4).

(a) the rigid rough base under the bottom row (``boundary.bottom = "contact"``, μ =
    ``contact.friction``): per column ``i``, gap change ``g = u_y`` and slip ``u_t = u_x`` of
    node ``(i, 0)``; the reaction ``(r_t, r_n)`` acts on that node, ``r_n ≥ 0`` pushes up.
(b) every frictional interface (μ = its ``friction``), keyed by the lower layer's name: per
    column, the pair (top node of the lower layer, bottom node of the upper layer) with
    relative displacement ``d = u_upper − u_lower``, ``g = d_y``, ``u_t = d_x``; the reaction
    acts ``+r`` on the upper node and ``−r`` on the lower one.

Contact laws (the increment from the reference state, where every contact is closed with
zero force)::

    g ≥ 0,  r_n ≥ 0,  g·r_n = 0,  |r_t| ≤ μ r_n,
    u_t > 0 ⇒ r_t = −μ r_n,   u_t < 0 ⇒ r_t = +μ r_n   (friction opposes the slip).

A node in state ``slip+`` slides (or is about to slide) in ``+x`` — for an interface: the
upper node relative to the lower — and its friction reaction is ``r_t = −μ r_n`` (DESIGN §4:
impending slip in direction ``s`` has ``r_t = −s μ r_n``); ``slip-`` mirrors it.

Formulation (condensed, dense)
------------------------------
``u`` splits into prescribed DOFs ``p`` (``LatticeModel.constrained_dofs``, values from the
load) and free DOFs ``f``.  Each contact component is a linear functional ``a(u)`` with
coefficients ±1 (``A_n``, ``A_t``: one row per contact); its free part ``C`` is the force
map: contact reactions ``r`` put the nodal forces ``C r`` on the free DOFs (work-conjugate to
``g``, ``u_t``).  Equilibrium ``K_ff u_f = b0 + C r`` with ``b0 = f_f − K_fp u_p`` (gravity
``f_y = −gravity·ρa³`` per node) and a sparse LU of ``K_ff`` (SciPy ``splu``, many
right-hand sides, in blocks) gives the contact response

    (g, u_t) = G r + c0,    G = Cᵀ K_ff⁻¹ C  (dense, symmetric),
                            c0 = Cᵀ K_ff⁻¹ b0 + A_p u_p  (the response at r = 0).

The 2-D friction LCP, per contact, in ``x = (r_n, β⁺, β⁻, λ) ≥ 0`` with ``r_t = β⁺ − β⁻``::

    w_n = g                  ≥ 0  ⊥ r_n      (Signorini)
    w_+ = λ + u_t            ≥ 0  ⊥ β⁺       (β⁺ > 0, i.e. r_t > 0, only if u_t = −λ ≤ 0)
    w_− = λ − u_t            ≥ 0  ⊥ β⁻       (β⁻ > 0, i.e. r_t < 0, only if u_t = +λ ≥ 0)
    w_λ = μ r_n − β⁺ − β⁻    ≥ 0  ⊥ λ        (λ > 0, a slip |u_t| = λ, only on the cone)

so that ``λ = 0`` forces ``u_t = 0`` (stick) and ``λ > 0`` forces ``|r_t| = μ r_n`` opposing
the slip.  With all contacts stacked, ordered ``[r_n (normal set), β⁺, β⁻, λ (friction
set), α⁺, α⁻ (rigid modes, below)]``::

        [ Gnn   Gnt  −Gnt   0   Hn  −Hn ]        [ c0_n  ]
        [ Gtn   Gtt  −Gtt   I   Ht  −Ht ]        [ c0_t  ]
    M = [−Gtn  −Gtt   Gtt   I  −Ht   Ht ],   q = [−c0_t  ]
        [ μE    −I    −I    0    0    0 ]        [  0    ]
        [−Hnᵀ  −Htᵀ   Htᵀ   0    0    0 ]        [ −e    ]
        [ Hnᵀ   Htᵀ  −Htᵀ   0    0    0 ]        [  e    ]

The force unknowns are scaled by ``s_G = max|G|`` (``x`` holds ``s_G·r``, the λ and α rows
of forces are multiplied by ``s_G``) so that every block of M is O(1); complementarity is
unchanged.  ``StaticResult.lcp_matrix``/``lcp_q`` hold this (M, q) and
:meth:`StaticResult.split_lcp` maps any solution of it back to physical reactions (used to
compare with Siconos on the same problem).

Which contacts enter the LCP:
- μ = 0: no friction unknowns (the law is ``r_t = 0`` exactly).
- *held* contacts — every DOF of the normal functional prescribed by the Dirichlet
  boundary (e.g. a bottom corner under a ``fixed`` side): the boundary carries the force,
  so the contact takes no part in the LCP; its reactions are reported 0 and its state is
  the one whose MEiCP role matches what the boundary imposes: ``stick`` when the
  tangential functional is prescribed too (v = 0), else ``separated`` (no friction
  capacity: the normal force goes to the boundary, the tangential DOF is free).
  ``held`` / ``interface_held`` flag them.  A held gap that the load makes negative is a
  :class:`ProblemError` (prescribed penetration).
- tangential functional prescribed, normal free (bottom corner under a ``fixed_x`` side):
  only ``r_n`` enters; the slip is the prescribed value, and the friction force, which acts
  on prescribed DOFs only, is reported ``r_t = −sign(u_t) μ r_n`` when ``u_t ≠ 0`` (forced
  slip) and ``0`` when ``u_t = 0`` (stick; the boundary carries any tangential force).

Floating components
-------------------
The condensation needs ``K_ff`` invertible, i.e. the lattice held by its Dirichlet
boundary.  A rigid connected component (two or more rows; layers joined by bonded
interfaces) whose rigid-body modes (x, y translation, rotation) the boundary does not
remove — a block resting on the base under gravity with a free top, the lower layer of a
frictional interface on the base — is condensed with those modes pinned and kept as free
variables ``α`` (``u_f = K_rr⁻¹(b0 + C r) + N α``, N the modes) plus the compatibility
``Nᵀ(b0 + C r) = 0`` (its load must be carried by the contacts): the last two LCP rows
(``α = α⁺ − α⁻``, ``H = Cᵀ N``, ``e = Nᵀ b0``).  A mode that no contact row can restrain
(a layer touching no contact, sliding on a frictionless contact) and any other singular
``K_ff`` (a one-row layer between frictional interfaces is a mechanism) is a
:class:`ProblemError` naming the layers, raised before the LCP; ``allow_floating=False``
makes every rigid mode not held by the Dirichlet boundary an error.

Classification tolerances (``tol``, default :data:`TOL`; ``F``, ``D`` below)
-----------------------------------------------------------------------------
``F`` = force scale = max(max|r|, max|b0|) (reactions and the equivalent nodal load);
``D`` = displacement scale = max|u|.  For a contact that is not held:

- ``r_n > tol·F``: in contact.
    * μ > 0: *saturated* iff ``|r_t| ≥ μ r_n (1 − tol) − tol·F``, *moving* iff
      ``|u_t| > tol·D``.  Saturated or moving → ``slip+``/``slip-`` with direction
      ``s = −sign(r_t)`` (``sign(u_t)`` if ``r_t = 0``); else ``stick``.
    * μ = 0: the cone ``|r_t| ≤ 0`` is always saturated, so the node slips: ``s = sign(u_t)``
      when ``|u_t| > tol·D``; else (it has not moved, e.g. the symmetry column) the sign
      of ``c0_t``, the tangential response of the contact to the load with every reaction
      zero — the direction the tangential force increment of the load pushes it; if that
      is also below ``tol·D``, ``slip+`` by convention.  (For μ = 0 the tangential DOF is
      really free both ways; the MEiCP table has no such state, and the sign only picks
      which half-line the eigenproblem's slip lives on.)
    * tangential functional prescribed (normal free): ``slip±`` by the sign of the
      prescribed slip when ``|u_t| > tol·D`` (forced slip), else ``stick`` — whatever μ.
- ``r_n ≤ tol·F``: ``separated`` if ``g > tol·D``, else ``grazing``.

``StaticResult.tolerances`` records ``tol``, ``F``, ``D`` and the absolute thresholds used.
A failed LCP (no certified solution) gives ``status`` from the LCP and no states: states
are never invented.

Size limit of the condensed formulation: at most :data:`MAX_CONTACTS` contacts (dense G,
dense pivoting); above it a :class:`ProblemError` says so.

Mixed formulation (sparse, PETSc)
---------------------------------
``formulation="mixed"`` (the default above :data:`AUTO_CONDENSED_LIMIT` contacts) keeps the
displacements: ``z = (u_f, r_n, β⁺, β⁻, λ)``, u_f unbounded, the rest ≥ 0, and::

    K_ff u_f − C_nᵀ r_n − C_tᵀ(β⁺ − β⁻) − b0 = 0
    gap(u)  = C_n u_f + A_np u_p         ≥ 0 ⊥ r_n
    λ + slip(u) = λ + C_t u_f + A_tp u_p ≥ 0 ⊥ β⁺
    λ − slip(u)                          ≥ 0 ⊥ β⁻
    μ r_n − β⁺ − β⁻                      ≥ 0 ⊥ λ

with ``C_n = A_nf[normal set]``, ``C_t = A_tf[friction set]`` (the same maps, sets and sign
conventions as the condensed path; forces scaled by ``s_K = max|K_ff|``).  The Jacobian is
constant and sparse.  (1) SNES VI (``vinewtonrsls``, then ``vinewtonssls``; MUMPS LU; options
under ``-meicp_static_``) on the system with :data:`MIXED_REG` added on the diagonal of the
β± and λ rows — without it the λ row has no diagonal and a sticking contact is a degenerate
pair (β⁺, β⁻ columns opposite, λ ± slip rows both 0), which makes the Newton systems
singular.  (2) The contact states are read from that iterate and the equalities they imply
(gap = 0 or r_n = 0; slip = 0, r_t = ∓μ r_n or r_t = 0) are solved exactly in
``(u_f, r_n, r_t)`` (sparse LU): the regularisation is gone.  (3) The certificate —
complementarity of every pair relative to the force scale F, displacement scale D and F·D,
and ``‖K_ff u_f − b0 − C r‖∞ / F``, both from the unregularised sparse data — must be
≤ :data:`MIXED_CERT_TOL`; if not, the states are corrected as in a primal-dual active-set
method (penetration → contact, tension → separated, outside the cone → slip, slip against
the friction → stick) and (2) repeated.  No certificate: a failed result with the SNES
reasons, no states.  The mixed path does not classify the LCP matrix (the mixed matrix is
not the contact operator) and has no ``lcp_matrix``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.csgraph as csgraph
import scipy.sparse.linalg as spla

from ..core.errors import ProblemError
from ..core.results import SOLVED, Result
from ..lcp.problem import DEFAULT_TOL as LCP_TOL
from ..lcp.problem import LCPResult

#: default relative tolerance of the state classification (see the module docstring)
TOL = 1e-9
#: most contacts (all sets together) for the condensed dense formulation
MAX_CONTACTS = 2000
#: K_rr counts as singular when the Rayleigh quotient of its inverse-iteration vector is
#: below this times max|K_rr| (a genuinely held lattice of 10⁶ DOFs is around 1e-6)
SINGULAR_RTOL = 1e-12
#: rank tolerance (relative) of the rigid-mode and contact-restraint tests
RANK_RTOL = 1e-9
#: largest LCP for which method="auto" falls back to dense Lemke when its own choice failed
LEMKE_LIMIT = 4 * MAX_CONTACTS
#: entries of q below this times max|q| are rounding noise and set to 0
Q_NOISE = 1e-12
#: right-hand sides per block when forming G (bounded by memory, see _condense)
RHS_BLOCK_ENTRIES = 2 * 10**7

BASE = "base"


# --------------------------------------------------------------------------- result

@dataclass
class StaticResult(Result):
    """Result of :func:`static_equilibrium`.

    states: the base's contact nodes, left to right (empty without a base, or when the LCP
        failed); interface_states: the same per frictional interface, keyed by the lower
        layer's name.
    r_n, r_t, gap, slip: per base contact (arrays, left to right): reactions on the node,
        gap change ``u_y`` and slip ``u_x``; interface_r_n, interface_r_t, interface_gap,
        interface_slip: dicts of the same per interface (reaction on the upper node,
        relative displacement ``u_upper − u_lower``).
    held, interface_held: bool arrays, contacts held by the Dirichlet boundary (see module
        docstring).
    u: displacement, natural numbering (length 2·N); None when the LCP failed.
    lcp: the :class:`~meicp.lcp.problem.LCPResult`; lcp_matrix, lcp_q: the LCP solved
        (scaled, see the module docstring); layout: how its unknowns map to contacts.
    classes: :class:`~meicp.lcp.classes.MatrixClasses` of ``lcp_matrix`` (exact tests up to
        ``classify_limit`` unknowns, sufficient tests above); guarantees: sentences on
        existence / uniqueness at this μ (seed 002 §7 workflow).
    tolerances: the classification tolerances actually used.
    equilibrium_residual: ``‖K_ff u_f − b0 − C r‖∞ / F`` of the returned state.
    friction: μ per contact set.  rigid_modes: how many rigid modes the contacts hold.
    notes: remarks (ignored load components, inconsistencies within tolerance).
    """

    states: list = field(default_factory=list)
    interface_states: dict = field(default_factory=dict)
    r_n: np.ndarray | None = None
    r_t: np.ndarray | None = None
    gap: np.ndarray | None = None
    slip: np.ndarray | None = None
    held: np.ndarray | None = None
    interface_r_n: dict = field(default_factory=dict)
    interface_r_t: dict = field(default_factory=dict)
    interface_gap: dict = field(default_factory=dict)
    interface_slip: dict = field(default_factory=dict)
    interface_held: dict = field(default_factory=dict)
    u: np.ndarray | None = None
    lcp: LCPResult | None = None
    lcp_matrix: np.ndarray | None = None
    lcp_q: np.ndarray | None = None
    layout: dict = field(default_factory=dict)
    classes: object = None
    guarantees: list = field(default_factory=list)
    tolerances: dict = field(default_factory=dict)
    equilibrium_residual: float = float("nan")
    friction: dict = field(default_factory=dict)
    rigid_modes: int = 0
    notes: list = field(default_factory=list)

    def split_lcp(self, x) -> dict:
        """Physical quantities of an LCP solution ``x`` of ``(lcp_matrix, lcp_q)``:
        ``r_n`` (normal set), ``r_t`` (friction set), ``beta_plus``, ``beta_minus``, ``lam``,
        ``alpha``, with ``normal``/``friction`` = the contact ids (rows of ``layout["contacts"]``)."""
        lay = self.layout
        x = np.asarray(x, dtype=float)
        s = lay["scale"]
        out = {k: x[lay[k]] / s for k in ("r_n", "beta_plus", "beta_minus")}
        out["r_t"] = out["beta_plus"] - out["beta_minus"]
        out["lam"] = x[lay["lam"]]
        out["alpha"] = x[lay["alpha_plus"]] - x[lay["alpha_minus"]]
        out["normal"], out["friction"] = lay["normal"], lay["friction_set"]
        return out

    def summary(self) -> str:
        head = f"static equilibrium: {self.status}"
        if self.message:
            head += f" — {self.message}"
        lines = [head]
        if self.states:
            lines.append("  base: " + " ".join(self.states))
        for name, st in self.interface_states.items():
            lines.append(f"  interface above {name!r}: " + " ".join(st))
        lines.extend(f"  - {g}" for g in self.guarantees)
        return "\n".join(lines)


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

@dataclass
class _Contacts:
    labels: list          # (set name, column) per contact
    sets: list            # (set name, first contact, end, μ)
    mu: np.ndarray
    A_n: sp.csr_matrix    # normal functional per contact (nc × ndof)
    A_t: sp.csr_matrix


def _contact_sets(scene, model) -> _Contacts:
    nx = model.nx
    rows_n, cols_n, vals, labels, sets, mu = [], [], [], [], [], []
    cols_t = []

    def add(name, friction, lower, upper):
        c0 = len(labels)
        for i in range(nx):
            c = len(labels)
            labels.append((name, i))
            mu.append(friction)
            if lower is None:
                rows_n.append([c]); cols_n.append([2 * upper[i] + 1]); cols_t.append([2 * upper[i]])
                vals.append([1.0])
            else:
                rows_n.append([c, c]); cols_n.append([2 * upper[i] + 1, 2 * lower[i] + 1])
                cols_t.append([2 * upper[i], 2 * lower[i]])
                vals.append([1.0, -1.0])
        sets.append((name, c0, len(labels), float(friction)))

    if scene.boundary.bottom == "contact":
        add(BASE, scene.contact.friction, None, model.contact_nodes())
    for itf in scene.frictional_interfaces():
        lower, upper = model.interface_node_pairs(itf.index)
        add(itf.below, itf.friction, lower, upper)
    nc = len(labels)
    r = np.concatenate(rows_n) if nc else np.zeros(0, int)
    v = np.concatenate(vals) if nc else np.zeros(0)
    A_n = sp.csr_matrix((v, (r, np.concatenate(cols_n) if nc else r)), shape=(nc, model.n_dofs))
    A_t = sp.csr_matrix((v, (r, np.concatenate(cols_t) if nc else r)), shape=(nc, model.n_dofs))
    return _Contacts(labels, sets, np.asarray(mu, dtype=float), A_n, A_t)


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


# --------------------------------------------------------------------------- factorisation

def _factor(K_rr, model, free_r):
    """``splu`` of the SPD ``K_rr`` and a singularity check (inverse iteration)."""
    n = K_rr.shape[0]
    if n == 0:
        return None
    try:
        lu = spla.splu(K_rr.tocsc(), permc_spec="COLAMD")  # measured faster solves than MMD here
    except RuntimeError as exc:  # "Factor is exactly singular"
        raise ProblemError(_singular_message(model, None, free_r, f"SuperLU: {exc}")) from None
    rng = np.random.default_rng(20240607)
    x = rng.standard_normal(n)
    rho = np.inf
    for _ in range(3):
        x = lu.solve(x)
        nrm = np.linalg.norm(x)
        if not np.isfinite(nrm) or nrm == 0:
            rho = 0.0
            break
        x /= nrm
        rho = float(x @ (K_rr @ x))
    kmax = float(np.max(np.abs(K_rr.data))) if K_rr.nnz else 1.0
    if not rho > SINGULAR_RTOL * kmax:
        raise ProblemError(_singular_message(model, x if np.all(np.isfinite(x)) else None, free_r,
                                             f"smallest-eigenvalue estimate {rho:.2e} ≤ "
                                             f"{SINGULAR_RTOL:g}·max|K| = {SINGULAR_RTOL * kmax:.2e}"))
    return lu


def _singular_message(model, x, free_r, detail) -> str:
    where = ""
    if x is not None:
        nodes = free_r[np.abs(x) > 0.1 * np.max(np.abs(x))] // 2
        where = f" (its zero-energy mode lives in layers {', '.join(map(repr, _layers_of_nodes(model, nodes)))})"
    return ("static equilibrium: the stiffness on the free DOFs is singular" + where + f": {detail}. "
            "The condensed formulation needs the lattice held by its Dirichlet boundary, or rigid "
            "components whose rigid-body modes the contacts hold; a layer of one row between "
            "frictional interfaces (or a one-row lattice) is a mechanism.")


def _condense(lu, C_r, nr):
    """``C_rᵀ K_rr⁻¹ C_r`` (dense), solving in blocks of right-hand sides."""
    m = C_r.shape[1]
    G = np.zeros((m, m))
    if m == 0 or lu is None:
        return G
    C_r = C_r.tocsc()
    step = max(1, min(m, RHS_BLOCK_ENTRIES // max(nr, 1)))
    CT = C_r.T.tocsr()
    for a in range(0, m, step):
        b = min(m, a + step)
        X = lu.solve(C_r[:, a:b].toarray())
        G[:, a:b] = CT @ X
    return 0.5 * (G + G.T)


# --------------------------------------------------------------------------- mixed formulation

#: formulation="auto" uses the condensed (dense) path up to this many contacts, else mixed
AUTO_CONDENSED_LIMIT = 200
#: relative diagonal regularisation of the β± and λ rows in the SNES VI stage of the mixed
#: formulation (removed again by the certified polish)
MIXED_REG = 1e-8
#: relative threshold that reads contact states from the (regularised) SNES iterate
MIXED_ID_TOL = 1e-6
#: most active-set corrections of the polish
MIXED_POLISH_ITERS = 40
#: certificate tolerance of the mixed formulation (complementarity and equilibrium)
MIXED_CERT_TOL = 1e-9
#: options prefix of the mixed formulation's SNES VI
MIXED_PREFIX = "meicp_static_"

# per-contact states of the polish
_SEP, _STICK, _PLUS, _MINUS, _CONTACT = 0, 1, 2, 3, 4


class _MixedData:
    """The sparse mixed LCP in scaled variables: z = (u_f, ρ_n, ρ⁺, ρ⁻, λ), forces r = s_K·ρ."""

    def __init__(self, K_ff, b0, A_nf, A_tf, A_np, A_tp, u_p, active, fric, mu):
        self.nf = K_ff.shape[0]
        self.nN, self.nF = active.size, fric.size
        self.sK = float(np.max(np.abs(K_ff.data))) if K_ff.nnz else 1.0
        self.Cn = A_nf[active].tocsr()                        # nN × nf
        self.Ct = A_tf[fric].tocsr()                          # nF × nf
        self.gn0 = A_np[active] @ u_p                         # gap at u_f = 0
        self.gt0 = A_tp[fric] @ u_p                           # slip at u_f = 0
        self.K = (K_ff / self.sK).tocsr()
        self.b = b0 / self.sK
        self.b0 = b0
        self.K_ff = K_ff
        self.mu_f = mu[fric]
        self.pos = np.searchsorted(active, fric)              # friction contact → its normal row
        E = sp.csr_matrix((self.mu_f, (np.arange(self.nF), self.pos)), shape=(self.nF, self.nN))
        self.E = E
        nf, nN, nF = self.nf, self.nN, self.nF
        o = np.cumsum([0, nf, nN, nF, nF, nF])
        self.sl = {k: slice(o[i], o[i + 1]) for i, k in enumerate(("u", "n", "p", "m", "l"))}
        self.n = int(o[-1])
        I = sp.identity(nF, format="csr")
        if nF:
            self.J0 = sp.bmat([
                [self.K, -self.Cn.T, -self.Ct.T, self.Ct.T, None],
                [self.Cn, None, None, None, None],
                [self.Ct, None, None, None, I],
                [-self.Ct, None, None, None, I],
                [None, E, -I, -I, None]], format="csr")
        elif nN:
            self.J0 = sp.bmat([[self.K, -self.Cn.T], [self.Cn, None]], format="csr")
        else:
            self.J0 = self.K.copy()
        self.J0 = sp.csr_matrix(self.J0, shape=(self.n, self.n))
        self.q = np.concatenate([-self.b, self.gn0, self.gt0, -self.gt0, np.zeros(nF)])
        self.lower = np.concatenate([np.full(nf, -np.inf), np.zeros(nN + 3 * nF)])
        self.upper = np.full(self.n, np.inf)

    def regularised(self, eps):
        d = np.zeros(self.n)
        d[self.nf + self.nN:] = eps
        return (self.J0 + sp.diags(d)).tocsr()

    def split(self, z):
        s = self.sl
        return z[s["u"]], z[s["n"]], z[s["p"]], z[s["m"]], z[s["l"]]

    def scales(self, z):
        u, rn, rp, rm, lam = self.split(z)
        F = max(float(np.max(np.abs(z[self.nf:self.nf + self.nN + 2 * self.nF]), initial=0.0)),
                float(np.max(np.abs(self.b), initial=0.0)))
        D = max(float(np.max(np.abs(u), initial=0.0)), float(np.max(np.abs(self.gn0), initial=0.0)),
                float(np.max(np.abs(self.gt0), initial=0.0)), float(np.max(np.abs(lam), initial=0.0)))
        return F, D

    def certificate(self, z):
        """``(complementarity residual, equilibrium residual)``, both relative: per pair
        (r_n ⊥ gap, β± ⊥ λ ± slip, λ ⊥ μ r_n − β⁺ − β⁻) the bound violations of each side and
        the product, over the force scale F, the displacement scale D and F·D; the
        equilibrium ``‖K_ff u_f − b0 − C r‖∞ / F`` — all from the unregularised sparse data."""
        w = self.J0 @ z + self.q
        F, D = self.scales(z)
        F, D = max(F, 1e-300), max(D, 1e-300)
        nf, nN, nF = self.nf, self.nN, self.nF
        x, wc = z[nf:], w[nf:]
        is_force = np.concatenate([np.ones(nN + 2 * nF, bool), np.zeros(nF, bool)])
        xs = np.where(is_force, F, D)       # scale of the variable
        ws = np.where(is_force, D, F)       # scale of its complementary function
        comp = 0.0
        if x.size:
            comp = max(float(np.max(-x / xs, initial=0.0)), float(np.max(-wc / ws, initial=0.0)),
                       float(np.max(np.abs(x * wc) / (F * D), initial=0.0)))
        eq = float(np.max(np.abs(w[:nf]), initial=0.0)) / F
        return comp, eq

    def identify(self, z):
        """States read from an iterate (tolerant: MIXED_ID_TOL)."""
        u, rn, rp, rm, lam = self.split(z)
        F, D = self.scales(z)
        t = MIXED_ID_TOL
        sn = np.where(rn > t * F, _CONTACT, _SEP)
        st = np.full(self.nF, _SEP)
        rt = rp - rm
        rnf = rn[self.pos]
        slip = self.Ct @ u + self.gt0
        incontact = sn[self.pos] == _CONTACT
        sat = np.abs(rt) >= self.mu_f * rnf * (1 - t)
        moving = lam > t * D
        d = np.where(rt != 0, -np.sign(rt), np.sign(slip))
        st[incontact] = _STICK
        sl = incontact & (sat | moving)
        st[sl & (d >= 0)] = _PLUS
        st[sl & (d < 0)] = _MINUS
        return sn, st

    def polish(self, sn, st, comm):
        """Exact solve of the equalities of the given states in (u_f, ρ_n, ρ_t), then
        (β⁺, β⁻, λ) from ρ_t and the slip.  Returns z or None (singular)."""
        nf, nN, nF = self.nf, self.nN, self.nF
        con = (sn == _CONTACT).astype(float)
        sep_f = (st == _SEP).astype(float)
        stk = (st == _STICK).astype(float)
        sgn = np.where(st == _PLUS, 1.0, np.where(st == _MINUS, -1.0, 0.0))
        slp = np.abs(sgn)
        # normal rows: contact → gap = 0; separated → ρ_n = 0
        Rn_u = sp.diags(con) @ self.Cn
        Rn_n = sp.diags(1.0 - con)
        rhs_n = -con * self.gn0
        # tangential rows: stick → slip = 0; slip s → ρ_t + s μ ρ_n = 0; separated → ρ_t = 0
        Rt_u = sp.diags(stk) @ self.Ct
        Rt_n = sp.diags(sgn) @ self.E
        Rt_t = sp.diags(slp + sep_f)
        rhs_t = -stk * self.gt0
        blocks = [[self.K, -self.Cn.T, -self.Ct.T], [Rn_u, Rn_n, None], [Rt_u, Rt_n, Rt_t]]
        if nF == 0:
            blocks = [[self.K, -self.Cn.T], [Rn_u, Rn_n]]
        A = sp.bmat(blocks, format="csr")
        rhs = np.concatenate([self.b, rhs_n, rhs_t]) if nF else np.concatenate([self.b, rhs_n])
        from ..petsc.lcp import lu_solve
        sol, ok = lu_solve(A, rhs, comm=comm, prefix=MIXED_PREFIX + "polish_",
                           options={"mat_mumps_icntl_14": 400})
        if not ok:
            return None
        u, rn = sol[:nf], sol[nf:nf + nN]
        rt = sol[nf + nN:] if nF else np.zeros(0)
        slip = self.Ct @ u + self.gt0
        lam = np.where(slp > 0, sgn * slip, np.where(sep_f > 0, np.abs(slip), 0.0))
        return np.concatenate([u, rn, np.maximum(rt, 0.0), np.maximum(-rt, 0.0), lam])

    def correct(self, z, sn, st):
        """One primal-dual active-set correction of the states from a polished z; returns
        ``(sn, st, changed)``."""
        u, rn, rp, rm, lam = self.split(z)
        F, D = self.scales(z)
        t = MIXED_CERT_TOL
        gap = self.Cn @ u + self.gn0
        slip = self.Ct @ u + self.gt0
        rt = rp - rm
        sn2, st2 = sn.copy(), st.copy()
        sn2[(sn == _SEP) & (gap < -t * D)] = _CONTACT
        sn2[(sn == _CONTACT) & (rn < -t * F)] = _SEP
        con_f = sn2[self.pos] == _CONTACT
        st2[~con_f] = _SEP
        newly = con_f & (st == _SEP)
        st2[newly] = _STICK
        rnf = rn[self.pos]
        over = (st == _STICK) & con_f & (np.abs(rt) > self.mu_f * rnf * (1 + t) + t * F)
        st2[over & (rt < 0)] = _PLUS
        st2[over & (rt >= 0)] = _MINUS
        sgn = np.where(st == _PLUS, 1.0, np.where(st == _MINUS, -1.0, 0.0))
        back = (sgn != 0) & con_f & (sgn * slip < -t * D)
        st2[back] = _STICK
        changed = bool(np.any(sn2 != sn) or np.any(st2 != st))
        return sn2, st2, changed


def _size(comm) -> int:
    if comm is None:
        return 1
    return comm.getSize() if hasattr(comm, "getSize") else comm.Get_size()


def _solve_mixed(data: _MixedData, comm, petsc_options, notes) -> tuple:
    """SNES VI on the regularised mixed LCP, then the certified polish.  Returns
    ``(z or None, info dict)``."""
    from ..petsc.lcp import snes_vi_affine

    info = {"attempts": []}
    J = data.regularised(MIXED_REG)
    pcomm = comm if comm is not None and _size(comm) > 1 else None
    best = None
    types = ("vinewtonrsls", "vinewtonssls")
    if petsc_options and "snes_type" in petsc_options:
        types = types[:1]  # the caller's choice overrides both defaults: one attempt
    for snes_type in types:
        t0 = time.perf_counter()
        z, its, reason, sec, snes_type = snes_vi_affine(J, data.q, data.lower, data.upper, comm=pcomm,
                                             prefix=MIXED_PREFIX,
                                             defaults={"snes_type": snes_type, "snes_rtol": 1e-12,
                                                       "snes_max_it": 100,
                                                       # delayed pivots of the saddle-point
                                                       # systems overflow MUMPS' default workspace
                                                       "mat_mumps_icntl_14": 400},
                                             options=petsc_options)
        attempt = {"snes_type": snes_type, "iterations": its, "reason": reason,
                   "seconds": time.perf_counter() - t0}
        info["attempts"].append(attempt)
        if not np.all(np.isfinite(z)):
            continue
        sn, st = data.identify(z)
        zp = None
        for k in range(MIXED_POLISH_ITERS):
            zp = data.polish(sn, st, pcomm)
            if zp is None:
                break
            comp, eq = data.certificate(zp)
            if comp <= MIXED_CERT_TOL and eq <= MIXED_CERT_TOL:
                attempt.update(polish_iterations=k + 1, certificate=(comp, eq))
                info.update(attempt)
                return zp, info
            sn, st, changed = data.correct(zp, sn, st)
            if not changed:
                break
        if zp is not None:
            cert = data.certificate(zp)
            attempt["certificate"] = cert
            if best is None or max(cert) < max(best[1]):
                best = (zp, cert)
    info["best_certificate"] = best[1] if best else None
    return None, info


def _static_mixed(scene, model, cts, K_ff, b0, free, presc, u_p, A_nf, A_tf, A_np, A_tp, held_n, held_t,
                  active, fric, N, keep, tol, notes, timings, t_start, comm, petsc_options):
    """The sparse mixed formulation (module docstring, "Mixed formulation")."""
    nc = len(cts.labels)
    k = N.shape[1]
    t0 = time.perf_counter()
    data = _MixedData(K_ff, b0, A_nf, A_tf, A_np, A_tp, u_p, active, fric, cts.mu)
    timings["assemble_mixed"] = time.perf_counter() - t0
    notes = list(notes) + [
        "formulation = mixed: the LCP matrix is not classified (the mixed matrix, displacements and "
        "reactions together, is not the contact operator: its classes say nothing about the "
        "contact problem; the condensed formulation classifies it)"]
    t0 = time.perf_counter()
    z, info = _solve_mixed(data, comm, petsc_options, notes) if data.n else (np.zeros(0), {"attempts": []})
    timings["lcp"] = time.perf_counter() - t0
    n_lcp = data.nN + 3 * data.nF
    lay = {"formulation": "mixed", "unknowns": data.n, "normal": active, "friction_set": fric,
           "contacts": list(cts.labels), "rigid_modes": k, "sets": [s[:3] for s in cts.sets],
           "scale": 1.0 / data.sK, "attempts": info.get("attempts", [])}
    reason = "; ".join(f"{a['snes_type']}: {a['reason']} after {a['iterations']} iterations"
                       for a in info.get("attempts", []))
    result = StaticResult(layout=lay, friction={s[0]: s[3] for s in cts.sets}, rigid_modes=k, notes=notes)
    result.timings = timings
    mus = ", ".join(f"{name}: μ = {mu:g}" for name, _, _, mu in cts.sets)
    result.guarantees = [f"Static mixed LCP ({mus}): {data.nf} displacement unknowns, {data.nN} normal "
                         f"reactions, {data.nF} frictional contacts (β⁺, β⁻, λ each) — {data.n} unknowns; "
                         "matrix classes not computed (mixed formulation)."]
    if z is None:
        result.status = "failed"
        best = info.get("best_certificate")
        result.message = (f"the static mixed LCP ({data.n} unknowns) was not solved: SNES VI {reason}; "
                          + (f"best polished certificate (complementarity, equilibrium) = "
                             f"({best[0]:.1e}, {best[1]:.1e}) > {MIXED_CERT_TOL:g}" if best else
                             "no iterate could be polished")
                          + "; no contact states reported")
        result.guarantees.append("For this load no equilibrium was certified.")
        timings["total"] = time.perf_counter() - t_start
        return result
    t0 = time.perf_counter()
    comp, eq = data.certificate(z) if data.n else (0.0, 0.0)
    u_f, rn_s, rp, rm, lam = data.split(z) if data.n else (np.zeros(0),) * 5
    r_n = np.zeros(nc)
    r_t = np.zeros(nc)
    r_n[active] = rn_s * data.sK
    r_t[fric] = (rp - rm) * data.sK
    u, gap, slip, F, D = _response(model, cts, free, presc, u_f, u_p, r_n, r_t, b0)
    C_f = sp.hstack([A_nf[active].T, A_tf[fric].T]).tocsr()
    res = K_ff @ u_f - b0 - C_f @ np.concatenate([r_n[active], r_t[fric]])
    result.equilibrium_residual = float(np.max(np.abs(res))) / F if res.size and F > 0 else 0.0
    _held_contacts(cts, gap, slip, r_n, r_t, held_n, held_t, tol, D)
    c0_t = np.zeros(nc)
    zero_mu = np.flatnonzero(~held_n & ~held_t & (cts.mu == 0))
    if zero_mu.size and np.any(np.abs(slip[zero_mu]) <= tol * D):
        # the load's tangential response at r = 0 (direction rule of μ = 0): one solve with the
        # rigid modes pinned as in the condensed formulation
        K_rr = K_ff[keep][:, keep].tocsc()
        if K_rr.shape[0]:
            u0_r = spla.spsolve(K_rr, b0[keep])
            c0_t[zero_mu] = A_tf[zero_mu][:, keep] @ u0_r + A_tp[zero_mu] @ u_p
    states = _classify_states(r_n, r_t, gap, slip, cts.mu, held_n, held_t, c0_t, tol, F, D, result.notes,
                              cts.labels)
    _store_contacts(result, cts, states, (r_n, r_t, gap, slip, held_n), u, tol, F, D, MIXED_CERT_TOL)
    result.status = SOLVED
    result.residual = comp
    result.iterations = int(info.get("iterations", 0))
    result.guarantees.append(f"For this load an equilibrium exists: the mixed LCP solution passed its "
                             f"certificate (complementarity {comp:.1e}, equilibrium {eq:.1e}).")
    counts = {s: states.count(s) for s in ("stick", "slip+", "slip-", "separated", "grazing") if s in states}
    how = (f"SNES {info.get('snes_type')} ({info.get('reason')}, {info.get('iterations')} it) + "
           f"{info.get('polish_iterations')} polish" if info.get("attempts") else "no unknowns")
    result.message = (f"{nc} contacts ({', '.join(f'{v} {s}' for s, v in counts.items())}); mixed LCP "
                      f"{data.n} unknowns ({n_lcp} contact) by {how}, certificate {comp:.1e}; "
                      f"equilibrium residual {result.equilibrium_residual:.1e}")
    timings["states"] = time.perf_counter() - t0
    timings["total"] = time.perf_counter() - t_start
    return result


# --------------------------------------------------------------------------- entry point

def static_equilibrium(scene, *, model=None, tol: float = TOL, method: str = "auto",
                       classify_limit: int = 12, lcp_tol: float = LCP_TOL,
                       allow_floating: bool = True, formulation: str = "auto", comm=None,
                       petsc_options: dict | None = None, **lcp_options) -> StaticResult:
    """Static frictional equilibrium of ``scene`` under its ``[load]``; every contact's state.

    scene: a :class:`~meicp.io.scene.Scene` (or a scene file path); model: its
    :class:`~meicp.lattice.model.LatticeModel` if already built.  Every contact set of the
    scene (rigid base, frictional interfaces) is solved together, whatever its ``states``
    key says (the sets interact; the caller picks the sets it asked to solve).

    tol: relative classification tolerance (module docstring); method: passed to
    :func:`meicp.solve_lcp` (``auto`` = dense Lemke here, with fallbacks); lcp_tol: its
    certificate tolerance; classify_limit: ``exact_limit`` of :func:`meicp.classify` on the
    LCP matrix; allow_floating: condense rigid components held by contact (module
    docstring) instead of raising.

    formulation: ``"condensed"`` (dense compliance, Lemke; classifies the LCP matrix),
    ``"mixed"`` (sparse, displacements kept, PETSc SNES VI + certified polish; no matrix
    classes; options ``petsc_options`` under ``-meicp_static_``) or ``"auto"`` (condensed up
    to :data:`AUTO_CONDENSED_LIMIT` contacts, else mixed).  comm: with several ranks the
    mixed formulation's PETSc solves are distributed over it (collective then: every rank
    calls with the same scene); the condensed formulation ignores it.

    Serial SciPy (condensed), deterministic: under MPI every rank may call it with the same scene and
    gets the same answer.  Raises :class:`ProblemError` before any solve for a scene with no
    contact set ("a load with no contact"), a bad load, more than :data:`MAX_CONTACTS`
    contacts for the condensed formulation, or a singular stiffness (module docstring).  A failed LCP is not an
    exception: ``status`` comes from the LCP and no states are reported.
    """
    from ..io.scene import Scene, load_scene
    from ..lattice.assembly import assemble
    from ..lattice.model import LatticeModel
    from ..lcp import solve_lcp
    from ..lcp.classes import classify

    t_start = time.perf_counter()
    timings = {}
    if isinstance(scene, (str, Path)):
        scene = load_scene(scene)
    if not isinstance(scene, Scene):
        raise ProblemError(f"scene must be a Scene or a scene path, got {type(scene).__name__}")
    if not (tol > 0 and tol < 1):
        raise ProblemError(f"tol must be in (0, 1), got {tol!r}")
    has_base = scene.boundary.bottom == "contact"
    if not has_base and not scene.frictional_interfaces():
        what = "a load with no contact" if scene.load is not None else "no contact"
        raise ProblemError(f"static equilibrium: {what}: the scene has no contact set (boundary.bottom "
                           f"is {scene.boundary.bottom!r}, not \"contact\", and no interface is "
                           "frictional), so there are no contact states to solve for")
    if has_base and scene.contact is None:
        raise ProblemError("contact: required when boundary.bottom = \"contact\"")
    nsets = int(has_base) + len(scene.frictional_interfaces())
    nc_total = nsets * scene.nx
    if formulation not in ("auto", "condensed", "mixed"):
        raise ProblemError(f"formulation must be 'auto', 'condensed' or 'mixed', got {formulation!r}")
    if formulation == "auto":
        formulation = "condensed" if nc_total <= AUTO_CONDENSED_LIMIT else "mixed"
    if formulation == "condensed" and nc_total > MAX_CONTACTS:
        raise ProblemError(f"static equilibrium: {nc_total} contacts exceed the condensed dense "
                           f"formulation's limit of {MAX_CONTACTS}; use formulation=\"mixed\" (the "
                           "sparse mixed formulation)")
    model = model if model is not None else LatticeModel(scene)
    if not isinstance(model, LatticeModel) or (model.scene is not scene and model.scene != scene):
        raise ProblemError("model must be the LatticeModel of this scene")

    # ---------------------------------------------------------------- data
    t0 = time.perf_counter()
    presc, u_p, notes = prescribed_displacements(model, scene.load)
    f = body_force(model, scene.load)
    K, _ = assemble(model)
    K = K.tocsr()
    free = model.free_dofs()
    cts = _contact_sets(scene, model)
    nc = len(cts.labels)
    A_nf = cts.A_n[:, free].tocsr()
    A_tf = cts.A_t[:, free].tocsr()
    A_np = cts.A_n[:, presc].tocsr()
    A_tp = cts.A_t[:, presc].tocsr()
    held_n = np.diff(A_nf.indptr) == 0
    held_t = np.diff(A_tf.indptr) == 0
    active = np.flatnonzero(~held_n)
    fric = np.flatnonzero(~held_n & ~held_t & (cts.mu > 0))
    K_ff = K[free][:, free].tocsr()
    K_fp = K[free][:, presc].tocsr()
    b0 = f[free] - K_fp @ u_p
    timings["assemble"] = time.perf_counter() - t0

    # ---------------------------------------------------------------- rigid modes, factor
    t0 = time.perf_counter()
    N, owner, comp_nodes = _floating_modes(model, free, presc)
    k = N.shape[1]
    if k and not allow_floating:
        raise ProblemError(_singular_message(model, None, free, "rigid-body modes not removed by the "
                                             "Dirichlet boundary, in " + _describe_modes(
                                                 model, N, owner, comp_nodes, free, np.arange(k))
                                             + " (allow_floating=False)"))
    keep = np.ones(free.size, dtype=bool)
    if k and formulation == "mixed":
        _, _, piv = sla.qr(N.T, mode="economic", pivoting=True)
        keep[piv[:k]] = False
        H = sp.hstack([A_nf[active].T, A_tf[fric].T]).tocsr().T @ N
        sv = np.linalg.svd(H, compute_uv=False) if H.size else np.zeros(0)
        if sv.size < k or sv[-1] <= RANK_RTOL * max(sv[0] if sv.size else 0.0, 1.0):
            raise ProblemError("static equilibrium: a rigid-body mode of "
                               + _describe_modes(model, N, owner, comp_nodes, free, np.arange(k))
                               + " is held neither by the Dirichlet boundary nor by any contact law")
    if formulation == "mixed":
        timings["factor"] = time.perf_counter() - t0
        return _static_mixed(scene, model, cts, K_ff, b0, free, presc, u_p, A_nf, A_tf, A_np, A_tp,
                             held_n, held_t, active, fric, N, keep, tol, notes, timings, t_start, comm,
                             petsc_options)
    if k:
        kn = float(np.abs(K_ff @ N).max()) / max(float(np.abs(K_ff.data).max()), 1e-300)
        if kn > 1e-8:  # the rigid modes must be in the null space of K (a bug otherwise)
            raise RuntimeError(f"rigid modes are not in the null space of K (|K N| = {kn:.1e})")
        _, _, piv = sla.qr(N.T, mode="economic", pivoting=True)
        keep[piv[:k]] = False
    free_r = free[keep]
    K_rr = K_ff[keep][:, keep].tocsc()
    lu = _factor(K_rr, model, free_r)
    timings["factor"] = time.perf_counter() - t0

    # ---------------------------------------------------------------- condensation
    t0 = time.perf_counter()
    C_f = sp.hstack([A_nf[active].T, A_tf[fric].T]).tocsr()  # nf × (|N| + |F|)
    C_r = C_f[keep]
    G = _condense(lu, C_r, free_r.size)
    u0_r = lu.solve(b0[keep]) if lu is not None else np.zeros(0)
    c0 = C_r.T @ u0_r + np.concatenate([A_np[active] @ u_p, A_tp[fric] @ u_p])
    H = C_f.T @ N  # (|N| + |F|) × k
    e = N.T @ b0
    if k:
        sv = np.linalg.svd(H, compute_uv=False) if H.size else np.zeros(0)
        smax = sv[0] if sv.size else 0.0
        if sv.size < k or sv[-1] <= RANK_RTOL * max(smax, 1.0):
            _, _, vt = np.linalg.svd(H, full_matrices=True) if H.size else (None, None, np.eye(k))
            bad = vt[-1] if H.size else np.ones(k)
            cols = np.flatnonzero(np.abs(bad) > 1e-3 * np.abs(bad).max())
            raise ProblemError(
                "static equilibrium: a rigid-body mode of " + _describe_modes(model, N, owner, comp_nodes,
                                                                             free, cols)
                + " is held neither by the Dirichlet boundary nor by any contact law (a component "
                "touching no contact, or sliding on a frictionless contact); the condensation needs "
                "the lattice held by its Dirichlet boundary or by its contacts")
    timings["condense"] = time.perf_counter() - t0

    # ---------------------------------------------------------------- the LCP
    nN, nF = active.size, fric.size
    pos_in_N = np.searchsorted(active, fric)
    sG = float(np.max(np.abs(G))) if G.size and np.max(np.abs(G)) > 0 else 1.0
    Gs = G / sG
    Gnn, Gnt = Gs[:nN, :nN], Gs[:nN, nN:]
    Gtn, Gtt = Gs[nN:, :nN], Gs[nN:, nN:]
    Hn, Ht = H[:nN], H[nN:]
    n_lcp = nN + 3 * nF + 2 * k
    sl = {}
    o = 0
    for name, size in (("r_n", nN), ("beta_plus", nF), ("beta_minus", nF), ("lam", nF),
                       ("alpha_plus", k), ("alpha_minus", k)):
        sl[name] = slice(o, o + size)
        o += size
    Mx = np.zeros((n_lcp, n_lcp))
    q = np.zeros(n_lcp)
    R, P, Mi, L, Ap, Am = (sl[s] for s in ("r_n", "beta_plus", "beta_minus", "lam", "alpha_plus",
                                           "alpha_minus"))
    I_F = np.eye(nF)
    E = np.zeros((nF, nN))
    E[np.arange(nF), pos_in_N] = cts.mu[fric]
    Mx[R, R], Mx[R, P], Mx[R, Mi], Mx[R, Ap], Mx[R, Am] = Gnn, Gnt, -Gnt, Hn, -Hn
    Mx[P, R], Mx[P, P], Mx[P, Mi], Mx[P, L], Mx[P, Ap], Mx[P, Am] = Gtn, Gtt, -Gtt, I_F, Ht, -Ht
    Mx[Mi, R], Mx[Mi, P], Mx[Mi, Mi], Mx[Mi, L], Mx[Mi, Ap], Mx[Mi, Am] = -Gtn, -Gtt, Gtt, I_F, -Ht, Ht
    Mx[L, R], Mx[L, P], Mx[L, Mi] = E, -I_F, -I_F
    Mx[Ap, R], Mx[Ap, P], Mx[Ap, Mi] = -Hn.T, -Ht.T, Ht.T
    Mx[Am, R], Mx[Am, P], Mx[Am, Mi] = Hn.T, Ht.T, -Ht.T
    q[R], q[P], q[Mi] = c0[:nN], c0[nN:], -c0[nN:]
    q[Ap], q[Am] = -sG * e, sG * e
    # rounding noise of the condensation (e.g. 1e-18 slips of a symmetric problem) makes
    # Lemke's degenerate pivots fail on a secondary ray: entries this small are zero
    q[np.abs(q) <= Q_NOISE * float(np.max(np.abs(q), initial=0.0))] = 0.0
    layout = dict(sl, scale=sG, normal=active, friction_set=fric, contacts=list(cts.labels),
                  rigid_modes=k, sets=[s[:3] for s in cts.sets])

    t0 = time.perf_counter()
    if n_lcp == 0:
        lcp = LCPResult(method="none", status=SOLVED, x=np.zeros(0), w=np.zeros(0), residual=0.0,
                        message="no contact unknowns: every contact is held by the Dirichlet boundary")
    else:
        lcp = solve_lcp(Mx, q, method=method, tol=lcp_tol, **lcp_options)
        tried = {a[0] for a in lcp.attempts}
        if (method == "auto" and not lcp.success and lcp.status != "infeasible"
                and "lemke" not in tried and n_lcp <= LEMKE_LIMIT):
            # auto skips dense pivoting above its DENSE_LIMIT; the friction LCP (zero λ
            # diagonal) often defeats Newton, so pivot anyway: slow (O(n³)) but robust
            first = lcp
            lcp = solve_lcp(Mx, q, method="lemke", tol=lcp_tol, **lcp_options)
            lcp.attempts = list(first.attempts) + [("lemke", lcp.status, lcp.message)]
    timings["lcp"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    classes = classify(Mx, exact_limit=classify_limit) if n_lcp else None
    timings["classify"] = time.perf_counter() - t0

    result = StaticResult(lcp=lcp, lcp_matrix=Mx, lcp_q=q, layout=layout, classes=classes,
                          friction={s[0]: s[3] for s in cts.sets}, rigid_modes=k, notes=notes,
                          iterations=lcp.iterations, residual=lcp.residual)
    result.guarantees = _guarantees(classes, G[:nN, :nN], cts, active, fric, k, lcp)
    result.timings = timings
    if not lcp.success:
        result.status = lcp.status
        result.message = (f"the static LCP ({n_lcp} unknowns) was not solved: {lcp.message or lcp.status}; "
                          "no contact states reported")
        result.timings["total"] = time.perf_counter() - t_start
        return result

    # ---------------------------------------------------------------- reconstruction
    t0 = time.perf_counter()
    x = lcp.x
    r_n = np.zeros(nc)
    r_t = np.zeros(nc)
    r_n[active] = x[R] / sG
    r_t[fric] = (x[P] - x[Mi]) / sG
    alpha = x[Ap] - x[Am]
    r_vec = np.concatenate([r_n[active], r_t[fric]])
    load_r = b0 + C_f @ r_vec
    u_f = np.zeros(free.size)
    if lu is not None:
        u_f[keep] = lu.solve(load_r[keep])
    u_f += N @ alpha
    u, gap, slip, F, D = _response(model, cts, free, presc, u_f, u_p, r_n, r_t, b0)
    res = K_ff @ u_f - load_r
    result.equilibrium_residual = float(np.max(np.abs(res))) / F if res.size and F > 0 else 0.0
    _held_contacts(cts, gap, slip, r_n, r_t, held_n, held_t, tol, D)
    c0_t = np.zeros(nc)
    c0_t[fric] = c0[nN:]
    # μ = 0 contacts: the load's tangential response at r = 0 (for the direction rule)
    zero_mu = np.flatnonzero(~held_n & ~held_t & (cts.mu == 0))
    if zero_mu.size and lu is not None:
        At0 = A_tf[zero_mu][:, keep]
        c0_t[zero_mu] = At0 @ u0_r + A_tp[zero_mu] @ u_p
    states = _classify_states(r_n, r_t, gap, slip, cts.mu, held_n, held_t, c0_t, tol, F, D, result.notes,
                              cts.labels)
    _store_contacts(result, cts, states, (r_n, r_t, gap, slip, held_n), u, tol, F, D, lcp_tol)
    result.status = SOLVED
    counts = {s: states.count(s) for s in ("stick", "slip+", "slip-", "separated", "grazing") if s in states}
    result.message = (f"{nc} contacts ({', '.join(f'{v} {s}' for s, v in counts.items())}); LCP "
                      f"{n_lcp} unknowns by {lcp.method}, certificate {lcp.residual:.1e}; equilibrium "
                      f"residual {result.equilibrium_residual:.1e}")
    timings["states"] = time.perf_counter() - t0
    timings["total"] = time.perf_counter() - t_start
    return result


# --------------------------------------------------------------------------- states

def _response(model, cts, free, presc, u_f, u_p, r_n, r_t, b0):
    """The full displacement, each contact's gap and slip, and the force and displacement
    scales the classification tolerances are relative to."""
    u = np.zeros(model.n_dofs)
    u[free] = u_f
    u[presc] = u_p
    F = max(float(np.max(np.abs(np.concatenate([r_n, r_t])))) if r_n.size else 0.0,
            float(np.max(np.abs(b0))) if b0.size else 0.0)
    D = float(np.max(np.abs(u))) if u.size else 0.0
    return u, cts.A_n @ u, cts.A_t @ u, F, D


def _held_contacts(cts, gap, slip, r_n, r_t, held_n, held_t, tol, D) -> None:
    """Contacts the Dirichlet boundary holds: a prescribed penetration is an error; on a
    tangentially prescribed contact friction acts on prescribed DOFs only, so r_t (in place)
    is ∓μ r_n when it moves and 0 when it does not."""
    for c in np.flatnonzero(held_n):
        if gap[c] < -tol * D:
            name, i = cts.labels[c]
            raise ProblemError(f"static equilibrium: the prescribed displacements close contact "
                               f"{name!r} column {i} by {-gap[c]:g} (penetration): the load moves "
                               "both sides of a contact held by the Dirichlet boundary into each other")
    tang_held = np.flatnonzero(~held_n & held_t & (cts.mu > 0))
    moving = np.abs(slip[tang_held]) > tol * D
    r_t[tang_held] = np.where(moving, -np.sign(slip[tang_held]) * cts.mu[tang_held] * r_n[tang_held], 0.0)


def _store_contacts(result, cts, states, per_contact, u, tol, F, D, certificate_tol) -> None:
    """Put the classified states, the per-contact arrays (r_n, r_t, gap, slip, held) and the
    tolerances used into ``result``, split into the base and each frictional interface."""
    r_n, r_t, gap, slip, held_n = per_contact
    result.tolerances = {"tol": tol, "force_scale": F, "displacement_scale": D,
                         "contact_force": tol * F, "gap": tol * D, "slip": tol * D,
                         "cone": f"|r_t| >= mu*r_n*(1 - {tol:g}) - {tol * F:.3g}",
                         "lcp_certificate": certificate_tol}
    result.u = u
    for name, a, b, _mu in cts.sets:
        if name == BASE:
            result.states = states[a:b]
            result.r_n, result.r_t, result.gap, result.slip = r_n[a:b], r_t[a:b], gap[a:b], slip[a:b]
            result.held = held_n[a:b].copy()
        else:
            result.interface_states[name] = states[a:b]
            result.interface_r_n[name], result.interface_r_t[name] = r_n[a:b], r_t[a:b]
            result.interface_gap[name], result.interface_slip[name] = gap[a:b], slip[a:b]
            result.interface_held[name] = held_n[a:b].copy()


def _classify_states(r_n, r_t, gap, slip, mu, held_n, held_t, c0_t, tol, F, D, notes, labels) -> list:
    out = []
    f_tol, d_tol = tol * F, tol * D
    for c in range(r_n.size):
        if held_n[c]:
            out.append("stick" if held_t[c] else "separated")
            continue
        if r_n[c] > f_tol:
            moving = abs(slip[c]) > d_tol
            if held_t[c]:  # the boundary prescribes the slip: forced slip, or held (stick)
                out.append(("slip+" if slip[c] > 0 else "slip-") if moving else "stick")
                continue
            if mu[c] == 0.0:
                if moving:
                    s = np.sign(slip[c])
                elif abs(c0_t[c]) > d_tol:
                    s = np.sign(c0_t[c])
                else:
                    s = 1.0
                out.append("slip+" if s > 0 else "slip-")
                continue
            saturated = abs(r_t[c]) >= mu[c] * r_n[c] * (1.0 - tol) - f_tol
            if saturated or moving:
                s = -np.sign(r_t[c]) if r_t[c] != 0 else np.sign(slip[c])
                if s == 0:
                    s = 1.0
                if moving and np.sign(slip[c]) != s:
                    notes.append(f"{labels[c]}: slip {slip[c]:.3g} against the friction direction "
                                 f"(r_t = {r_t[c]:.3g}) within tolerance")
                if moving and not saturated:
                    notes.append(f"{labels[c]}: slip {slip[c]:.3g} inside the cone "
                                 f"(|r_t| = {abs(r_t[c]):.3g} < μ r_n = {mu[c] * r_n[c]:.3g}) within tolerance")
                out.append("slip+" if s > 0 else "slip-")
            else:
                out.append("stick")
        else:
            out.append("separated" if gap[c] > d_tol else "grazing")
    return out


# --------------------------------------------------------------------------- guarantees

def _guarantees(classes, Gnn, cts, active, fric, k, lcp) -> list:
    mus = ", ".join(f"{name}: μ = {mu:g}" for name, _, _, mu in cts.sets)
    nN, nF = active.size, fric.size
    g = [f"Static LCP ({mus}): {nN} normal reactions, {nF} frictional contacts (β⁺, β⁻, λ each)"
         + (f", {k} rigid-body modes held by contact (α⁺, α⁻ each)" if k else "")
         + f" — {nN + 3 * nF + 2 * k} unknowns."]
    if classes is not None:
        g.extend(f"LCP matrix: {s}" for s in classes.guarantees)
    if nF:
        g.append("The friction split makes the LCP matrix neither P nor R0 by construction (zero λ "
                 "diagonal; λ e_λ solves LCP(0, M)): at a contact with r_n = 0 any λ ≥ |u_t| solves, "
                 "and at a sticking contact β⁺ and β⁻ may grow together.  These change neither the "
                 "reactions (r_n, r_t) nor the displacements, so 'not P' / 'not R0' above do not by "
                 "themselves mean that the equilibrium is non-unique; uniqueness of the reactions at "
                 "this μ is not decided by these classes.")
    if k:
        g.append("Rigid-body modes held by contact add a skew block (α⁺, α⁻ with zero diagonal): "
                 "existence then also needs the contacts to be able to carry the load of each "
                 "floating component (e.g. no uplift of a free block).")
    if nN and k == 0:
        try:
            np.linalg.cholesky(Gnn / max(np.abs(Gnn).max(), 1e-300))
            g.append("Normal compliance G_nn is SPD (Cholesky), hence P: the frictionless problem "
                     "(μ = 0) has exactly one equilibrium for every load.")
        except np.linalg.LinAlgError:
            g.append("Normal compliance G_nn is not numerically positive definite: even the "
                     "frictionless problem may have several equilibria.")
    if lcp.success:
        g.append(f"For this load an equilibrium exists: the LCP solution passed its certificate "
                 f"(residual {lcp.residual:.1e}).")
    else:
        g.append(f"For this load no equilibrium was certified (LCP status {lcp.status!r}).")
    return g


__all__ = ["StaticResult", "static_equilibrium", "prescribed_displacements", "body_force",
           "TOL", "MAX_CONTACTS", "AUTO_CONDENSED_LIMIT"]
