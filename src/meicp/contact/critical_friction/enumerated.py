"""The enumerated path of the critical friction: the σ = 0 EiCP in μ,
``(μB′ − A′)x = y`` with ``A′ = −P̃₀KQ̃`` and ``B′ = P̃₁KQ̃`` (the friction-free and the
unit-friction rows of :class:`~meicp.contact.maps.ReducedSystem`), condensed exactly onto the
rows that carry μ and every support enumerated; the μ found is lifted back to the whole
reduced lattice and certified there (docs/critical-friction.md)."""

from __future__ import annotations

import logging

import numpy as np
import scipy.sparse.linalg as spl
from scipy.optimize import linprog

from ...core.errors import ConvergenceError, ProblemError
from ...core import limits
from ...eicp.problem import EiCPProblem, certify_pair
from ...eicp.solve import solve_eicp
from ...petsc.pencil import reduced_pencil

log = logging.getLogger("meicp")

#: the μ-independent block −A′ (and its Schur complement) counts as singular beyond this
#: condition number: a motion of (near) zero stiffness, μ_c undefined
CRITICAL_COND = 1e12


def friction_pencil(K, red):
    """``A′ = −P̃₀ K Q̃``, ``B′ = P̃₁ K Q̃`` (sparse CSR) of the σ = 0 EiCP in μ, one μ for
    every contact (``red``: the :class:`~meicp.contact.maps.ReducedSystem`)."""
    return reduced_pencil(K, K, red.P0, red.Q, red.retained, P_B=red.P1)


def condense_in_mu(A1, B1, J):
    """Eliminate the rows/columns E where w = 0 and B′ = 0 (no μ in the equation):
    ``x_E = −A′_EE⁻¹ A′_EC x_C``.  Returns ``(Ac, Bc, Jc, lift, null)``: Jc the positions of
    J in C, ``lift(x_C)`` the whole reduced x, ``null`` an orthonormal basis (columns) of the
    null space of −Ac (usually empty).  ProblemError if ``−A′_EE`` is singular: then a
    motion with x_C = 0 costs no energy, a σ = 0 motion at every μ."""
    r = A1.shape[0]
    in_j = np.zeros(r, dtype=bool)
    in_j[J] = True
    with_mu = np.diff(B1.indptr) > 0           # rows of B′ with a stored entry
    keep = in_j | with_mu                       # C: J and any free row that carries μ
    C, E = np.flatnonzero(keep), np.flatnonzero(~keep)
    Jc = np.flatnonzero(in_j[C])
    A_CC, B_CC = A1[C][:, C].toarray(), B1[C][:, C].toarray()
    if E.size:
        A_EE = A1[E][:, E].tocsc()
        singular = f"the μ-independent block −A′_EE ({E.size} DOFs) is singular"
        try:
            lu = spl.splu(A_EE)
        except RuntimeError as exc:  # "Factor is exactly singular"
            raise ProblemError(singular_message(singular)) from exc
        inv = spl.LinearOperator(A_EE.shape, matvec=lu.solve, rmatvec=lambda v: lu.solve(v, trans="T"),
                                 dtype=float)
        cond = spl.norm(A_EE, 1) * spl.onenormest(inv)
        if not np.isfinite(cond) or cond > CRITICAL_COND:
            raise ProblemError(singular_message(f"{singular} (condition ≈ {cond:.1e})"))
        X_EC = lu.solve(A1[E][:, C].toarray())  # A′_EE⁻¹ A′_EC
        Ac = A_CC - A1[C][:, E] @ X_EC
        Bc = B_CC - B1[C][:, E] @ X_EC
    else:
        X_EC = np.zeros((0, C.size))
        Ac, Bc = A_CC, B_CC
    Ac, Bc = np.asarray(Ac), np.asarray(Bc)
    # −Ac is the Schur complement of −A′ = Q̃ᵀKQ̃: symmetric positive semidefinite, definite
    # unless a motion of zero stiffness is left (e.g. a layer sliding as a whole)
    ev, V = np.linalg.eigh(-0.5 * (Ac + Ac.T))
    null = V[:, ev <= max(ev[-1], 0.0) / CRITICAL_COND]

    def lift(xc):
        x = np.zeros(r)
        x[C] = xc
        x[E] = -X_EC @ xc
        return x

    return Ac, Bc, Jc, lift, null


def singular_message(what: str) -> str:
    return (f"critical_friction: {what}: a motion of zero stiffness exists with the sliding contacts "
            "held (a floating body, or a block free to slide as a whole), a σ = 0 motion at every μ; "
            "μ_c is undefined — hold the body (boundary or sticking contacts)")


def _sign_feasible(N: np.ndarray) -> bool:
    """Whether some nonzero x = N c has x ≥ 0 (LP: N c ≥ 0, Σ(N c) = 1), or x = 0 on these
    rows for some c ≠ 0 (N rank deficient)."""
    if np.linalg.matrix_rank(N) < N.shape[1]:
        return True
    res = linprog(np.zeros(N.shape[1]), A_ub=-N, b_ub=np.zeros(N.shape[0]), A_eq=N.sum(axis=0)[None, :],
                  b_eq=[1.0], bounds=[(None, None)] * N.shape[1], method="highs")
    return res.status == 0


def smallest_mu(A1, B1, J, mu_max):
    """Smallest μ in [0, mu_max] of ``(μB′ − A′)x = y`` by enumerating the condensed EiCP
    in ν = 1/μ, certified on the whole reduced pencil.  Returns (μ, singular): ``singular``
    when −Ac has a null space that is not sign-feasible (the enumeration met singular
    pencils; the caller must cross-check)."""
    Ac, Bc, Jc, lift, null = condense_in_mu(A1, B1, J)
    if null.shape[1] and _sign_feasible(null[Jc]):
        raise ProblemError(singular_message(f"the condensed block −Ac (order {Ac.shape[0]}) is singular and its "
                                            "null space holds a motion with x_J ≥ 0"))
    if Ac.shape[0] > Jc.size:
        log.info("critical_friction: %d free rows carry μ and stay in the condensed EiCP", Ac.shape[0] - Jc.size)
    # μ > 0 ⇔ ν = 1/μ > 0.  μ = 0 is never a solution: −Ac is positive semidefinite and
    # x_J ≥ 0 with xᵀ(−Ac)x = xᵀy = 0 only for x in its null space, excluded just above
    # max_j: the caller sized this enumeration (enumeration_is_small), not the by-name budget
    r = solve_eicp(-Bc, -Ac, J=Jc, method="enumerate", lam_min=1.0 / mu_max if mu_max > 0 else np.inf,
                   tol=1e-9, max_j=limits.EICP_MAX_J)
    nus = [s for s in r.solutions if s.lam > 0 and 1.0 / s.lam <= mu_max]
    if not nus:
        return np.inf, bool(null.shape[1])
    sol = max(nus, key=lambda s: s.lam)
    mu = 1.0 / sol.lam
    full = certify_pair(EiCPProblem.from_data(A1, B1, J), mu, lift(sol.x))
    if full.residual > 1e-9:
        raise ConvergenceError(f"critical_friction: μ_c = {mu:.10g} of the condensed EiCP fails the certificate on "
                               f"the whole reduced lattice (residual {full.residual:.1e})", r)
    return mu, bool(null.shape[1])
