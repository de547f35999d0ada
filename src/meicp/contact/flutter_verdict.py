"""The flutter analysis' values: a candidate mode of one sliding pencil, the analysis of
that pencil, and the scene's flutter verdict (:mod:`meicp.contact.flutter`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..core.comm import available_memory_on
from .flutter_growth import FlutterGrowth

#: a flutter mode's backward error must be at most this to be reported (the undamped and the
#: damped paths alike)
RESIDUAL_TOL = 1e-10
#: the searches past the dense limit: a value must stand off the real axis by MARGIN·η times the
#: pencil's scale (η the backward error) to count as non-real; MARGIN stands for the unknown
#: condition number (κ ≤ 1.1e3 measured on the dense cases); the undamped and the damped alike
MARGIN = 1e6
#: the searches: a value within this relative distance of an earlier one is the same eigenvalue
SAME = 1e-9


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
    eigenvalues by kind, or of targets), ``rejected`` (:class:`RejectedPair` s), ``growth`` (the certified bracket of the
    fastest growth rate, :class:`~meicp.contact.flutter_growth.FlutterGrowth`)."""

    flutter: bool | None
    modes: list = field(default_factory=list)
    evidence: str = ""
    complete: bool = False
    counts: dict = field(default_factory=dict)
    rejected: list = field(default_factory=list)
    growth: FlutterGrowth | None = None


@dataclass(frozen=True)
class FlutterVerdict:
    """What :func:`~meicp.contact.flutter.analyze_flutter` gives ``analyze``: the verdict, the
    modes in natural numbering (:class:`~meicp.contact.result.FlutterMode`, fastest first),
    the evidence, the seconds it took and the certified growth bracket (None: not analysed)."""

    flutter: bool | None
    modes: list
    evidence: str
    seconds: float = 0.0
    growth: FlutterGrowth | None = None


def memory_refusal(comm, need: float, what: str) -> PencilFlutter | None:
    """The undecided analysis of a search that needs ``need`` bytes more than ``comm``'s ranks
    have (``what``: the search, for the sentence), or None when it fits.  Collective."""
    memory, where = available_memory_on(comm, need)
    if memory is None or need <= memory:
        return None
    return PencilFlutter(None, evidence=(
        f"not searched: {what} needs about {need / 2**30:.1f} GiB more, {memory / 2**30:.1f} GiB is available on "
        f"{where}: undecided"), growth=FlutterGrowth(0.0, None, "not searched (memory): no bound"))


def real_ritz_note(count: int, offset: str) -> str:
    """The evidence's note on the real Ritz values of a search's real form that were skipped
    (``offset``: the shifted variable, real for them), "" when none was."""
    if not count:
        return ""
    return f"; {count} real Ritz value(s) of the real form skipped ({offset} real: pseudo-pairs next to the target)"


def search_conclusion(modes: list) -> str:
    """What a search past the dense limit concludes, the end of its evidence sentence: it
    proves flutter with a certified mode, never its absence nor the fastest growth."""
    if modes:
        return (": flutter is proved by the certified mode(s); that the fastest found is the fastest is not (not a "
                "proof of the growth rate)")
    return ": no certified flutter mode there — not a proof that none exists (undecided)"
