"""The flutter analysis' values: a candidate mode of one sliding pencil, the analysis of
that pencil, and the scene's flutter verdict (:mod:`meicp.contact.flutter`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class FlutterCandidate:
    """A certified non-real eigenpair of a sliding pencil, on its retained DOFs.

    sigma: the eigenvalue (Im σ > 0).  x: its eigenvector (unit norm, largest entry real).
    residual: its backward error.  radius: how far σ may be from the exact eigenvalue — the
    dense path's rounding radius, the search's margin — below |Im σ|, so σ is non-real.
    found_by: the path that found it (dense QR / QZ, or shift-invert at a target)."""

    sigma: complex
    x: np.ndarray
    residual: float
    radius: float
    found_by: str


@dataclass(frozen=True)
class RejectedPair:
    """A non-real eigenpair that failed the residual gate: never reported as a mode."""

    sigma: complex
    residual: float


@dataclass(frozen=True)
class PencilFlutter:
    """The flutter analysis of one sliding pencil: ``flutter`` (True / False / None),
    ``modes`` (:class:`FlutterCandidate` s, fastest first), ``evidence`` (what was searched,
    what it proves), ``complete`` (the whole spectrum was computed), ``counts`` (of
    eigenvalues by kind, or of targets), ``rejected`` (:class:`RejectedPair` s)."""

    flutter: bool | None
    modes: list = field(default_factory=list)
    evidence: str = ""
    complete: bool = False
    counts: dict = field(default_factory=dict)
    rejected: list = field(default_factory=list)


@dataclass(frozen=True)
class FlutterVerdict:
    """What :func:`~meicp.contact.flutter.analyze_flutter` gives ``analyze``: the verdict, the
    modes in natural numbering (:class:`~meicp.contact.result.FlutterMode`, fastest first),
    the evidence and the seconds it took.  ``growth_bound``: the largest growth rate any
    flutter mode can have, when the whole spectrum proves it (:func:`growth_bound`), else
    None."""

    flutter: bool | None
    modes: list
    evidence: str
    seconds: float = 0.0
    growth_bound: float | None = None


def growth_bound(part: PencilFlutter) -> float | None:
    """An upper bound on Re λ = Re √σ over every non-real σ of one sliding pencil, or None.

    Only a complete spectrum (the dense path, or a symmetry proof) bounds it, and only when no
    eigenvalue is borderline or failed the residual gate: then the non-real σ are exactly the
    modes found, each within its rounding ``radius`` r of the exact eigenvalue, and
    Re √σ' = √((|σ'| + Re σ')/2) ≤ √((|σ| + Re σ)/2 + r) for |σ' − σ| ≤ r.  0 when there is
    no non-real σ.  The search path never bounds it (it sees part of the spectrum)."""
    if not part.complete or part.counts.get("borderline", 0) or part.counts.get("rejected", 0):
        return None
    bounds = [float(np.sqrt(0.5 * (abs(m.sigma) + m.sigma.real) + m.radius)) for m in part.modes]
    return max(bounds, default=0.0)
