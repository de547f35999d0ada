"""No MEiCP solution with σ in a window [σ_a, σ_b], from condensations at its ends
(:mod:`.condensation`).

Base contact with lumped mass (B diagonal, N_M = 0, M̃_FJ = 0).  In the M̃_F-orthonormal modes
(ψ_i, λ_i) of (K̃_FF, M̃_F), for σ ≥ σ_a

    G(σ) = G(σ_a) + (σ − σ_a) M_J + Σ_i φ_i(σ) w_i,   φ_i(σ) = (σ − σ_a)/(σ + λ_i),
    w_i = (K̃ + μN)_JF ψ_i ψ_iᵀ K̃_FJ / (σ_a + λ_i),

φ_i increasing in σ.  For a positive diagonal D and β > 0, completing the square per mode,

    xᵀ D w_i x · φ_i(σ_b) ≥ −(r_iᵀx)²/(4β)·…   summed:   Σ_i φ_i(σ_b)·min(0, xᵀDw_ix) ≥ −xᵀ P Δ Pᵀ x / (4β),
    P = (D − βI)K̃_JF + μ D N_JF,   Δ = H_FF(σ_a)⁻¹ − H_FF(σ_b)⁻¹  (Ξ blocks of both ends).

Two window tests follow (either proves G(σ) ∈ R₀ for all σ in [σ_a, σ_b]):

* ``end`` bound (σ_b = ∞ allowed, Ξ(∞) = 0): φ_i(σ) ∈ [0, φ_i(σ_b)], so
  xᵀDG(σ)x ≥ xᵀ[sym(DG(σ_a)) − PΔPᵀ/(4β)]x.
* ``chord`` bound (σ_b finite): with t = (σ − σ_a)/(σ_b − σ_a), G(σ) = (1 − t)G(σ_a) + tG(σ_b)
  + Σ_i e_i φ_i(σ_b) w_i with 0 ≤ e_i = t(1 − t)(σ_b − σ_a)/(σ + λ_i) ≤ ē (λ_i ≥ τ, a
  certified lower bound of λ_min(K̃_FF, M̃_F)), and λ_min is concave along the chord, so
  Q_a = sym(DG(σ_a)) − ē·PΔPᵀ/(4β) ≻ 0 and Q_b = sym(DG(σ_b)) − ē·PΔPᵀ/(4β) ≻ 0 suffice.
  ē ≈ 0.17 when σ_b + τ = 2(σ_a + τ): windows uniform in log(σ + τ).

:func:`cover` chains windows from 0 to σ_max (a certified bound, e.g. the Rayleigh quotient's)
or ∞, splitting failed windows in log(σ + τ) at new samples.
"""
from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field

import numpy as np

from ..lcp.certificates import EPS, norm2_bound, optimise_scaling, pd_certificate, pd_margin, scaled

log = logging.getLogger("meicp")

#: rounding of forming P Δ Pᵀ as C0 − βC1 + β²C2 (:func:`pdp`), in units of the terms' size
FORMING_ROUNDING = 16 * EPS
#: a window that the seed scaling misses by more than this many times the margin of
#: sym(D_seed G(σ_a)) ≻ 0 itself is split without optimising a scaling for σ_a (10⁶ DOFs,
#: slip+ μ = 1 and 3: the windows split missed by 25 to 9,000 times that margin, and the seed
#: proved every window after the splits)
HOPELESS_DEFICIT = 10.0


def chord_factor(sa: float, sb: float, tau: float) -> float:
    """ē = max over t ∈ [0, 1] of t(1 − t)(σ_b − σ_a)/(σ_a + t(σ_b − σ_a) + τ) (closed form
    of the maximiser of t(1−t)/(c + t) with c = (σ_a + τ)/(σ_b − σ_a))."""
    s = sb - sa
    if s <= 0 or not np.isfinite(tau):  # τ = ∞: no free DOF, G(σ) is linear in σ
        return 0.0
    c = (sa + tau) / s
    if c <= 0:  # σ_a = τ = 0: the supremum, approached as t → 0
        return 1.0
    t = -c + np.sqrt(c * c + c)  # d/dt [t(1−t)/(c+t)] = 0
    t = min(max(t, 0.0), 1.0)
    return float(t * (1 - t) / (c + t)) * (1 + 1e-12)


def pdp(ca, cb, mu: float, d: np.ndarray):
    """``β → (P Δ Pᵀ, error bound)`` for the window [ca.sigma, cb.sigma] (cb None: σ_b = ∞),
    P = (D − βI)K̃_JF + μDN_JF: the terms of the quadratic in β formed once, since a window
    tries several β (a few n² operations each instead of ten)."""
    if cb is None:
        dKK, dNK, dZ = ca.KK, ca.NK, ca.Z
        eKK, eNK, eZ = ca.error_S, ca.error_R, ca.error_Z
    else:
        dKK, dNK, dZ = ca.KK - cb.KK, ca.NK - cb.NK, ca.Z - cb.Z
        eKK, eNK, eZ = ca.error_S + cb.error_S, ca.error_R + cb.error_R, ca.error_Z + cb.error_Z
    # X(β) = E ∘ dKK ∘ Eᵀ + μ(E ∘ dNKᵀ ∘ D + D ∘ dNK ∘ E) + μ² D ∘ dZ ∘ D with E = d − β:
    # C0 − β·C1 + β²·dKK, symmetrised
    NKt = dNK.T * d[None, :]
    C0 = d[:, None] * dKK * d[None, :] + mu * (d[:, None] * NKt + (d[:, None] * dNK * d[None, :]))
    C0 += mu * mu * d[:, None] * dZ * d[None, :]
    C1 = d[:, None] * dKK + dKK * d[None, :] + mu * (NKt + d[:, None] * dNK)
    C0, C1, C2 = 0.5 * (C0 + C0.T), 0.5 * (C1 + C1.T), 0.5 * (dKK + dKK.T)
    dn = d.max()
    # the sum's rounding, which may cancel where β ≈ d, charged like the condensation's error
    sizes = [FORMING_ROUNDING * norm2_bound(C) for C in (C0, C1, C2)]

    def at(beta: float) -> tuple[np.ndarray, float]:
        en = np.abs(d - beta).max()
        rounding = sizes[0] + beta * sizes[1] + beta * beta * sizes[2]
        return C0 - beta * C1 + (beta * beta) * C2, float(en * en * eKK + 2 * mu * en * dn * eNK
                                                          + mu * mu * dn * dn * eZ + rounding)
    return at


def window_certificate(ca, cb, mu: float, d: np.ndarray, tau: float, tol: float = 0.0, *,
                       measure_failure: bool = True):
    """The best of the end and chord bounds over a few β.  Returns ``(margin, how)``:
    margin > 0 proves the window; ``how`` = (kind, β).  A bound whose matrix fails a Cholesky
    below its allowance is not eigen-solved (:func:`~meicp.lcp.certificates.pd_margin`);
    when every one fails so, the margin is that of the first end bound (with
    ``measure_failure``; else −inf, sparing an eigen-solve to say by how much it failed)."""
    best = (-np.inf, None)
    DGa = scaled(ca.G(mu), d)
    DGb = None if cb is None else scaled(cb.G(mu), d)
    eb = None if cb is None else chord_factor(ca.sigma, cb.sigma, tau)
    first = None
    correction = pdp(ca, cb, mu, d)
    for beta in [f * float(np.mean(d)) for f in (0.25, 0.5, 1.0, 2.0, 4.0)]:
        X, eX = correction(beta)
        # end bound
        Qa = DGa - X / (4 * beta)
        err_end = d.max() * ca.error(mu) + eX / (4 * beta)
        first = first or (Qa, err_end, beta)
        m_end = pd_margin(Qa, err_end, tol=tol)
        if m_end > best[0]:
            best = (m_end, ("end", beta))
        if cb is not None and best[0] <= 0:
            Qa = DGa - eb * X / (4 * beta)
            Qb = DGb - eb * X / (4 * beta)
            m = pd_margin(Qa, d.max() * ca.error(mu) + eb * eX / (4 * beta), tol=tol)
            if m > 0:
                m = min(m, pd_margin(Qb, d.max() * cb.error(mu) + eb * eX / (4 * beta), tol=tol))
            if m > best[0]:
                best = (m, ("chord", beta))
        if best[0] > 0:
            break
    if best[1] is None:  # every bound rejected by its Cholesky: say by how much the first misses
        Qa, err_end, beta = first
        best = (pd_certificate(Qa, err_end, None, tol=tol).margin if measure_failure else -np.inf, ("end", beta))
    return best


@dataclass
class Cover:
    proved: bool
    windows: list = field(default_factory=list)   # (σ_a, σ_b, margin, (kind, β))
    samples: list = field(default_factory=list)   # σ values condensed
    failed: tuple | None = None                   # (σ_a, σ_b, margin) of the window that stopped it
    seconds: float = 0.0
    tau: float = 0.0                              # the certified τ the chords used last


def cover(condense_at, mu: float, tau: float, *, sigma_max: float = np.inf, max_samples: int = 24,
          initial: int = 1, optimise: bool = True, d_seed: np.ndarray | None = None, tol: float = 0.0,
          scale: float | None = None, sharper_tau=None, scalings: dict | None = None) -> Cover:
    """Prove G(σ) ∈ R₀ for every σ in [0, σ_max] (σ_max = ∞ allowed) by windows.

    ``condense_at(σ)`` returns a :class:`~.condensation.Condensed` with the Ξ blocks.  ``tau``: the
    certified lower bound of λ_min(K̃_FF, M̃_F).  ``scale``: where windows are split (default τ; an
    estimate of λ_min, certified or not: it moves the samples, not the bounds).  ``sharper_tau()``:
    certifies a larger τ (e.g. ``scale``) at the cost of a factorisation, returning it (or the
    old τ); called at most once, before the first chord it would tighten by a tenth or more.
    ``d_seed``: the starting scaling of every sample's optimisation (e.g. the critical-friction
    bracket's D, near-optimal at σ = 0), and the first tried on every window; a window it misses
    by more than ``HOPELESS_DEFICIT`` times its own margin at σ_a is split without optimising a
    scaling for σ_a.  ``scalings``: optimised scalings already known, by σ (e.g. the caller's
    own at σ = 0: optimising again from it gains nothing, 1 s at |J| = 1,000).  The first
    windows split [0, σ_max] uniformly in log(σ + scale) into ``initial`` pieces (with
    σ_max = ∞: [0, ∞) first); a failed window is split at the geometric mean of its σ + scale
    ends, until ``max_samples`` condensations.
    """
    t0 = time.perf_counter()
    cache, d_cache = {}, dict(scalings or {})
    s_split = max(tau, scale) if scale else tau

    def at(s):
        if s not in cache:
            cache[s] = condense_at(s)
        return cache[s]

    def scaling(s):
        if s not in d_cache:
            G = at(s).G(mu)
            d = np.ones(G.shape[0]) if d_seed is None else d_seed
            if optimise:
                d, _ = optimise_scaling([G], d0=d, iters=40)
            if d_seed is not None and (pd_certificate(G, at(s).error(mu), d_seed).margin / d_seed.mean()
                                       > pd_certificate(G, at(s).error(mu), d).margin / d.mean()):
                d = d_seed
            d_cache[s] = d
        return d_cache[s]

    def seed_slack(s):
        """The margin of sym(D_seed G(σ)) ≻ 0 at a sample (once)."""
        if s not in slack_cache:
            slack_cache[s] = pd_certificate(at(s).G(mu), at(s).error(mu), d_seed, tol=tol).margin
        return slack_cache[s]

    def split(a, b):
        """The two halves of [a, b] in log(σ + scale), or [] where rounding (or a zero scale)
        leaves no point strictly inside: the cover then stops there instead of looping."""
        mid = 2.0 * a + s_split if not np.isfinite(b) else np.sqrt((a + s_split) * (b + s_split)) - s_split
        if not np.isfinite(b) and a == 0:
            mid = 1.0
        return [(a, mid), (mid, b)] if a < mid < b else []

    slack_cache = {}
    out = Cover(False)
    if np.isfinite(sigma_max) and initial > 1:
        pts = np.exp(np.linspace(np.log(s_split), np.log(sigma_max + s_split), initial + 1)) - s_split
        pts[0], pts[-1] = 0.0, sigma_max
        pending = list(zip(pts[:-1], pts[1:]))
    else:
        pending = [(0.0, sigma_max)]
    while pending:
        a, b = pending.pop(0)
        if (sharper_tau is not None and np.isfinite(b) and s_split > tau
                and chord_factor(a, b, s_split) < 0.9 * chord_factor(a, b, tau)):
            # before the window's dense certificates, not after they fail: at |J| = 2,000 a
            # failed try cost 4 s more than the inertia
            tau, sharper_tau = max(tau, sharper_tau()), None
        ca = at(a)
        cb = at(b) if np.isfinite(b) else None
        best = (-np.inf, None)
        if d_seed is not None:
            # the seed (near-optimal at σ = 0) often proves the window as it is: the 40
            # eigen-solves of an optimised scaling only when it does not
            best = window_certificate(ca, cb, mu, d_seed, tau, tol)
            if best[0] > 0:
                out.windows.append((a, b, best[0], best[1]))
                continue
            slack = seed_slack(a)
            log.debug("window [%.4g, %.4g]: the seed misses by %.3g, its margin at σ_a %.3g", a, b, -best[0], slack)
            halves = split(a, b)
            if (slack > 0 and -best[0] > HOPELESS_DEFICIT * slack and halves and len(cache) < max_samples
                    and (a not in d_cache or d_cache[a] is d_seed)):
                # missed by far more than the sample's own slack, which a better scaling only
                # raises: split at once (at 10⁶ DOFs the optimised scaling of a sample, 1 s,
                # proved no window that the seed did not prove after the split); a scaling
                # already optimised for σ_a costs only its certificates, and is tried
                pending[:0] = halves
                continue
        dopt = scaling(a)
        # the scaling that best proves sym(DG(σ_a)) ≻ 0 may have a range that inflates
        # (D − βI); try its powers D^t, t = 1, ½, 0 (D = I)
        # (a failed try's margin is measured only for the window that stops the cover: on the
        # way it is 0.04 s of a try's 0.13 s at |J| = 1,000, for a number nobody reads)
        for t in (1.0, 0.5, 0.0):
            m, how = window_certificate(ca, cb, mu, dopt ** t, tau, tol, measure_failure=False)
            if m > best[0]:
                best = (m, how)
            if m > 0:
                break
        if best[0] > 0:
            out.windows.append((a, b, best[0], best[1]))
            continue
        # no window can start at a sample that is not itself certified: stop splitting
        halves = split(a, b)
        if (not pd_certificate(ca.G(mu), ca.error(mu), dopt, tol=tol).proved or len(cache) >= max_samples
                or not halves):
            margin = best[0] if np.isfinite(best[0]) else window_certificate(ca, cb, mu, dopt, tau, tol)[0]
            out.failed = (a, b, margin)
            break
        pending[:0] = halves
    else:
        out.proved = True
    out.samples = sorted(cache)
    out.seconds = time.perf_counter() - t0
    out.tau = tau
    return out
