"""No MEiCP solution with σ in a window [σ_a, σ_b], from condensations at its ends
(:mod:`.condensation`).

Lumped mass, a base contact or a frictional interface in centre-of-mass coordinates (B
diagonal, N_M = 0, M̃_FJ = 0).  In the M̃_F-orthonormal modes (ψ_i, λ_i) of (K̃_FF, M̃_F), for
σ ≥ σ_a

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

:func:`.cover.cover` chains windows from 0 to σ_max (a certified bound, e.g. the Rayleigh
quotient's) or ∞, splitting failed windows in log(σ + τ) at new samples.
"""
from __future__ import annotations

import numpy as np

from ...lcp.certificates import EPS, norm2_bound, pd_certificate, pd_margin, scaled

#: rounding of forming P Δ Pᵀ as C0 − βC1 + β²C2 (:func:`pdp`), in units of the terms' size
FORMING_ROUNDING = 16 * EPS


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
