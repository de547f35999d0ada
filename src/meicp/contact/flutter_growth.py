"""The certified bracket of the fastest flutter growth rate (docs/flutter.md §4a).

``lower``: the growth rate Re √σ of a certified flutter mode, less what rounding may take
from it; ``upper``: proved — no non-real eigenvalue of the sliding pencil grows faster.  The
fastest mode found is called *the fastest* only when the two meet (:attr:`FlutterGrowth.exact`).

Rounding moves an eigenvalue σ by at most its radius r (the dense path's first-order bound
``n·u·(‖A‖ + |σ|‖B‖)·κ``, the search's margin), so the exact eigenvalue lies in the disk
``|z − σ| ≤ r`` and its growth rate in :func:`disk_growth_range`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core.json_values import json_ready
from .result import growth_frequency

#: the bracket is exact when upper − lower ≤ EXACT_WIDTH·upper (issue 29)
EXACT_WIDTH = 1e-6
#: relative slack for the rounding of the bound's own arithmetic
_SLACK = 8 * float(np.finfo(float).eps)


def disk_growth_range(sigma: complex, radius: float) -> tuple[float, float]:
    """``(lo, hi)``: every z with ``|z − σ| ≤ radius`` has lo ≤ Re √z ≤ hi.

    A disk that misses the real axis lies in one open half-plane, where √z and √σ lie in one
    quadrant, so ``|√z + √σ| ≥ |√σ|`` and ``|Re √z − Re √σ| ≤ |z − σ| / |√σ|``.  A disk that
    meets it: ``Re √z = sqrt((|z| + Re z)/2) ≤ sqrt((|σ| + Re σ + 2r)/2)``, and 0 below."""
    s = complex(sigma)
    r = float(radius)
    if not (np.isfinite(s.real) and np.isfinite(s.imag) and np.isfinite(r)):
        return 0.0, math.inf
    g = growth_frequency(s)[0]
    if abs(s.imag) > r and abs(s) > 0:
        d = r / math.sqrt(abs(s))
        return max(g - d, 0.0) * (1 - _SLACK), (g + d) * (1 + _SLACK)
    return 0.0, math.sqrt(max(0.0, 0.5 * (abs(s) + s.real + 2 * r))) * (1 + _SLACK)


@dataclass(frozen=True)
class FlutterGrowth:
    """The certified bracket of the fastest flutter growth rate of steady sliding.

    lower: a certified flutter mode grows at least this fast (0 when none is certified).
    upper: no non-real eigenvalue of the sliding pencil grows faster (proved); None when no
    bound is proved.  ``upper == 0``: no flutter at all (a proof).  evidence: how each end
    was obtained.  loose: the upper end bounds the whole spectrum from outside (Bendixson's
    rectangle, the large-scale search), not from the eigenvalues themselves (the dense
    path): proved, but far above the fastest mode.  ``float(growth)`` is ``lower``."""

    lower: float
    upper: float | None
    evidence: str = ""
    loose: bool = False

    def __float__(self) -> float:
        return float(self.lower)

    def __str__(self) -> str:
        return self.describe()

    def __repr__(self) -> str:
        return f"FlutterGrowth(lower={self.lower:.10g}, upper={self.upper!r}, exact={self.exact})"

    @property
    def exact(self) -> bool:
        """The fastest mode found is proved the fastest (to EXACT_WIDTH relative)."""
        return bool(self.upper is not None and self.upper - self.lower <= EXACT_WIDTH * self.upper)

    @property
    def width(self) -> float:
        return math.inf if self.upper is None else self.upper - self.lower

    def describe(self) -> str:
        """One line for the CLI table and summaries."""
        if self.upper == 0.0:
            return "0: no flutter (proved)"
        if self.exact:
            return f"{self.lower:.8g}: the fastest, proved (bracket [{self.lower:.10g}, {self.upper:.10g}])"
        found = "fastest found" if self.lower > 0 else "no certified mode"
        bound = ("no upper bound proved" if self.upper is None else f"proved ≤ {self.upper:.6g}"
                 + (" by Bendixson's rectangle" if self.loose else ""))
        return f"≥ {self.lower:.6g} ({found}, not proved the fastest; {bound})"

    def to_dict(self) -> dict:
        """JSON-ready: no upper bound proved is an infinite ``upper`` — ``null`` with
        ``upper_infinite: 1`` (:mod:`meicp.core.json_values`)."""
        upper = math.inf if self.upper is None else float(self.upper)
        return json_ready({"lower": float(self.lower), "upper": upper, "exact": self.exact,
                           "upper_loose": bool(self.loose), "evidence": self.evidence})


def dense_growth(w: np.ndarray, radius: np.ndarray, candidates: np.ndarray, modes: list,
                 how: str) -> FlutterGrowth:
    """The bracket from a complete spectrum ``w`` with radii: ``candidates`` marks the
    eigenvalues that may be non-real (not certified real, finite); ``modes`` the certified
    flutter modes (:class:`~meicp.contact.flutter_verdict.FlutterCandidate`)."""
    upper = 0.0
    for s, r in zip(w[candidates], radius[candidates]):
        upper = max(upper, disk_growth_range(s, r)[1])
    lower = _certified_lower(modes)
    n = int(np.count_nonzero(candidates))
    if n == 0:
        text = f"{how}: every eigenvalue certified real — no flutter (a proof)"
    else:
        text = (f"{how}: the {n} eigenvalue(s) not certified real, each within its rounding disk, grow at most "
                f"{upper:.10g}; the fastest certified mode at least {lower:.10g}")
    return FlutterGrowth(float(lower), float(upper), text)


def rectangle_growth(real_max: float, imag_max: float) -> float:
    """The largest Re √σ over the rectangle ``Re σ ≤ real_max``, ``|Im σ| ≤ imag_max``:
    Re √σ = sqrt((|σ| + Re σ)/2) grows with Re σ and with |Im σ|, so it is taken at the
    corner (inf when a side is not finite)."""
    if not (math.isfinite(real_max) and math.isfinite(imag_max)):
        return math.inf
    x, y = float(real_max), abs(float(imag_max))
    return math.sqrt(max(0.0, 0.5 * (math.hypot(x, y) + x))) * (1 + _SLACK)


def search_growth(modes: list, why_no_bound: str, rectangle: tuple | None = None,
                  ceiling: tuple | None = None) -> FlutterGrowth:
    """The bracket of a search that computed part of the spectrum: the fastest certified
    mode below; above, when ``rectangle`` = ``(real_max, imag_max, how)`` bounds every
    eigenvalue (Bendixson: a certified Re σ ≤ real_max and |Im σ| ≤ imag_max), the growth at
    its corner (:func:`rectangle_growth`), or ``ceiling`` = ``(upper, how)`` a proved bound on
    every eigenvalue's growth (:func:`quadratic_ceiling`), a proof however loose; else no
    upper bound."""
    lower = _certified_lower(modes)
    text = f"the fastest certified mode found grows at least {lower:.6g}; "
    if ceiling is not None and math.isfinite(ceiling[0]):
        upper = max(float(ceiling[0]), lower)
        return FlutterGrowth(float(lower), upper, loose=True, evidence=text + (
            f"no eigenvalue grows faster than {upper:.6g} ({ceiling[1]}; a proof; {why_no_bound})"))
    corner = math.inf if rectangle is None else rectangle_growth(*rectangle[:2])
    if not math.isfinite(corner):
        return FlutterGrowth(float(lower), None, text + f"no upper bound: {why_no_bound}")
    real_max, imag_max, how = rectangle
    upper = max(corner, lower)
    return FlutterGrowth(float(lower), float(upper), loose=True, evidence=text + (
        f"every eigenvalue has Re σ ≤ {real_max:.6g} ({how}) and |Im σ| ≤ {imag_max:.6g} (skew-part bound), "
        f"so none grows faster than {upper:.6g} (Bendixson's rectangle, a proof; {why_no_bound})"))


def quadratic_ceiling(gamma: float, beta: float, nu: float, delta: float) -> float:
    """The largest growth u = Re λ of any eigenvalue of ``λ²B + λD − A`` (B ≻ 0) whose
    field-of-values ratios, for its eigenvector x, satisfy ``Re a ≤ γ``, ``|Im a| ≤ β``,
    ``Re d ≥ −ν``, ``|Im d| ≤ δ`` (a = xᴴAx/xᴴBx, d = xᴴDx/xᴴBx; ν, β, δ ≥ 0).

    ``xᴴQ(λ)x = 0`` is ``λ² + dλ − a = 0``; with λ = u + iv its imaginary part gives
    ``v(2u + Re d) = Im a − (Im d)u``, so for u > ν/2, ``|v| ≤ V(u) = (β + δu)/(2u − ν)``, and its
    real part ``u² + (Re d)u − Re a = v² + (Im d)v`` gives ``f(u) = u² − νu − γ − V² − δV ≤ 0``.
    On (ν/2, ∞) the first terms grow and V falls (V′ = −(δν + 2β)/(2u − ν)² ≤ 0), so f grows:
    every eigenvalue has u ≤ max(ν/2, the root of f), found by bisection and returned rounded
    up.  A Bendixson-type bound: proved, and far above the fastest mode."""
    nu, beta, delta = max(nu, 0.0), abs(beta), abs(delta)
    floor = 0.5 * nu

    def f(u: float) -> float:
        v = (beta + delta * u) / (2 * u - nu)
        return u * u - nu * u - gamma - v * v - delta * v

    hi = max(nu, 1.0)
    while not f(hi) > 0:  # NaN (β near overflow) included: no bound then
        hi *= 2
        if hi > 1e300:
            return math.inf
    lo = floor
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mid <= lo or mid >= hi:
            break
        lo, hi = (mid, hi) if (mid <= floor or not f(mid) > 0) else (lo, mid)  # NaN: not proved, go up
    return max(floor, hi) * (1 + 1e-12)


def _certified_lower(modes: list) -> float:
    """The growth rate every certified mode's disk guarantees, the largest of them."""
    return max((disk_growth_range(m.sigma, m.radius)[0] for m in modes), default=0.0)


def combine_growths(parts: list) -> FlutterGrowth | None:
    """The bracket over grazing branches: the smallest lower bound (flutter is claimed only
    when every branch has it) and the largest upper one."""
    parts = [p for p in parts if p is not None]
    if not parts:
        return None
    if len(parts) == 1:
        return parts[0]
    upper = None if any(p.upper is None for p in parts) else max(p.upper for p in parts)
    return FlutterGrowth(min(p.lower for p in parts), upper, " | ".join(p.evidence for p in parts),
                         loose=any(p.loose for p in parts))
