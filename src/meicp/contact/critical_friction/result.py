"""The critical friction's answer: :class:`CriticalFriction`, a float — the friction at which
the first instability starts — with its certified bracket, and the two onsets it is made of,
each an :class:`Onset`: divergence (a σ = 0 mode) and flutter (a non-real σ of the sliding
pencil)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: a divergence bracket is exact when upper − lower ≤ EXACT_WIDTH·upper (the lower end's
#: certificate is taken 10⁻⁶ below its computed value, so a tighter tolerance could never be met)
EXACT_WIDTH = 1e-5
#: a flutter bracket is exact when upper − lower ≤ FLUTTER_EXACT_WIDTH·upper
FLUTTER_EXACT_WIDTH = 1e-6


@dataclass(frozen=True)
class Onset:
    """The certified bracket of one instability's onset μ, as a function of friction.

    lower: no such instability for any μ in [0, lower), proved (``inf``: at no μ).
    upper: a μ where it is certified (``inf``: none found up to the bound searched).
    exact: the ends meet within the tolerance (divergence: :data:`EXACT_WIDTH`, flutter:
        :data:`FLUTTER_EXACT_WIDTH`), or none exists up to the bound searched, proved.
    evidence: how each end was obtained.
    mode: flutter only, the certified :class:`~meicp.contact.result.FlutterMode` at ``upper``
        (None for divergence, or when none was found).
    floor: divergence only, where ``lower`` is about σ = 0 modes alone (the cross-check for
        modes born at σ > 0 did not run): no divergence mode of any σ ≥ 0 for μ in [0, floor],
        proved (0: nothing proved); None where ``lower`` covers them too."""

    lower: float
    upper: float
    exact: bool
    evidence: str
    mode: object = None
    floor: float | None = None

    def __float__(self) -> float:
        return float(self.upper)

    def __repr__(self) -> str:
        return f"Onset({self.describe()})"

    @property
    def width(self) -> float:
        """(upper − lower)/upper: 0 when the ends meet, inf without an upper end."""
        return _width(self.lower, self.upper)

    @property
    def proved_free(self) -> float:
        """Below this μ no mode of this kind exists, of any σ ≥ 0 for divergence: ``lower``, or
        the ``floor`` where ``lower`` is about σ = 0 modes alone."""
        return self.lower if self.floor is None else min(self.floor, self.lower)

    def describe(self, what: str = "mode") -> str:
        """One line: ``1.4605 (exact)``, ``in [1.08, 1.4605] (width …)`` or ``≥ 2.3 (no …
        found …)``."""
        return _describe(self.lower, self.upper, self.exact, what)


def _width(lower: float, upper: float) -> float:
    if upper == lower:
        return 0.0
    return (upper - lower) / upper if np.isfinite(upper) else np.inf


def _describe(lower: float, upper: float, exact: bool, what: str) -> str:
    if exact and np.isfinite(upper):
        if lower == upper:
            return f"{upper:.10g} (exact)"
        return f"{upper:.10g} (exact within {_width(lower, upper):.1e}: proved ≥ {lower:.10g})"
    if exact:
        return f"none up to μ = {lower:.6g} (proved)"
    if not np.isfinite(upper):
        return f"≥ {lower:.10g} (no {what} found: upper end inf)"
    return f"in [{lower:.10g}, {upper:.10g}] (width {100 * _width(lower, upper):.2g} %)"


def first_onset(divergence: Onset, flutter: Onset | None) -> str | None:
    """Which instability starts first, when the brackets prove it: ``"flutter"`` when flutter
    is certified below the proved lower end of divergence, ``"divergence"`` the other way
    round, None when the brackets overlap (or flutter was not analysed)."""
    if flutter is None:
        return None
    # the divergence onset's lower end may be about σ = 0 modes alone: a mode born at σ > 0
    # below it would start first, so flutter is first only below what excludes those too
    if flutter.upper < divergence.proved_free:
        return "flutter"
    if divergence.upper < flutter.lower:
        return "divergence"
    return None


@dataclass(frozen=True)
class CriticalFrictionFailed:
    """The critical friction of a results.h5 whose ``meicp solve --critical-friction`` failed
    (a floating body, a scene without friction, …): the error it stored, no value."""

    error: str

    def __str__(self) -> str:
        return f"not computed: {self.error}"


class CriticalFriction(float):
    """The friction at which the first instability starts, as a float — the upper end of the
    overall bracket: a μ at which a certified mode exists (inf when none was found) —
    carrying that bracket and the two onsets it combines.

    lower, upper, exact, evidence: the overall bracket ``[min(free_d, lower_f),
        min(upper_d, upper_f)]`` (``free_d``: :attr:`Onset.proved_free` of divergence); exact when the first onset's bracket is exact and lies
        below the other's lower end, or both are exact.
    divergence: the :class:`Onset` of divergence (a σ = 0 mode, μ_c).
    flutter: the :class:`Onset` of flutter (the smallest μ with a non-real σ of the sliding
        pencil, μ_f); None when flutter was not analysed (``flutter=False``): the value is
        then the divergence onset.
    first: ``"flutter"``, ``"divergence"``, or None when the brackets overlap or flutter was
        not analysed."""

    lower: float
    upper: float
    exact: bool
    evidence: str
    divergence: Onset
    flutter: Onset | None
    first: str | None

    def __new__(cls, upper: float, lower: float, exact: bool, evidence: str, *,
                divergence: Onset | None = None, flutter: Onset | None = None):
        obj = super().__new__(cls, upper)
        obj.upper, obj.lower, obj.exact, obj.evidence = float(upper), float(lower), bool(exact), str(evidence)
        obj.divergence = divergence if divergence is not None else Onset(obj.lower, obj.upper, obj.exact, obj.evidence)
        obj.flutter = flutter
        obj.first = first_onset(obj.divergence, flutter)
        return obj

    @classmethod
    def of(cls, divergence: Onset, flutter: Onset | None) -> "CriticalFriction":
        """The overall onset of the two brackets (``flutter`` None: not analysed, the
        divergence onset alone)."""
        if flutter is None:
            return cls(divergence.upper, divergence.lower, divergence.exact,
                       divergence.evidence + "; flutter not analysed", divergence=divergence)
        first = first_onset(divergence, flutter)
        lower, upper = min(divergence.proved_free, flutter.lower), min(divergence.upper, flutter.upper)
        if first is None:
            # both known: divergence's only where σ > 0 births are excluded up to its lower end
            exact = divergence.exact and divergence.proved_free >= divergence.lower and flutter.exact
            which = ("the two brackets overlap: which instability starts first is undecided" if exact or
                     np.isfinite(upper) else "no instability found")
            if flutter.upper < divergence.lower:
                which = (f"flutter is certified at μ = {flutter.upper:.8g}, below the σ = 0 onset, but divergence "
                         f"modes born at σ > 0 are excluded only for μ ≤ {divergence.proved_free:.8g}: which "
                         "instability starts first is undecided")
        else:
            exact = (flutter if first == "flutter" else divergence).exact
            which = f"{first} starts first"
        evidence = f"{which}; divergence: {divergence.evidence}; flutter: {flutter.evidence}"
        return cls(upper, lower, exact, evidence, divergence=divergence, flutter=flutter)

    def __reduce__(self):
        return (_rebuild, (self.upper, self.lower, self.exact, self.evidence, self.divergence, self.flutter))

    def __repr__(self) -> str:
        return f"CriticalFriction({self.describe()})"

    def __str__(self) -> str:  # print(mu_c) and f"{mu_c}" show the number, as for any float
        return float.__repr__(self)

    @property
    def width(self) -> float:
        """(upper − lower)/upper: 0 when exact, inf without a mode."""
        return _width(self.lower, self.upper)

    def describe(self) -> str:
        """One line: ``1.4605 (exact)``, ``in [1.08, 1.4605] (width …)`` or ``≥ 2.3 (no σ = 0 mode
        found …)``, and which instability starts first when known."""
        what = "σ = 0 mode" if self.flutter is None else "instability"
        text = _describe(self.lower, self.upper, self.exact, what)
        if self.first is not None:
            text += f" — {self.first} first"
        return text


def _rebuild(upper, lower, exact, evidence, divergence, flutter) -> CriticalFriction:
    return CriticalFriction(upper, lower, exact, evidence, divergence=divergence, flutter=flutter)
