"""The critical friction's answer: :class:`CriticalFriction`, a float with its certified
bracket."""

from __future__ import annotations

import numpy as np

#: a bracket is exact when upper − lower ≤ EXACT_WIDTH·upper (the lower end's certificate
#: is taken 10⁻⁶ below its computed value, so a tighter tolerance could never be met)
EXACT_WIDTH = 1e-5


class CriticalFriction(float):
    """The critical friction as a float — the upper end: a μ at which a certified σ = 0 mode
    exists (inf when none was found up to ``mu_max``) — carrying its certified bracket:
    ``lower`` (no σ = 0 mode for any μ < lower, proved), ``upper`` (= the value), ``exact``
    (μ_c is known: the ends meet within EXACT_WIDTH, or no mode exists up to ``mu_max``,
    proved) and ``evidence`` (how each end was obtained)."""

    lower: float
    upper: float
    exact: bool
    evidence: str

    def __new__(cls, upper: float, lower: float, exact: bool, evidence: str):
        obj = super().__new__(cls, upper)
        obj.upper, obj.lower, obj.exact, obj.evidence = float(upper), float(lower), bool(exact), str(evidence)
        return obj

    def __reduce__(self):
        return (CriticalFriction, (self.upper, self.lower, self.exact, self.evidence))

    def __repr__(self) -> str:
        return f"CriticalFriction({self.describe()})"

    def __str__(self) -> str:  # print(mu_c) and f"{mu_c}" show the number, as for any float
        return float.__repr__(self)

    @property
    def width(self) -> float:
        """(upper − lower)/upper: 0 when exact, inf without a mode."""
        if self.upper == self.lower:
            return 0.0
        return (self.upper - self.lower) / self.upper if np.isfinite(self.upper) else np.inf

    def describe(self) -> str:
        """One line: ``1.4605 (exact)``, ``in [1.08, 1.4605] (width …)`` or ``≥ 2.3 (no σ = 0 mode
        found …)``."""
        if self.exact and np.isfinite(self.upper):
            if self.lower == self.upper:
                return f"{self.upper:.10g} (exact)"
            return f"{self.upper:.10g} (exact within {self.width:.1e}: proved ≥ {self.lower:.10g})"
        if self.exact:
            return f"none up to μ = {self.lower:.6g} (proved)"
        if not np.isfinite(self.upper):
            return f"≥ {self.lower:.10g} (no σ = 0 mode found: upper end inf)"
        return f"in [{self.lower:.10g}, {self.upper:.10g}] (width {100 * self.width:.2g} %)"
