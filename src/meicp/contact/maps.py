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
frictional interfaces enter through the change of variables ``u = T u'`` of
:func:`interface_transform` (per pair: the centre of mass and the relative displacement d);
the maps are then ``Q̃ = T Q`` and ``P̃ = P Tᵀ`` in natural numbering, and the pencil is
``A = −P̃ K Q̃``, ``B = P̃ M Q̃``.  With lumped M, B is diagonal and positive for a base contact
and for an interface alike (``TᵀMT`` is diagonal), except where a node belongs to two pairs
(a one-row layer between two interfaces): there ``u_upper = u_lower + d`` and M couples them.

μ stays data: :class:`ReducedSystem` keeps the friction-free rows P̃₀, the unit-friction rows
P̃₁ (one ``e_nᵀ`` per slip row) and the μ of each complementarity row (the only rows friction
enters), and forms ``P̃ = P̃₀ + diag(μ)·P̃₁`` in one place (:meth:`ReducedSystem.rows_at`);
the critical friction (μ as the eigenvalue), the friction range (μ scaled) and the
condensation's friction part read P̃₀, P̃₁ and μ directly.

Retained DOFs are ordered by their natural DOF number, so a distributed layout that
follows the lattice's row bands keeps each reduced DOF on the rank of its node.
"""

from __future__ import annotations

import dataclasses
import itertools
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from ..core import limits
from ..core.errors import ProblemError
from .lines import ContactLine, ContactState

#: the tangential cases of a grazing contact
TANGENTIAL_CASES = (ContactState.STICK, ContactState.SLIP_PLUS, ContactState.SLIP_MINUS)


@dataclass
class ReducedSystem:
    """The maps of one assignment of states, μ kept as data.  Q (n × r) and the rows
    ``P̃ = P₀ + diag(μ)·P₁`` (r × n) in natural numbering: ``P0`` the friction-free rows (unit
    rows, ``s·e_tᵀ`` for a slip DOF), ``P1`` the unit-friction rows (``e_nᵀ`` in the row of each
    slip DOF, zero rows elsewhere), ``mu`` the μ of the row of each J position (its contact
    line's for a slip row, 0 for a grazing contact's normal row; every other row has none, so
    the vector over all r rows is only formed when P̃ is).  ``retained`` the natural DOF of each
    reduced DOF (sorted), ``J`` the complementarity positions, ``pair_of`` for each J position:
    (contact line name, contact index, ``"t"`` or ``"n"``)."""

    Q: sp.csr_matrix
    P0: sp.csr_matrix
    P1: sp.csr_matrix
    mu: np.ndarray
    retained: np.ndarray
    J: np.ndarray
    pair_of: list = field(default_factory=list)
    grazing_case: tuple = ()

    @property
    def P(self) -> sp.csr_matrix:
        """P̃ with each contact line's own μ (formed when asked: the pencil reads it once)."""
        return self.rows_at()

    def friction_rows(self, mu=None) -> sp.csr_matrix:
        """``diag(μ)·P₁``: the part of P̃ proportional to friction (``mu``: None for each line's
        own μ, a number for every contact at that μ)."""
        return (sp.diags(self._row_mu(mu)) @ self.P1).tocsr()

    def rows_at(self, mu=None) -> sp.csr_matrix:
        """``P̃ = P₀ + diag(μ)·P₁``, the one place it is formed (``mu`` as for
        :meth:`friction_rows`)."""
        return (self.P0 + self.friction_rows(mu)).tocsr()

    def with_friction(self, mu: float) -> "ReducedSystem":
        """These maps with every contact at friction ``mu`` (the same states and DOFs)."""
        return dataclasses.replace(self, mu=self._row_mu(mu)[self.J])

    def _row_mu(self, mu) -> np.ndarray:
        """μ of every row of P̃: each line's own (``mu`` None), or ``mu`` in every slip row."""
        rows = np.zeros(self.P0.shape[0])
        if mu is None:
            rows[self.J] = self.mu
        else:
            rows[np.diff(self.P1.indptr) > 0] = float(mu)
        return rows


def grazing_cases(lines: list[ContactLine]):
    """Every assignment of tangential cases to the grazing contacts: tuples of
    (line index, contact index, case) with case a :data:`TANGENTIAL_CASES` state."""
    grazing = [(s, i) for s, line in enumerate(lines) for i, st in enumerate(line.states)
               if st is ContactState.GRAZING]
    if len(grazing) > limits.MAX_GRAZING:
        raise ProblemError(f"{len(grazing)} grazing contacts: their 3^{len(grazing)} tangential cases are "
                           f"too many to enumerate (limit {limits.MAX_GRAZING}); prescribe their states")
    for cases in itertools.product(TANGENTIAL_CASES, repeat=len(grazing)):
        yield tuple((s, i, c) for (s, i), c in zip(grazing, cases))


def reduced_system(model, lines: list[ContactLine], grazing_case: tuple = ()) -> ReducedSystem:
    """The maps Q̃, P̃₀, P̃₁ and μ for the states of ``lines`` (grazing contacts resolved by
    ``grazing_case`` from :func:`grazing_cases`)."""
    STICK, SEPARATED, GRAZING = ContactState.STICK, ContactState.SEPARATED, ContactState.GRAZING
    n = model.n_dofs
    keep = np.ones(n, dtype=bool)
    keep[model.constrained_dofs()] = False
    T, keep = interface_transform(model, lines, keep)
    # per DOF: column sign (0 removed / ±1), complementarity flag, row: the friction entry μ·e_n
    col_sign = keep.astype(np.int8)
    comp = np.zeros(n, dtype=bool)
    row_extra = {}  # t DOF -> (n DOF, μ)
    pair_of = {}
    case_of = {(s, i): ContactState(c) for s, i, c in grazing_case}
    for s_idx, line in enumerate(lines):
        for i, (node, state) in enumerate(zip(line.upper, line.states)):
            t, nn = 2 * node, 2 * node + 1
            if not keep[t] and state.slip_sign:  # x held by a fixed side: it cannot slip
                state = STICK
            if not (keep[t] or keep[nn]):
                continue  # held in both directions by the boundary
            tangential = state
            if state is GRAZING:
                tangential = case_of.get((s_idx, i))
                if tangential is None:
                    raise ProblemError("grazing contacts need a tangential case (use grazing_cases)")
                comp[nn] = True  # x_n = v_n ≥ 0 ⊥ w_n ≥ 0
                pair_of[nn] = (line.name, i, "n")
            if state is SEPARATED:
                continue
            if state is STICK or tangential is STICK:
                col_sign[t] = 0
                if state is STICK:
                    col_sign[nn] = 0
                continue
            if not keep[nn]:  # y held by the boundary: slip on a held normal is plain free x
                continue
            # slip in direction s (also the tangential case of a grazing contact)
            col_sign[t] = tangential.slip_sign
            comp[t] = True
            pair_of[t] = (line.name, i, "t")
            row_extra[t] = (nn, line.friction)
            if state is not GRAZING:
                col_sign[nn] = 0
    retained = np.flatnonzero(col_sign != 0)
    r = retained.size
    pos = np.full(n, -1, dtype=np.int64)
    pos[retained] = np.arange(r)
    Q = sp.csr_matrix((col_sign[retained].astype(float), (retained, np.arange(r))), shape=(n, r))
    # P₀: row k = sign·e_dof (the slip direction for slip rows, 1 otherwise); P₁: e_n in slip rows
    P0 = sp.csr_matrix((np.where(comp[retained] & np.isin(retained, list(row_extra)), col_sign[retained], 1.0),
                        (np.arange(r), retained)), shape=(r, n))
    slip = np.array(list(row_extra), dtype=np.int64)
    normal = np.array([nn for nn, _ in row_extra.values()], dtype=np.int64)
    P1 = sp.csr_matrix((np.ones(slip.size), (pos[slip], normal)), shape=(r, n))
    row_mu = np.zeros(r)
    row_mu[pos[slip]] = [m for _, m in row_extra.values()]
    if T is not None:
        Q = (T @ Q).tocsr()
        P0 = (P0 @ T.T).tocsr()
        P1 = (P1 @ T.T).tocsr()
    J = np.flatnonzero(comp[retained])
    return ReducedSystem(Q, P0, P1, row_mu[J], retained, J, [pair_of[d] for d in retained[J]], tuple(grazing_case))


def interface_transform(model, lines: list[ContactLine], keep: np.ndarray) -> tuple[sp.csr_matrix | None, np.ndarray]:
    """``(T, kept)``: the change of variables ``u = T u'`` of the frictional interfaces and which
    slots of u' stay (``keep``, natural numbering, marks the DOFs no boundary holds).  None and
    ``keep`` without frictional interfaces.

    Each pair carries its relative displacement ``d = u_upper − u_lower`` in the upper node's
    slot, so the contact algebra is the base's.  The lower node's slot carries, per component,

    - the centre of mass ``c = (m_l u_l + m_u u_u)/m`` (``m = m_l + m_u``, lumped) when both
      DOFs are free: ``u_l = c − (m_u/m) d``, ``u_u = c + (m_l/m) d``, and ``TᵀMT`` is
      ``diag(m, m_l m_u/m)`` — B stays diagonal;
    - nothing when the lower DOF is held (``d = u_u``), and when only the upper DOF is held
      ``d = −u_l`` takes the upper slot and the lower slot is dropped;
    - ``u_lower`` itself (``u_upper = u_lower + d``, the inverse of ``u' = (I − E) u``) when a
      node of the pair belongs to another contact too — a one-row layer between two frictional
      interfaces, or the base's contact node under a one-row layer.  Per-pair centres of mass
      do not compose there: the mass couples ``u_lower`` and ``d`` and B is not diagonal (the
      Rayleigh bound and the σ-windows then check sym(B) instead of relying on it).

    Only ``T⁻¹``'s rows for the d slots matter to the contact laws (``e_uᵀ − e_lᵀ``): with them
    ``P̃ = P Tᵀ`` reads the interface reaction ``r`` off ``w = Cᵀ r`` exactly as for the base.
    """
    pairs = [(line.upper, line.lower) for line in lines if line.lower is not None]
    if not pairs:
        return None, keep
    n = model.n_dofs
    upper = np.concatenate([p[0] for p in pairs]).astype(np.int64)
    lower = np.concatenate([p[1] for p in pairs]).astype(np.int64)
    uses = np.bincount(np.concatenate([upper, lower] + [line.upper for line in lines if line.lower is None]),
                       minlength=model.n_nodes)
    own = (uses[upper] == 1) & (uses[lower] == 1)  # a pair no other contact touches
    mass = model.mass()
    kept = keep.copy()
    diag = np.ones(n)
    rows, cols, vals = [], [], []  # off-diagonal entries of T
    coupled_u, coupled_l = [], []
    for comp in (0, 1):
        du, dl = 2 * upper + comp, 2 * lower + comp
        both = keep[du] & keep[dl]
        com = own & both
        ml, mu_ = mass[lower[com]], mass[upper[com]]
        # u_l = c − (m_u/s) d', u_u = c + (m_l/s) d' with s the power of 2 nearest m = m_l + m_u:
        # the slot carries d' = (s/m)·d, a positive multiple of d (the contact laws do not see
        # it), and cᵀMd' = (−m_l·m_u + m_u·m_l)/s is exactly 0 in floating point, so B's
        # off-diagonal entries vanish exactly, not to rounding
        s = np.exp2(np.round(np.log2(ml + mu_)))
        rows += [du[com], dl[com]]
        cols += [dl[com], du[com]]
        vals += [np.ones(com.sum()), -mu_ / s]
        diag[du[com]] = ml / s
        upper_held = keep[dl] & ~keep[du]
        if np.any(upper_held & ~own):
            raise ProblemError("a frictional interface node held by the boundary while its partner also "
                               "touches another contact (a one-row layer between two contacts with a fixed "
                               "side): this change of variables cannot express it")
        # u_u = 0: d = −u_l takes the upper slot, the lower slot goes
        h = upper_held
        rows.append(dl[h])
        cols.append(du[h])
        vals.append(-np.ones(h.sum()))
        diag[du[h]] = 0.0
        kept[du[h]], kept[dl[h]] = True, False
        chain = ~own & both
        coupled_u.append(du[chain])
        coupled_l.append(dl[chain])
    T = (sp.diags(diag) + sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                                         shape=(n, n))).tocsr()
    cu, cl = np.concatenate(coupled_u), np.concatenate(coupled_l)
    if cu.size:
        # u' = (I − E) u on these pairs: T = (I − E)⁻¹ = I + E + E² + … (E nilpotent: a chain
        # of interfaces through one-row layers)
        E = sp.csr_matrix((np.ones(cu.size), (cu, cl)), shape=(n, n))
        term, series = E, sp.identity(n, format="csr") + E
        while (term := (term @ E).tocsr()).nnz:
            series = series + term
        T = (T @ series).tocsr()
    T.eliminate_zeros()
    return T.tocsr(), kept
