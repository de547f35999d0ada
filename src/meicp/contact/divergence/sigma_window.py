"""The top of the divergence σ-window: an estimate of ``λ_max(sym A, sym B)`` and its
certificate.

Every MEiCP solution satisfies ``σ = xᵀsym(A)x / xᵀsym(B)x`` (complementarity gives
``xᵀw = 0``), so no divergence mode lies above ``λ_max(sym A, sym B)``; the same bound holds
for the real part of every eigenvalue of every support's pencil.  Lanczos on the
symmetric-definite pencil (:func:`meicp.petsc.lanczos.largest_ritz_value`) finds it without a
factorisation when the top is isolated; when it sits in the cluster of slow vibrations near 0
Lanczos needs hundreds of restarts, so they are capped and the last Ritz value is used.  A
Ritz value is a *lower* estimate — itself a Rayleigh quotient, so θ > 0 shows that sym(A) is
not negative definite: the window claim is made by the Rayleigh bound at τ above θ
(:func:`certified_top`, one LDLᵀ inertia each), never by the estimate.  Without sym(B) ≻ 0 (a one-row
layer between two frictional interfaces at large μ, where B is not diagonal) no Rayleigh
quotient bounds σ and Lanczos would break down:
nothing is estimated.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from ...core.matrix import max_abs_entry
from ...petsc.lanczos import largest_ritz_value
from ..rayleigh import rayleigh_bound, symmetric_part_definite

#: a Ritz value of (sym A, sym B) above this multiple of max|A|/max|B| is positive beyond
#: rounding: the Rayleigh bound at 0 is then not tried
RITZ_POSITIVE = 1e-8
#: Lanczos restarts of the short run that decides whether the Rayleigh bound at 0 is tried
#: (an isolated positive top shows a positive Ritz value within a few restarts)
PROBE_RESTARTS = 5
#: Lanczos restarts of the whole run that places σ_max (after a short run that did not converge)
WINDOW_RESTARTS = 60
#: residual tolerance of the top Ritz pair: a Ritz value of a symmetric-definite pencil is
#: exact to about the square of its residual, and the window is certified by an inertia
#: 1e-3 above θ (docs/benchmarks-notes.md, "ESTIMATE_TOL")
ESTIMATE_TOL = 1e-5
#: σ_max candidates tried above the Lanczos estimate θ: τ = θ⁺·(1 + GAP·4^k) + floor
WINDOW_GAP = 1e-3
WINDOW_TRIES = 3


def ritz_estimate(A, B, *, max_it: int) -> tuple[float, bool, int]:
    """``(θ, converged, restarts)``: the largest Ritz value of ``(sym A, sym B)`` in at most
    ``max_it`` Lanczos restarts, a lower estimate of λ_max (nan when SLEPc fails)."""
    return largest_ritz_value(A, B, max_it=max_it, tol=ESTIMATE_TOL)


@dataclass(frozen=True)
class TopEstimate:
    """What the short Lanczos run established about the top of the σ-window.

    b_definite: sym(B) ≻ 0 was proved (else nothing was estimated: θ is nan).  theta: the
    largest Ritz value (nan when not estimated).  converged: its residual met ESTIMATE_TOL.
    scale: max|A| / max|B|, the unit of σ for rounding tests.  positive: θ exceeded
    RITZ_POSITIVE·scale in the *short* run (sym A is then not negative definite, and the top
    stands clear of the cluster of slow vibrations where Lanczos stalls)."""

    b_definite: bool
    theta: float
    converged: bool
    scale: float
    positive: bool

    @property
    def shift(self) -> float:
        """The search's first shift: just above the estimated top (0 without one): the first
        pair taken is then the rightmost eigenvalue of the full support."""
        return max(self.theta if math.isfinite(self.theta) else 0.0, 0.0) * 1.001 + 1e-10 * self.scale


def probe_top(A, B, estimate=ritz_estimate) -> TopEstimate:
    """Whether sym(B) ≻ 0, and the short Lanczos run (PROBE_RESTARTS) on (sym A, sym B).

    First, because a Ritz value θ > 0 spares the Rayleigh bound at 0 (one LDLᵀ of the whole
    pencil) that could then prove nothing; short, because where sym(A) ≺ 0 the top sits among
    the slow vibrations just below 0 and a full run stalls for its whole budget before the bound
    proves stability anyway (docs/benchmarks-notes.md, "short Lanczos run").  Its options:
    -meicp_window_* on the command line."""
    b_definite, _ = symmetric_part_definite(B)
    theta, converged = estimate(A, B, max_it=PROBE_RESTARTS)[:2] if b_definite else (math.nan, False)
    scale = max_abs_entry(A) / max(max_abs_entry(B), 1e-300)
    return TopEstimate(b_definite, theta, converged, scale, theta > RITZ_POSITIVE * scale)


def certified_sigma_max(A, B, top: TopEstimate, estimate=ritz_estimate) -> tuple[float | None, TopEstimate]:
    """``(σ_max, top)``: a τ above which the Rayleigh bound proves no MEiCP solution, or None;
    and the estimate it rests on (the whole Lanczos run when the short one did not converge).

    Looked for only after a positive Ritz value: with none in the short run the top sits in
    the cluster of slow vibrations (the bound at 0 failed on it) and the whole run stalls for
    its budget (docs/benchmarks-notes.md, "σ-window")."""
    if not (top.b_definite and top.positive):
        return None, top
    if not top.converged:
        theta, converged = estimate(A, B, max_it=WINDOW_RESTARTS)[:2]
        top = replace(top, theta=theta, converged=converged)
    # an unconverged Ritz value lies below λ_max: certifying above it wastes factorisations
    return (certified_top(A, B, top.theta, top.scale) if top.converged else None), top


def certified_top(A, B, theta: float, scale: float) -> float | None:
    """The smallest τ tried above the estimate θ of λ_max(sym A, sym B) that the Rayleigh
    bound certifies (no MEiCP solution has σ ≥ τ), or None."""
    if not math.isfinite(theta):
        return None
    for k in range(WINDOW_TRIES):
        tau = max(theta, 0.0) * (1.0 + WINDOW_GAP * 4 ** k) + 1e-10 * scale * 4 ** k
        if rayleigh_bound(A, B, tau, decisive=False).proved:
            return tau
    return None


def no_sigma_max(top: TopEstimate) -> str:
    """Why no σ_max was certified, for an undecided verdict."""
    if not math.isfinite(top.theta):
        return "no σ-window (λ_max(sym A, sym B) not estimated)"
    if not top.positive and not top.converged:
        return (f"no σ_max: no Ritz value of (sym A, sym B) above 0 in {PROBE_RESTARTS} Lanczos restarts "
                f"(largest {top.theta:.6g}; the top lies among the slow vibrations, where Lanczos stalls)")
    return f"no σ_max certified above the estimate {top.theta:.6g} of λ_max(sym A, sym B)"
