"""Chaining window certificates (:mod:`.windows`) from σ = 0 to σ_max (a certified bound,
e.g. the Rayleigh quotient's) or ∞: G(σ) ∈ R₀ on every window proves that no MEiCP solution
has σ in [0, σ_max].  A failed window is split in log(σ + scale) at a new sample (one
condensation), until a budget of samples.

The settings are a :class:`Cover`; the condensations made and the scalings optimised at
them are a :class:`Samples`; each window is decided by :func:`certify_window`; the result is
a :class:`Coverage`.
"""
from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field

import numpy as np

from ...core.progress import Ticker
from ...lcp.certificates import optimise_scaling, pd_certificate
from .windows import chord_factor, window_certificate

log = logging.getLogger("meicp")

#: a window that the seed scaling misses by more than this many times the margin of
#: sym(D_seed G(σ_a)) ≻ 0 itself is split without optimising a scaling for σ_a: a better
#: scaling only raises that margin, and the seed proved every window after the splits where
#: it was measured (docs/benchmarks-notes.md, "HOPELESS_DEFICIT")
HOPELESS_DEFICIT = 10.0


@dataclass(frozen=True)
class Cover:
    """How to cover [0, σ_max] by windows.

    mu: the friction factor of G(σ) (``G(mu)`` of a condensation).  tau: the certified lower
    bound of λ_min(K̃_FF, M̃_F).  sigma_max: the window's end (∞ allowed).  max_samples:
    condensations allowed.  initial: the first windows split [0, σ_max] uniformly in
    log(σ + scale) into this many pieces (with σ_max = ∞: [0, ∞) first).  optimise: optimise
    a scaling per sample.  d_seed: the starting scaling of every sample's optimisation (e.g.
    the critical-friction bracket's D, near-optimal at σ = 0), and the first tried on every
    window; a window it misses by more than ``HOPELESS_DEFICIT`` times its own margin at σ_a
    is split without optimising a scaling for σ_a.  tol: relative margin every certificate
    must clear.  scale: where windows are split (default τ; an estimate of λ_min, certified
    or not: it moves the samples, not the bounds)."""

    mu: float
    tau: float
    sigma_max: float = np.inf
    max_samples: int = 24
    initial: int = 1
    optimise: bool = True
    d_seed: np.ndarray | None = None
    tol: float = 0.0
    scale: float | None = None

    @property
    def split_scale(self) -> float:
        return max(self.tau, self.scale) if self.scale else self.tau


@dataclass(frozen=True)
class Coverage:
    """What :func:`cover` proved: ``proved`` on all of [0, σ_max]; ``windows`` (σ_a, σ_b,
    margin, (kind, β)) certified; ``samples`` the σ values condensed; ``failed`` (σ_a, σ_b,
    margin) of the window that stopped it; ``seconds``; ``tau`` the certified τ the chords
    used last."""

    proved: bool
    windows: list
    samples: list
    failed: tuple | None
    seconds: float
    tau: float


class Samples:
    """The condensations made so far, by σ, and the scalings optimised at them (``scalings``:
    those already known, e.g. the caller's own at σ = 0: optimising again from it gains
    nothing, docs/benchmarks-notes.md, "scalings")."""

    def __init__(self, condense_at, settings: Cover, scalings: dict | None = None):
        self.condense_at = condense_at
        self.settings = settings
        self.condensed: dict = {}
        self.scalings = dict(scalings or {})
        self.seed_margins: dict = {}

    @property
    def count(self) -> int:
        return len(self.condensed)

    def at(self, s: float):
        """The condensation at σ = s (made once)."""
        if s not in self.condensed:
            self.condensed[s] = self.condense_at(s)
        return self.condensed[s]

    def scaling(self, s: float) -> np.ndarray:
        """The scaling D for σ = s: optimised from the seed (or I), unless the seed proves
        sym(DG(s)) ≻ 0 with a larger relative margin."""
        if s not in self.scalings:
            mu, d_seed = self.settings.mu, self.settings.d_seed
            G = self.at(s).G(mu)
            d = np.ones(G.shape[0]) if d_seed is None else d_seed
            if self.settings.optimise:
                d, _ = optimise_scaling([G], d0=d, iters=40)
            if d_seed is not None and (pd_certificate(G, self.at(s).error(mu), d_seed).margin / d_seed.mean()
                                       > pd_certificate(G, self.at(s).error(mu), d).margin / d.mean()):
                d = d_seed
            self.scalings[s] = d
        return self.scalings[s]

    def seed_slack(self, s: float) -> float:
        """The margin of sym(D_seed G(σ)) ≻ 0 at a sample (once)."""
        if s not in self.seed_margins:
            c, st = self.at(s), self.settings
            self.seed_margins[s] = pd_certificate(c.G(st.mu), c.error(st.mu), st.d_seed, tol=st.tol).margin
        return self.seed_margins[s]

    def optimised_for(self, s: float) -> bool:
        """Whether a scaling other than the seed was optimised for σ = s."""
        return s in self.scalings and self.scalings[s] is not self.settings.d_seed


def split(a: float, b: float, scale: float) -> list:
    """The two halves of [a, b] in log(σ + scale), or [] where rounding (or a zero scale)
    leaves no point strictly inside: the cover then stops there instead of looping."""
    mid = 2.0 * a + scale if not np.isfinite(b) else np.sqrt((a + scale) * (b + scale)) - scale
    if not np.isfinite(b) and a == 0:
        mid = 1.0
    return [(a, mid), (mid, b)] if a < mid < b else []


def first_windows(settings: Cover) -> list:
    """[0, σ_max] in ``initial`` pieces uniform in log(σ + scale) (one piece when σ_max = ∞)."""
    s_split, sigma_max = settings.split_scale, settings.sigma_max
    if np.isfinite(sigma_max) and settings.initial > 1:
        pts = np.exp(np.linspace(np.log(s_split), np.log(sigma_max + s_split), settings.initial + 1)) - s_split
        pts[0], pts[-1] = 0.0, sigma_max
        return list(zip(pts[:-1], pts[1:]))
    return [(0.0, sigma_max)]


@dataclass(frozen=True)
class WindowOutcome:
    """One window's decision: ``proved`` (``margin`` > 0, by ``how``), else split into
    ``halves``, else (no halves) the cover stops there with ``margin``."""

    proved: bool
    margin: float
    how: tuple | None
    halves: list = field(default_factory=list)


def certify_window(samples: Samples, a: float, b: float, tau: float) -> WindowOutcome:
    """Certify G(σ) ∈ R₀ on [a, b] (b = ∞ allowed): the seed scaling first, then the
    scaling optimised at σ_a and its powers."""
    st = samples.settings
    ca = samples.at(a)
    cb = samples.at(b) if np.isfinite(b) else None
    best = (-np.inf, None)
    if st.d_seed is not None:
        # the seed (near-optimal at σ = 0) often proves the window as it is: the 40
        # eigen-solves of an optimised scaling only when it does not
        best = window_certificate(ca, cb, st.mu, st.d_seed, tau, st.tol)
        if best[0] > 0:
            return WindowOutcome(True, *best)
        slack = samples.seed_slack(a)
        log.debug("window [%.4g, %.4g]: the seed misses by %.3g, its margin at σ_a %.3g", a, b, -best[0], slack)
        halves = split(a, b, st.split_scale)
        if (slack > 0 and -best[0] > HOPELESS_DEFICIT * slack and halves and samples.count < st.max_samples
                and not samples.optimised_for(a)):
            # missed by far more than the sample's own slack, which a better scaling only
            # raises: split at once; a scaling already optimised for σ_a costs only its
            # certificates, and is tried
            return WindowOutcome(False, *best, halves)
    dopt = samples.scaling(a)
    # the scaling that best proves sym(DG(σ_a)) ≻ 0 may have a range that inflates
    # (D − βI); try its powers D^t, t = 1, ½, 0 (D = I).  A failed try's margin is measured
    # only for the window that stops the cover: on the way it is a number nobody reads
    for t in (1.0, 0.5, 0.0):
        m, how = window_certificate(ca, cb, st.mu, dopt ** t, tau, st.tol, measure_failure=False)
        if m > best[0]:
            best = (m, how)
        if m > 0:
            return WindowOutcome(True, *best)
    # no window can start at a sample that is not itself certified: stop splitting
    halves = split(a, b, st.split_scale)
    if (pd_certificate(ca.G(st.mu), ca.error(st.mu), dopt, tol=st.tol).proved and samples.count < st.max_samples
            and halves):
        return WindowOutcome(False, *best, halves)
    margin = best[0] if np.isfinite(best[0]) else window_certificate(ca, cb, st.mu, dopt, tau, st.tol)[0]
    return WindowOutcome(False, margin, best[1])


def cover(condense_at, settings: Cover, *, sharper_tau=None, scalings: dict | None = None) -> Coverage:
    """Prove G(σ) ∈ R₀ for every σ in [0, settings.sigma_max] by windows.

    ``condense_at(σ)`` returns a :class:`~meicp.contact.condensation.Condensed` with the Ξ
    blocks.  ``sharper_tau()``: certifies a larger τ (e.g. ``settings.scale``) at the cost of
    a factorisation, returning it (or the old τ); called at most once, before the first chord
    it would tighten by a tenth or more — before the window's dense certificates, not after
    they fail (docs/benchmarks-notes.md, "sharper τ").  ``scalings``: see :class:`Samples`."""
    t0 = time.perf_counter()
    samples = Samples(condense_at, settings, scalings)
    tau, s_split = settings.tau, settings.split_scale
    windows, failed = [], None
    pending = first_windows(settings)
    ticker = Ticker("condensed proof", interval=0.0)  # once it has run a while: a line per window
    while pending:
        a, b = pending.pop(0)
        if (sharper_tau is not None and np.isfinite(b) and s_split > tau
                and chord_factor(a, b, s_split) < 0.9 * chord_factor(a, b, tau)):
            tau, sharper_tau = max(tau, sharper_tau()), None
        window = certify_window(samples, a, b, tau)
        outcome = "proved" if window.proved else "split" if window.halves else "not proved"
        ticker.say(lambda: f"window [{a:.4g}, {b:.4g}] {outcome}; {len(windows) + window.proved} window(s) "
                           f"proved, {len(pending) + len(window.halves)} left, {samples.count} condensation(s)")
        if window.proved:
            windows.append((a, b, window.margin, window.how))
        elif window.halves:
            pending[:0] = window.halves
        else:
            failed = (a, b, window.margin)
            break
    return Coverage(failed is None, windows, sorted(samples.condensed), failed, time.perf_counter() - t0, tau)
