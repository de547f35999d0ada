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
#: condition number (κ ≤ 1.1e3 measured on the dense cases) times :func:`partner_condition`, a
#: lower bound of it that a near-defective pair makes large; the undamped and the damped alike
MARGIN = 1e6
#: the searches: a value within this relative distance of an earlier one is the same eigenvalue
SAME = 1e-9
#: restarts after which a search's solve stops when its error estimates, falling as they did,
#: would not reach the tolerance within GIVE_UP_BUDGET restarts (:class:`~meicp.petsc.flutter.StallWatch`;
#: at μ = 0.002 on a 10⁵-DOF lattice the undamped search's last target ran on toward 500
#: restarts of 2.7 s, the estimate stuck at 1.5e-2), or — the damped search — when its Ritz
#: values show nothing growing (Re λ < 0; :class:`~meicp.petsc.flutter_quadratic.GrowthWatch`):
#: a speed heuristic, the target then counts as failed (undecided)
GIVE_UP_RESTARTS = 10
GIVE_UP_BUDGET = 60


def separation(x1, x2) -> float:
    """θ = min over φ of ‖x₁/‖x₁‖ − e^{iφ}x₂/‖x₂‖‖ = √(2 − 2|x₁ᴴx₂|/(‖x₁‖‖x₂‖)): 0 for parallel vectors."""
    x1, x2 = np.asarray(x1), np.asarray(x2)
    norms = float(np.linalg.norm(x1) * np.linalg.norm(x2))
    cos = abs(complex(np.vdot(x1, x2))) / norms if norms > 0 else 1.0
    return float(np.sqrt(max(2.0 - 2.0 * cos, 0.0)))


def partner_condition(value: complex, x, partners, spread) -> float:
    """A lower bound of the condition number ‖x‖‖y‖/|yᴴQ'(value)x| of an eigenvalue (right
    eigenvector x, left y) from other eigenpairs ``partners`` — (value₂, x₂), the conjugate
    (value̅, x̄) of a real pencil always among them.  For value₂ ≠ value the left vector y
    annihilates (Q(value) − Q(value₂))x₂ = (value − value₂)·W x₂, so with x₂ turned to the
    phase nearest x, |yᴴQ'x| = |yᴴ(W(x − x₂) + (Q' − W)x)| ≤ ‖y‖‖x‖·(a·θ + b), θ =
    :func:`separation`, ``spread(value, value₂) = (a, b)`` bounding ‖W‖ and ‖Q' − W‖ (σB − A:
    W = Q' = B, so (‖B‖, 0); λ²B + λD − A: W = (λ + λ₂)B + D, Q' − W = (λ − λ₂)B).  Large where two
    eigenvalues nearly coalesce — their eigenvectors nearly parallel — or a real one was
    computed off the axis (x nearly real, θ to x̄ small): ρ ≈ 1e-8 where a search certified
    such "modes", θ ≥ 0.06 for every true flutter mode measured, even just past the onset.
    The searches' margins take MARGIN times this bound where it exceeds their own."""
    x = np.asarray(x)
    worst = np.inf
    for value2, x2 in [(complex(value).conjugate(), x.conjugate()), *partners]:
        a, b = spread(complex(value), complex(value2))
        worst = min(worst, a * separation(x, x2) + b)
    return 1.0 / worst if worst > 0 else np.inf


def gated_partners(pairs, value: complex, gate: float) -> list:
    """The (value₂, x₂) of a solve's ``pairs`` ((value, x, backward error)) that serve
    :func:`partner_condition` for ``value``: those passing the residual ``gate``, ``value`` itself
    excluded (an inaccurate copy of it with its eigenvector would make any mode undecided)."""
    return [(v2, x2) for v2, x2, r2 in pairs if r2 <= gate and abs(v2 - value) > SAME * abs(value)]


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
