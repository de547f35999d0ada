"""A proof at any size that no eigenvalue of the damped sliding pencil grows: every λ of
``Q(λ) = λ²B + λD − A`` has Re λ < 0, so steady sliding cannot flutter (docs/damping.md,
"damped flutter-free proof").

For an eigenpair (λ, x) with B = diag(b) ≻ 0, ``xᴴQ(λ)x = 0`` is ``λ² + dλ − a = 0`` with
``a = xᴴAx/xᴴBx`` and ``d = xᴴDx/xᴴBx``.  Both roots of ``z² + pz + q`` have Re z < 0 iff
``p₁ > 0`` and ``p₁(p₁q₁ + p₂q₂) − q₂² > 0`` (the Hurwitz criterion for complex coefficients,
p = p₁ + ip₂, q = q₁ + iq₂); here p = d, q = −a.  With ``Re a ≤ −g`` (g > 0), ``|Im a| ≤ β``,
``Re d ≥ d₀ > 0`` and ``|Im d| ≤ δ`` the left side is at least

    h = g·d₀² − d₀·δ·β − β²

(it grows with q₁, and with p₁ past δβ/(2g), which h > 0 implies): h > 0 proves it.

- β: skew(A) = −skew(diag(μ)P̃₁KQ̃), the friction rows' part: its Gershgorin discs scaled by B.
- d₀ and δ: split ``C = cK + αM + C₊`` with c the largest factor with η ≥ c·k on every pair of
  materials a bond joins, so C₊ (the excess viscosity, bond by bond) ⪰ 0.  Then
  ``D = −cA + αB + Q̃ᵀC₊Q̃ + F₊ + E``: Q̃ᵀC₊Q̃ ⪰ 0, F₊ the friction rows' part of P̃C₊Q̃ (its
  discs ν₊, δ₊), E the rounding of the split (its discs ε), so ``Re d ≥ α + c·g − ν₊ − ε`` and
  ``|Im d| ≤ c·β + δ₊ + ε``.
- g: the smallest with h > 0 (bisection: d₀ grows with g), then proved by one LDLᵀ inertia,
  ``sym(A) + g·B ≺ 0`` with its rounding margin (:func:`~.rayleigh.rayleigh_bound` at τ = −g).

It holds where the damping outweighs the friction's skew part on the slowest motion: mass
damping, or Kelvin–Voigt damping with one relaxation time (C₊ = 0), at small μ; a lattice
whose slowest vibration is fast (a shallow layer held on top) keeps it at any width.  It needs
B diagonal (a base contact, an interface in centre-of-mass coordinates).  SciPy rows on every
rank, the inertia collective.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from ..lattice.assembly import damping_matrix_scipy, mass_matrix_scipy, stiffness_matrix_scipy
from .damped_proportional import bonded_pairs
from .damped_rayleigh import friction_discs
from .rayleigh import rayleigh_bound

#: every bound's relative allowance for the rounding of the products and sums that form it
ROUNDING = 1e-9


def stiffness_part(model) -> tuple[float, float]:
    """``(c, α)``: the largest c with η ≥ c·k on every pair of materials a bond joins (0 when
    one has no viscosity), and ``[damping] mass``."""
    k, eta = bonded_pairs(model)
    return (float(np.min(eta / k)) if k.size else 0.0), float(model.damping_mass)


def needed_shift(beta: float, delta: float, d0_at) -> float:
    """The smallest g (to 1e-6 relative, rounded up) with ``d₀ = d0_at(g) > 0`` and
    ``g·d₀² − d₀·δ·β − β² > 0``; inf when none below 1e300.  ``d0_at`` non-decreasing."""
    def holds(g: float) -> bool:
        d0 = d0_at(g)
        return d0 > 0 and g * d0 * d0 - d0 * delta * beta - beta * beta > 0

    hi = 1e-300
    while not holds(hi):
        hi *= 4
        if hi > 1e300:
            return math.inf
    if hi == 1e-300:  # β = 0 (no skew part): any g > 0 with d₀ > 0
        return hi
    lo = hi / 4
    while hi - lo > 1e-6 * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if holds(mid) else (mid, hi)
    return hi


def damped_flutter_free(pen) -> tuple[bool, str]:
    """``(proved, statement)``: whether every eigenvalue of the damped sliding pencil ``pen``
    has Re λ < 0 (module docstring), and the sentence saying what was shown or why not.
    Collective on the pencil's communicator (every rank computes the same bounds)."""
    maps, model = pen.maps, pen.model
    Q = sp.csr_matrix(maps.Q)
    if abs(sp.csr_matrix(maps.P0) - Q.T).max() != 0:
        return False, "not tried: P̃₀ ≠ Q̃ᵀ"
    M = mass_matrix_scipy(model)
    B = (maps.P @ M @ Q).tocsr()
    b = B.diagonal()
    if (B - sp.diags(b)).count_nonzero() or not np.all(b > 0):
        return False, "not tried: B is not diagonal with positive entries"
    c, alpha = stiffness_part(model)
    K, C = stiffness_matrix_scipy(model), damping_matrix_scipy(model)
    excess = damping_matrix_scipy(model, table=np.clip(model.cmat - c * model.kmat, 0.0, None), mass=0.0)
    grow = 1 + ROUNDING
    _, beta = friction_discs(maps, K, b)
    nu, delta_plus = friction_discs(maps, excess, b)
    eps = _discs(maps, C - c * K - alpha * M - excess, b) + ROUNDING * _discs(maps, abs(C) + c * abs(K) + alpha * M, b)
    beta, nu, delta_plus = beta * grow, nu * grow, delta_plus * grow
    delta = c * beta + delta_plus + eps
    g = needed_shift(beta, delta, lambda g: (alpha + c * g) / grow - nu - eps)
    split = (f"C = {c:.4g}·K + {alpha:.4g}·M + C₊ (C₊ ⪰ 0, its friction rows' discs {nu:.3g}, {delta_plus:.3g}; "
             f"rounding {eps:.2g}), |Im xᴴAx/xᴴBx| ≤ β = {beta:.4g}")
    if not math.isfinite(g):
        return False, (f"damped flutter-free proof not possible: {split}; Re xᴴDx/xᴴBx ≥ α + c·g − {nu + eps:.3g} "
                       "stays too small for any g")
    bound = rayleigh_bound(pen.A, pen.B, -g, decisive=False)
    if not bound.proved:
        return False, (f"damped flutter-free proof failed: it needs sym(A) + g·B ≺ 0 with g = {g:.6g} ({split}), "
                       f"and {bound.reason}")
    return True, (f"no eigenvalue grows (a proof): {bound.reason}, so Re xᴴAx/xᴴBx < −{g:.6g} for every x; {split}; "
                  f"so Re xᴴDx/xᴴBx ≥ {(alpha + c * g) / grow - nu - eps:.4g} > 0 and |Im| ≤ {delta:.4g}, and "
                  "λ² + dλ − a = 0 has both roots in Re λ < 0 (Hurwitz)")


def _discs(maps, X: sp.spmatrix, b: np.ndarray) -> float:
    """A bound on ‖diag(b)^-½ P̃XQ̃ diag(b)^-½‖₂: the larger of its row and column sums."""
    scale = sp.diags(1.0 / np.sqrt(b))
    W = abs(scale @ (maps.P @ X @ sp.csr_matrix(maps.Q)) @ scale).tocsr()
    if not W.nnz:
        return 0.0
    return float(max(np.asarray(W.sum(axis=1)).max(), np.asarray(W.sum(axis=0)).max()))


__all__ = ["damped_flutter_free", "needed_shift", "stiffness_part"]
