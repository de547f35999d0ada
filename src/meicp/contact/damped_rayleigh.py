"""The damped Rayleigh bound: a proof at any size that the quadratic MEiCP
``y = (λ²B + λD − A)x`` has no real λ ≥ 0 (docs/damping.md, "damped divergence at scale").

Complementarity gives ``xᵀy = 0``, so every solution has ``λ²·xᵀBx + λ·xᵀDx − xᵀAx = 0``: no
solution with λ ≥ 0 exists when ``λ²·sym(B) + λ·sym(D) − sym(A) ≻ 0`` for every λ ≥ 0.  The
undamped bound (sym(A) ≺ 0) does not carry over as it stands, since the friction rows of
P̃ make sym(D) indefinite although C ⪰ 0 (issue 31).  Split them off:
``D = P̃CQ̃ = Q̃ᵀCQ̃ + F`` with ``F = diag(μ)P̃₁CQ̃`` (P̃₀ = Q̃ᵀ), where ``Q̃ᵀCQ̃ ⪰ 0``.  With B = diag(b)
positive and ν ≥ the largest Gershgorin radius of ``diag(b)^-½·sym(F)·diag(b)^-½`` (a pass over
the |J| friction rows, no factorisation; plus a rounding slack for Q̃ᵀCQ̃),
``sym(D) ⪰ −ν·B`` and, for every λ ≥ 0,

    λ²B + λ·sym(D) − sym(A) ⪰ (λ² − νλ)·B − sym(A) ⪰ −(ν²/4)·B − sym(A),

so the undamped Rayleigh bound at τ = −ν²/4 (:func:`~.rayleigh.rayleigh_bound`, one LDLᵀ
inertia with its rounding margin) proves it.  It needs B diagonal (a base contact, an
interface in centre-of-mass coordinates); otherwise it is not tried.  Collective.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..lattice.assembly import mass_matrix_scipy
from .maps import reduced_system
from .problem import pencil_of
from .rayleigh import pencil_bound

#: the rounding slack on Q̃ᵀCQ̃ ⪰ 0, in units of eps·‖Q̃‖₁‖Q̃‖_∞‖C‖₁/min(b)
SLACK = 64
#: largest_proved: while nothing above 0 is proved, each step divides its upper end by
#: DESCENT, down to SMALLEST·upper (then 0 is returned: 7 steps)
DESCENT = 8
SMALLEST = 1e-6


def friction_shift(maps, C: sp.spmatrix, M: sp.spmatrix) -> tuple[float | None, str]:
    """``(ν, why)`` with ``sym(D) ⪰ −ν·B`` (module docstring), or ``(None, why not)`` when B is
    not diagonal or P̃₀ is not Q̃ᵀ.  SciPy, every rank alike."""
    b, why = diagonal_mass(maps, M)
    if b is None:
        return None, why
    gershgorin, _ = friction_discs(maps, C, b)
    slack = congruence_slack(maps, C, b)
    return (gershgorin + slack) * (1 + 1e-12), (f"sym(D) ⪰ −ν·B with ν = {gershgorin + slack:.6g} (Gershgorin's "
                                                 "discs of the friction rows' part, scaled by B; Q̃ᵀCQ̃ ⪰ 0)")


def congruence_slack(maps, C: sp.spmatrix, b: np.ndarray) -> float:
    """s with ``Q̃ᵀCQ̃ + s·diag(b) ⪰ 0`` as computed: the rounding of the congruence of C ⪰ 0,
    :data:`SLACK`·eps·‖Q̃‖₁‖Q̃‖_∞‖C‖₁/min(b)."""
    Q = sp.csr_matrix(maps.Q)
    norm_Q = float(abs(Q).sum(axis=0).max()) * float(abs(Q).sum(axis=1).max())
    return SLACK * np.finfo(float).eps * norm_Q * float(abs(C).sum(axis=0).max()) / float(b.min())


def diagonal_mass(maps, M: sp.spmatrix) -> tuple[np.ndarray | None, str]:
    """``(b, "")`` with B = P̃MQ̃ = diag(b), b > 0, when the damping splits as a congruence plus
    friction rows (P̃₀ = Q̃ᵀ) and B is diagonal positive; else ``(None, why not)``."""
    Q = sp.csr_matrix(maps.Q)
    if Q.shape[1] == 0:
        return None, "no retained DOF"
    if abs(sp.csr_matrix(maps.P0) - Q.T).max() != 0:
        return None, "P̃₀ ≠ Q̃ᵀ (the damping's friction-free part is not a congruence)"
    B = (maps.P @ M @ Q).tocsr()
    b = B.diagonal()
    if (B - sp.diags(b)).count_nonzero() or not np.all(b > 0):
        return None, "B is not diagonal with positive entries"
    return b, ""


def friction_discs(maps, C: sp.spmatrix, b: np.ndarray) -> tuple[float, float]:
    """The largest Gershgorin radii of the symmetric and the skew part of
    ``diag(b)^-½·F·diag(b)^-½``, ``F = diag(μ)P̃₁CQ̃`` the friction rows' part of ``P̃CQ̃``
    (a pass over the |J| friction rows); the caller adds the rounding."""
    F = (maps.friction_rows() @ C @ sp.csr_matrix(maps.Q)).tocsr()
    scale = sp.diags(1.0 / np.sqrt(b))
    out = []
    for part in (0.5 * (F + F.T), 0.5 * (F - F.T)):
        W = (scale @ part @ scale).tocsr()
        out.append(float(np.asarray(abs(W).sum(axis=1)).max()) if W.nnz else 0.0)
    return out[0], out[1]


def divergence_free_up_to(lattice, lines, case, upper: float, *, rel: float = 1e-4, comm=None) -> float:
    """The largest m ≤ ``upper`` (to ``rel``) with no damped divergence mode, any λ ≥ 0, at any
    μ in [0, m], every contact at the same μ, for one grazing ``case``; 0 when nothing is
    proved.  ``f(μ) = sym(A(μ)) + (ν(μ)²/4)·B`` is convex in μ — A(μ) affine, ν(μ) = μ·ν₁ + s
    (the friction rows' part scales with μ, the slack does not) and B ⪰ 0 — so f(0) ≺ 0 and
    f(m) ≺ 0 (the bound at both ends) give f ≺ 0 on [0, m].  Bisection on m.  SciPy lattices
    (the critical friction's), every rank alike; the inertias factored over ``comm`` (None:
    this process alone: at 10⁶ DOFs 16.5 s a step, docs/benchmarks-notes.md, "floor inertias")."""
    red = reduced_system(lattice.model, lines, case)
    C, M = lattice.damping(), mass_matrix_scipy(lattice.model)  # μ changes neither: assembled once

    def proved(mu: float) -> bool:
        pen = pencil_of(lattice, lines, case, maps=red.with_friction(mu))
        return pen.A is None or damped_rayleigh_bound(pen, C, M, comm=comm)[0]

    if not np.isfinite(upper) or not proved(0.0):
        return 0.0
    return largest_proved(proved, upper, rel)


def largest_proved(proved, upper: float, rel: float) -> float:
    """The largest m ≤ ``upper`` (to ``rel``) with ``proved(m)`` found by bisection, given
    ``proved(0)``; 0 when nothing above SMALLEST·upper is.  While nothing above 0 is proved it
    steps down by DESCENT (halving from lo = 0, hi − lo > rel·hi held forever: a grazing case
    looped here; at 10⁶ DOFs each step is a pencil and an LDLᵀ), then bisects."""
    if proved(upper):
        return upper
    lo, hi = 0.0, upper
    while hi - lo > rel * hi:
        if lo == 0.0 and hi <= SMALLEST * upper:
            break
        mid = hi / DESCENT if lo == 0.0 else 0.5 * (lo + hi)
        lo, hi = (mid, hi) if proved(mid) else (lo, mid)
    return lo


def damped_rayleigh_bound(pen, C: sp.spmatrix | None = None, M: sp.spmatrix | None = None, *,
                          comm=None) -> tuple[bool, str]:
    """``(proved, statement)``: whether no real λ ≥ 0 solves the damped pencil's quadratic
    MEiCP, by the bound of the module docstring; the statement says what was shown or why
    it proves nothing.  ``C``, ``M``: the lattice's damping and mass (SciPy) when the caller
    has them, else assembled here.  Collective on the pencil's communicator; a SciPy pencil
    every rank holds is factored over ``comm`` (None: this process alone)."""
    lattice = pen.lattice
    C = lattice.damping() if C is None else C
    M = mass_matrix_scipy(lattice.model) if M is None else M
    nu, why = friction_shift(pen.maps, C, M)
    if nu is None:
        return False, f"damped Rayleigh bound not tried: {why}"
    tau = -0.25 * nu * nu
    bound = pencil_bound(pen, tau, comm)
    if bound.proved:
        return True, (f"damped Rayleigh bound: {why}, and {bound.reason}, so λ²·xᵀBx + λ·xᵀDx − xᵀAx > 0 for every "
                      "λ ≥ 0 and x ≠ 0: no real λ ≥ 0 (a proof)")
    return False, f"damped Rayleigh bound at τ = −ν²/4 = {tau:.6g} ({why}): {bound.reason}"
