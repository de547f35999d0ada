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
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..lattice.assembly import damping_matrix_scipy
from .damped_proportional import bonded_pairs
from .damped_rayleigh import diagonal_mass, friction_discs, largest_proved
from .problem import pencil_of
from .rayleigh import pencil_bound

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


@dataclass(frozen=True)
class Bounds:
    """The row-pass bounds of one sliding pencil (module docstring): β, the split's c and α,
    ν₊ and δ₊ of C₊'s friction rows, the rounding ε, with ``grow`` charged on each."""

    beta: float
    c: float
    alpha: float
    nu: float
    delta_plus: float
    eps: float

    @property
    def delta(self) -> float:
        return self.c * self.beta + self.delta_plus + self.eps

    def d0(self, g: float) -> float:
        return (self.alpha + self.c * g) / (1 + ROUNDING) - self.nu - self.eps

    def needed(self) -> float:
        """The smallest g with which an inertia proves it (inf: none)."""
        return needed_shift(self.beta, self.delta, self.d0)

    def describe(self) -> str:
        return (f"C = {self.c:.4g}·K + {self.alpha:.4g}·M + C₊ (C₊ ⪰ 0, its friction rows' discs {self.nu:.3g}, "
                f"{self.delta_plus:.3g}; rounding {self.eps:.2g}), |Im xᴴAx/xᴴBx| ≤ β = {self.beta:.4g}")


class DampingSplit:
    """K, M, C of an assembled lattice (:class:`~meicp.petsc.assembly.LatticeMatrices`: SciPy on
    every rank, its own when serial) and the excess C₊, made once for every pencil and every μ
    the bounds are asked at."""

    def __init__(self, lattice):
        model = lattice.model
        self.c, self.alpha = stiffness_part(model)
        (self.K, self.M), self.C = lattice.whole(), lattice.damping()
        self.excess = damping_matrix_scipy(model, table=np.clip(model.cmat - self.c * model.kmat, 0.0, None),
                                           mass=0.0)

    def bounds(self, maps) -> tuple[Bounds | None, str]:
        """The :class:`Bounds` of the pencil of ``maps``, or None and why not."""
        b, why = diagonal_mass(maps, self.M)
        if b is None:
            return None, f"not tried: {why}"
        c, alpha, grow = self.c, self.alpha, 1 + ROUNDING
        _, beta = friction_discs(maps, self.K, b)
        nu, delta_plus = friction_discs(maps, self.excess, b)
        eps = (_discs(maps, self.C - c * self.K - alpha * self.M - self.excess, b)
               + ROUNDING * _discs(maps, abs(self.C) + c * abs(self.K) + alpha * self.M, b))
        return Bounds(beta * grow, c, alpha, nu * grow, delta_plus * grow, eps), ""


def damped_flutter_free(pen) -> tuple[bool, str]:
    """``(proved, statement)``: whether every eigenvalue of the damped sliding pencil ``pen``
    has Re λ < 0 (module docstring), and the sentence saying what was shown or why not.
    Collective on the pencil's communicator (every rank computes the same bounds)."""
    bounds, why = DampingSplit(pen.lattice).bounds(pen.maps)
    if bounds is None:
        return False, why
    g = bounds.needed()
    if not math.isfinite(g):
        return False, (f"damped flutter-free proof not possible: {bounds.describe()}; Re xᴴDx/xᴴBx ≥ α + c·g − "
                       f"{bounds.nu + bounds.eps:.3g} stays too small for any g")
    proof = pencil_bound(pen, -g)
    if not proof.proved:
        return False, (f"damped flutter-free proof failed: it needs sym(A) + g·B ≺ 0 with g = {g:.6g} "
                       f"({bounds.describe()}), and {proof.reason}")
    return True, (f"no eigenvalue grows (a proof): {proof.reason}, so Re xᴴAx/xᴴBx < −{g:.6g} for every x; "
                  f"{bounds.describe()}; so Re xᴴDx/xᴴBx ≥ {bounds.d0(g):.4g} > 0 and |Im| ≤ {bounds.delta:.4g}, and "
                  "λ² + dλ − a = 0 has both roots in Re λ < 0 (Hurwitz)")


def flutter_free_up_to(lattice, lines, maps, upper: float, *, rel: float = 1e-4, comm=None) -> tuple[float, str]:
    """``(m, statement)``: the largest m ≤ ``upper`` (to ``rel``) such that no eigenvalue of
    the damped sliding pencil of ``maps`` grows at any μ in [0, m] (every contact at μ); 0 when
    nothing is proved.  At μ ≤ m every bound is at most its value at m (β, ν₊, δ₊ and ε grow
    with μ; B does not depend on it), so g = g(m) serves every μ in [0, m], and
    ``sym(A(μ)) + g·B`` is affine in μ: negative definite at 0 and at m (two inertias), it is
    so on [0, m].  Bisection on m (:func:`~.damped_rayleigh.largest_proved`).  ``lattice``: the SciPy
    :class:`~meicp.petsc.assembly.LatticeMatrices` of the critical friction, every rank alike;
    its inertias factored over ``comm`` (None: this process alone)."""
    pieces = DampingSplit(lattice)

    def negative(pen, g: float) -> bool:
        return pen.A is None or pencil_bound(pen, -g, comm).proved

    with pencil_of(lattice, lines, (), maps=maps.with_friction(0.0)) as at_zero:
        def proved(m: float) -> bool:
            bounds, _ = pieces.bounds(maps.with_friction(m))
            g = math.inf if bounds is None else bounds.needed()
            if not (math.isfinite(g) and negative(at_zero, g)):
                return False
            if m == 0.0:
                return True
            with pencil_of(lattice, lines, (), maps=maps.with_friction(m)) as pen:
                return negative(pen, g)

        if not math.isfinite(upper) or upper <= 0 or not proved(0.0):
            return 0.0, "the damped flutter-free proof does not hold at μ = 0"
        lo = largest_proved(proved, upper, rel)
    return lo, (f"no eigenvalue of the damped sliding pencil grows for any μ in [0, {lo:.8g}] (the damped flutter-free "
                "proof with the bounds at its upper end, sym(A(μ)) + g·B ≺ 0 at both ends, affine in μ: a proof)")


def _discs(maps, X: sp.spmatrix, b: np.ndarray) -> float:
    """A bound on ‖diag(b)^-½ P̃XQ̃ diag(b)^-½‖₂: the larger row or column sum of
    ``diag(b)^-½ |P̃||X||Q̃| diag(b)^-½`` — entrywise above |P̃XQ̃|, and growing with μ (|P̃| =
    |P̃₀| + μ|P̃₁|: their entries lie in different columns)."""
    scale = sp.diags(1.0 / np.sqrt(b))
    W = (scale @ (abs(maps.P) @ abs(X) @ abs(sp.csr_matrix(maps.Q))) @ scale).tocsr()
    if not W.nnz:
        return 0.0
    return float(max(np.asarray(W.sum(axis=1)).max(), np.asarray(W.sum(axis=0)).max()))


__all__ = ["Bounds", "damped_flutter_free", "flutter_free_up_to", "needed_shift", "stiffness_part"]
