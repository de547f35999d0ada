"""Condensed λ-windows carried over an interval of μ: a proof at any size that no damped
divergence mode (real λ ≥ 0 of ``y = (λ²B + λD − A)x``) exists for any μ in [start, reach],
every contact at the same μ — the damped divergence onset's lower end past the enumeration
(docs/critical-friction.md, "With damping").

With every contact at μ the friction rows are μ times the unit ones, ``N = μN₁``,
``N_C = μN_C1``, and ``H_FF(λ) = K̃_FF + λC̃_FF + λ²M̃_FF`` does not involve them.  So with the
unit rows in ``U = [K̃_JF; C̃_JF; N₁_JF; N_C1,JF]`` the condensation ``Ξ(λ) = U X(λ) Uᵀ`` is the
same at every μ (at μ its friction blocks are scaled by μ): one set of condensations serves
every μ, and the rest is dense work.

For one scaling W and one β the window bound of :mod:`.damped_windows`,
``sym(W G(λ; μ)) ⪰ 𝓜(λ, μ)``, is **concave in μ**: its first part is affine in μ (``H_JJ`` and
``b = μb₁`` are), and its second is ``−Π Δ Πᵀ/(4β)`` with ``Π = (W − βI)a + μWb₁`` and
``Δ = X_a − X_b ⪰ 0``, whose μ² coefficient ``−Wb₁Δb₁ᵀW/(4β)`` is ⪯ 0.  λ_min of a concave
matrix function is concave, so a window [λ_a, λ_b] proved at μ₀ and at μ₁ with the same W and
β (each end's margin with its own errors charged) is proved on [λ_a, λ_b] × [μ₀, μ₁].  The
cover starts with [start, top] and halves a μ interval that fails, left first, so what is
proved is [start, reach] whole.  The windows cover [0, λ_max] for the interval's top: ν(μ)
grows with μ and γ(μ) (Gershgorin's bound of sym(A(μ)), a maximum of functions affine in μ)
is convex, so the ceiling at ν(top) and the larger γ at the two ends holds at every μ of it.
Collective (the dense work on rank 0, the others serve its condensations).
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from ..core.comm import mpi_comm
from ..core.progress import Ticker
from ..lcp.certificates import optimise_scaling
from .damped_windows import (DampedCondenser, DampedPieces, G_at, NothingToCondense, Sample,
                             ceiling_of, cover_windows, damped_pieces, ordering_spread, window_margin_over)
from .on_root import decided_on_root

#: the seconds the cover may take (the dense work on rank 0)
MAX_SECONDS = 60.0
#: the condensations one μ interval may add to the λ-windows (where more are needed the interval is
#: halved instead: near a damped divergence onset the windows need splitting, away from it not)
NEW_PER_INTERVAL = 2
#: the condensations the whole cover may make
MAX_CONDENSATIONS = 64
#: the narrowest μ interval tried, relative to the top: the cover stops at one that fails
MIN_WIDTH = 1e-4
#: the first friction block of Ξ (K̃_JF, C̃_JF, N₁_JF, N_C1,JF)
N_BLOCK = 2


@dataclasses.dataclass(frozen=True)
class MuCover:
    """What :func:`prove_up_to` established: no damped divergence mode for μ in
    [start, reach] (``reach == start``: nothing proved), ``intervals`` of μ proved,
    ``condensations`` made, ``statement``."""

    start: float
    reach: float
    intervals: int
    condensations: int
    statement: str


def _at_friction(pieces: DampedPieces, mu: float) -> DampedPieces:
    """The unit pieces with every contact at μ: the friction rows scaled, ν(μ) = μν₁ + s
    (ν₁ = the unit pieces' ν ≥ their Gershgorin radius, s the congruence slack)."""
    return dataclasses.replace(pieces, N=mu * pieces.N, NC=mu * pieces.NC,
                               nu=mu * pieces.nu + pieces.slack * (1 + 1e-12))


def _scaled(sample: Sample, mu: float) -> Sample:
    """Ξ at μ: the friction blocks of the unit Ξ scaled by μ, the error by max(1, μ)²."""
    k = sample.Xi.shape[0] // 4
    d = np.ones(4 * k)
    d[N_BLOCK * k:] = mu
    return Sample(sample.lam, d[:, None] * sample.Xi * d[None, :], sample.error * max(1.0, mu) ** 2)


def prove_up_to(pen1, start: float, top: float, comm=None, *, tol: float = 1e-10, max_samples: int = MAX_CONDENSATIONS,
                seconds: float = MAX_SECONDS) -> MuCover:
    """How far above ``start`` (towards ``top``) no damped divergence mode exists at any μ, by
    λ-windows carried over μ (module docstring).  ``pen1``: the damped pencil with every
    contact at μ = 1 (its friction rows the unit ones).  Collective on ``comm`` (default the
    pencil's)."""
    comm = mpi_comm(pen1.comm if comm is None else comm)
    unit, why = damped_pieces(pen1)
    if unit is None or unit.J.size == 0:
        return MuCover(start, start, 0, 0, f"λ-windows over μ not tried: {why or 'no complementarity DOFs'}")
    ends = (_at_friction(unit, start), _at_friction(unit, top))
    lam_max = ceiling_of(ends[1].nu, max(p.gamma() for p in ends))
    free = dataclasses.replace(unit, N=0 * unit.N, NC=0 * unit.NC)
    JJ0, JJ1 = free.H_JJ(), unit.H_JJ()
    N_JJ, NC_JJ = JJ1[0] - JJ0[0], JJ1[1] - JJ0[1]
    with (DampedCondenser(comm, unit, pen1.maps.retained) if unit.F.size else NothingToCondense(unit)) as cond:
        why = cond.held()
        if why:
            return MuCover(start, start, 0, 0, f"λ-windows over μ: {why}")

        def decide(condense):
            return _cover_in_mu(condense, cond.tau, unit, JJ0, N_JJ, NC_JJ, start, top, lam_max, tol, max_samples,
                                seconds)

        reach, intervals, made, stop = decided_on_root(comm, decide, cond.at)
    text = (f"condensed λ-windows carried over μ: no divergence mode of any λ ≥ 0 for μ in [{start:.8g}, {reach:.8g}] "
            f"({intervals} μ interval(s) on {made} condensation(s), windows over [0, {lam_max:.6g}], each proved at both "
            f"ends of its μ interval with one scaling: the bound is concave in μ; Schur complements by MUMPS, error "
            f"measured: a measurement, not a bound){'; ' + stop if stop else ''}")
    return MuCover(start, reach, intervals, made, text)


def _cover_in_mu(condense, tau, unit, JJ0, N_JJ, NC_JJ, start, top, lam_max, tol, max_samples,
                 seconds) -> tuple[float, int, int, str]:
    """Rank 0: the μ intervals from ``start``; ``(reach, intervals proved, condensations, why it
    stopped)``."""
    made: dict = {}

    def condensed_at(lam):
        if lam not in made:
            made[lam] = condense(lam)
        return made[lam]

    scaled: dict = {}  # Ξ at the current interval's two μ: its λ-cover and both ends read them

    def at(mu):
        def sample(lam):
            if (mu, lam) not in scaled:
                scaled[mu, lam] = _scaled(condensed_at(lam), mu)
            return scaled[mu, lam]
        return sample

    def blocks_JJ(mu):
        return [JJ0[0] + mu * N_JJ, JJ0[1] + mu * NC_JJ, JJ0[2]]

    t0 = time.perf_counter()
    ticker = Ticker("damped λ-windows over μ", interval=5.0)
    reach, intervals, windows, hints = start, 0, None, {}
    pending = [(start, top)]
    while pending:
        m0, m1 = pending.pop(0)
        for key in [key for key in scaled if key[0] not in (m0, m1)]:
            del scaled[key]
        if time.perf_counter() - t0 > seconds:
            return reach, intervals, len(made), f"stopped after {time.perf_counter() - t0:.0f} s"
        used: dict = {}
        budget = min(max_samples, len(made) + NEW_PER_INTERVAL)  # a μ interval too wide splits in μ first
        ok, proved, _, _ = cover_windows(at(m1), blocks_JJ(m1), tau, _at_friction(unit, m1), lam_max, tol,
                                         budget, pending=windows, condensed=lambda: len(made), hints=hints,
                                         used=used)
        if ok and all(_both_ends(at, blocks_JJ, unit, tau, m0, m1, lo, hi, used, tol) for lo, hi, _ in proved):
            reach, intervals = m1, intervals + 1
            windows, hints = sorted((lo, hi) for lo, hi, _ in proved), used
            ticker.say(lambda: f"μ ≤ {reach:.6g} proved ({intervals} interval(s), {len(made)} condensation(s))")
            continue
        if m1 - m0 <= MIN_WIDTH * top:
            return reach, intervals, len(made), (f"the μ interval [{m0:.8g}, {m1:.8g}] is not proved (its λ-windows, "
                                                 f"{len(made)} condensations)")
        mid = 0.5 * (m0 + m1)
        pending[:0] = [(m0, mid), (mid, m1)]
    return reach, intervals, len(made), ""


def _both_ends(at, blocks_JJ, unit, tau, m0, m1, lo, hi, used, tol) -> bool:
    """Whether the window [lo, hi] is proved at μ = m0 and m1 with one scaling and one β (the
    λ-cover's at m1, else one optimised for both); ``used[lo]`` becomes that scaling."""
    ends = [(blocks_JJ(m), at(m)(lo), at(m)(hi)) for m in (m0, m1)]
    spread = ordering_spread(unit, tau, lo, hi)
    w = used[lo]
    if window_margin_over(ends, w, spread, tol)[0] > 0:
        return True
    w, _ = optimise_scaling([G_at(J, a) for J, a, _ in ends], d0=w, iters=40)
    used[lo] = w
    return window_margin_over(ends, w, spread, tol)[0] > 0
