"""From contact states to the MEiCP's maps (docs/design.md §7.1–§7.2): which DOFs stay, which pair up.

For every contact (a base node, or a frictional interface pair in relative coordinates
``d = u_upper − u_lower``) the state decides its two DOFs (t = x, n = y):

| state      | v (column of Q)                        | row of P                       | role          |
|------------|----------------------------------------|--------------------------------|---------------|
| separated  | v_t, v_n free (unit columns)           | unit rows (w = 0)              | free          |
| stick      | v_t = v_n = 0 (no column)              | —                              | removed       |
| slip s     | v_n = 0; x = s·v_t ≥ 0 (column s·e_t)  | s·e_tᵀ + μ·e_nᵀ  (y ≥ 0)       | one pair      |
| grazing, c | x_n = v_n ≥ 0 (column e_n), and per the | e_nᵀ (y_n = w_n ≥ 0), and for  | one or two    |
|            | tangential case c: stick (no column) or | slip: s·e_tᵀ + μ·e_nᵀ          | pairs         |
|            | slip s (column s·e_t)                   |                                |               |

Dirichlet DOFs are removed; every other DOF is free with a unit column and row.  The
frictional interfaces enter through the change of variables ``u = T u'`` with
``u_upper = u'_lower + d``; the maps are then ``Q̃ = T Q`` and ``P̃ = P Tᵀ`` in natural
numbering, and the pencil is ``A = −P̃ K Q̃``, ``B = P̃ M Q̃`` (B is diagonal for a base
contact with lumped M, and nonsymmetric once an interface couples u_lower and d).

Retained DOFs are ordered by their natural DOF number, so a distributed layout that
follows the lattice's row bands keeps each reduced DOF on the rank of its node.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from ..core.errors import ProblemError
from ..scene import SOLVE, STATES

#: how many grazing contacts' tangential cases (3 each) may be enumerated
MAX_GRAZING = 6


@dataclass(frozen=True)
class ContactSet:
    """One contact line: the base (``name = "base"``) or a frictional interface (the lower
    layer's name).  ``lower``: node of the lower side (None for the base); ``upper``: the
    node that carries the contact DOFs (the base's contact node, or the upper node whose
    DOFs become the relative displacement d)."""

    name: str
    upper: np.ndarray
    lower: np.ndarray | None
    friction: float
    states: tuple


@dataclass
class ReducedSystem:
    """The maps of one assignment of states.  Q (n × r) and P (r × n) in natural numbering,
    ``retained`` the natural DOF of each reduced DOF (sorted), ``J`` the complementarity
    positions, ``pair_of`` for each J position: (contact set name, contact index)."""

    Q: sp.csr_matrix
    P: sp.csr_matrix
    P_friction: sp.csr_matrix  # the part of P proportional to μ (for μ as the eigenvalue)
    retained: np.ndarray
    J: np.ndarray
    pair_of: list = field(default_factory=list)
    grazing_case: tuple = ()


def contact_sets(scene, model, states_override: dict | None = None) -> list[ContactSet]:
    """The scene's contact lines with their states resolved (``states_override``: name →
    list of states, e.g. from the static equilibrium).  Raises ProblemError for a state list
    of the wrong length or an unresolved ``"solve"``."""
    sets = []
    override = states_override or {}
    if model.boundary.bottom == "contact":
        nodes = model.contact_nodes()
        states = _resolve(override.get("base", scene.contact.states), nodes.size, "contact.states")
        sets.append(ContactSet("base", nodes, None, float(scene.contact.friction), states))
    for k, itf in enumerate(scene.interfaces):
        if itf.kind != "frictional":
            continue
        lower, upper = model.interface_node_pairs(itf.index)
        states = _resolve(override.get(itf.below, itf.states), upper.size, f"interfaces[{k}].states")
        sets.append(ContactSet(itf.below, upper, lower, float(itf.friction), states))
    return sets


def _resolve(states, count: int, key: str) -> tuple:
    if states == SOLVE or states is None:
        raise ProblemError(f"{key} = \"solve\" needs the static equilibrium first")
    if isinstance(states, str):
        states = (states,) * count
    states = tuple(states)
    if len(states) != count:
        raise ProblemError(f"{key} has {len(states)} states for {count} contact nodes")
    bad = [s for s in states if s not in STATES]
    if bad:
        raise ProblemError(f"{key}: unknown state {bad[0]!r} (expected one of {', '.join(STATES)})")
    return states


def grazing_cases(sets: list[ContactSet]):
    """Every assignment of tangential cases to the grazing contacts: tuples of
    (set index, contact index, case) with case in stick | slip+ | slip-."""
    grazing = [(s, i) for s, cs in enumerate(sets) for i, st in enumerate(cs.states) if st == "grazing"]
    if len(grazing) > MAX_GRAZING:
        raise ProblemError(f"{len(grazing)} grazing contacts: their 3^{len(grazing)} tangential cases are "
                           f"too many to enumerate (limit {MAX_GRAZING}); prescribe their states")
    for cases in itertools.product(("stick", "slip+", "slip-"), repeat=len(grazing)):
        yield tuple((s, i, c) for (s, i), c in zip(grazing, cases))


def reduced_system(model, sets: list[ContactSet], grazing_case: tuple = ()) -> ReducedSystem:
    """The maps Q̃, P̃ for the states of ``sets`` (grazing contacts resolved by
    ``grazing_case`` from :func:`grazing_cases`)."""
    n = model.n_dofs
    keep = np.ones(n, dtype=bool)
    keep[model.constrained_dofs()] = False
    # per DOF: column sign (0 removed / ±1), complementarity flag, row: extra μ·e_n entry
    col_sign = keep.astype(np.int8)
    comp = np.zeros(n, dtype=bool)
    row_extra = {}  # t DOF -> (n DOF, μ)
    pair_of = {}
    case_of = {(s, i): c for s, i, c in grazing_case}
    for s_idx, cs in enumerate(sets):
        for i, (node, state) in enumerate(zip(cs.upper, cs.states)):
            t, nn = 2 * node, 2 * node + 1
            if not keep[t]:  # x held by a fixed side: it cannot slip
                state = {"slip+": "stick", "slip-": "stick"}.get(state, state)
            if not (keep[t] or keep[nn]):
                continue  # held in both directions by the boundary
            tangential = state
            if state == "grazing":
                tangential = case_of.get((s_idx, i))
                if tangential is None:
                    raise ProblemError("grazing contacts need a tangential case (use grazing_cases)")
                comp[nn] = True  # x_n = v_n ≥ 0 ⊥ w_n ≥ 0
                pair_of[nn] = (cs.name, i, "n")
            if state == "separated":
                continue
            if state == "stick" or tangential == "stick":
                col_sign[t] = 0
                if state == "stick":
                    col_sign[nn] = 0
                continue
            if not keep[nn]:  # y held by the boundary: slip on a held normal is plain free x
                continue
            # slip in direction s (also the tangential case of a grazing contact)
            sign = 1 if tangential == "slip+" else -1
            col_sign[t] = sign
            comp[t] = True
            pair_of[t] = (cs.name, i, "t")
            row_extra[t] = (nn, cs.friction)
            if state != "grazing":
                col_sign[nn] = 0
    retained = np.flatnonzero(col_sign != 0)
    r = retained.size
    pos = np.full(n, -1, dtype=np.int64)
    pos[retained] = np.arange(r)
    Q = sp.csr_matrix((col_sign[retained].astype(float), (retained, np.arange(r))), shape=(n, r))
    # P: row k = sign·e_dof (+ μ e_n for slip rows); for non-slip DOFs sign = 1
    P_rows = [np.arange(r)]
    P_cols = [retained]
    P_vals = [np.where(comp[retained] & np.isin(retained, list(row_extra)), col_sign[retained], 1.0)]
    fr_rows, fr_cols, fr_vals = [], [], []
    for t, (nn, mu) in row_extra.items():
        fr_rows.append(pos[t])
        fr_cols.append(nn)
        fr_vals.append(1.0)
        P_rows.append(np.array([pos[t]]))
        P_cols.append(np.array([nn]))
        P_vals.append(np.array([mu]))
    P = sp.csr_matrix((np.concatenate(P_vals), (np.concatenate(P_rows), np.concatenate(P_cols))), shape=(r, n))
    P_friction = sp.csr_matrix((np.array(fr_vals, dtype=float), (np.array(fr_rows, dtype=np.int64),
                                np.array(fr_cols, dtype=np.int64))), shape=(r, n))
    T = interface_transform(model, sets)
    if T is not None:
        Q = (T @ Q).tocsr()
        P = (P @ T.T).tocsr()
        P_friction = (P_friction @ T.T).tocsr()
    J = np.flatnonzero(comp[retained])
    return ReducedSystem(Q, P, P_friction, retained, J, [pair_of[d] for d in retained[J]], tuple(grazing_case))


def interface_transform(model, sets: list[ContactSet]) -> sp.csr_matrix | None:
    """``T`` with ``u = T u'``: the upper node of each frictional pair carries
    ``d = u_upper − u_lower`` in u', so ``u_upper = u'_upper + u'_lower``.  None without
    frictional interfaces."""
    pairs = [(cs.upper, cs.lower) for cs in sets if cs.lower is not None]
    if not pairs:
        return None
    n = model.n_dofs
    upper = np.concatenate([p[0] for p in pairs])
    lower = np.concatenate([p[1] for p in pairs])
    rows = np.concatenate([2 * upper, 2 * upper + 1])
    cols = np.concatenate([2 * lower, 2 * lower + 1])
    E = sp.csr_matrix((np.ones(rows.size), (rows, cols)), shape=(n, n))
    return (sp.identity(n, format="csr") + E).tocsr()


def friction_part(red: ReducedSystem, sets: list[ContactSet]) -> sp.csr_matrix:
    """μ·P₁: the part of P̃ proportional to friction, with each contact line's own μ
    (``P̃ − friction_part`` is P̃ at μ = 0)."""
    mus = np.zeros(red.P.shape[0])
    for k, (name, _, kind) in enumerate(red.pair_of):
        if kind == "t":
            mus[red.J[k]] = next(cs.friction for cs in sets if cs.name == name)
    return (sp.diags(mus) @ red.P_friction).tocsr()
