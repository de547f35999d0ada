"""The steps of the window procedure (:func:`.driver.window_verdict`), one function each:
every step either decides — it returns the :class:`~.verdict.DivergenceVerdict` — or says
what it established for the next."""

from __future__ import annotations

import logging
import math
import time

from ..friction_range import proved_friction_range
from ..rayleigh import pencil_bound, rayleigh_bound
from .search import SearchOutcome
from .sigma_window import TopEstimate
from .verdict import DivergenceProof, DivergenceVerdict

log = logging.getLogger("meicp")


def _window_proof(test: str, statement: str, sigma_window, outcome: SearchOutcome | None, **more) -> DivergenceProof:
    tally = (0, 0) if outcome is None else (outcome.tally.supports_visited, outcome.tally.eigen_solves)
    return DivergenceProof(test, statement, supports_visited=tally[0], sigma_window=sigma_window,
                           eigen_solves=tally[1], **more)


def bound_at_zero(pen, top: TopEstimate, started: float) -> tuple[DivergenceVerdict | None, str]:
    """1. The Rayleigh bound at 0 — ``sym(A) ≺ 0`` with ``sym(B) ≻ 0`` proves that no σ ≥ 0
    exists (one factorisation; any pencil, interfaces included) — unless the short run's
    Ritz value θ > 0 already rules it out (θ is a Rayleigh quotient).  Returns the proof's
    verdict, or None and why it stopped."""
    if top.positive:
        return None, (f"Rayleigh bound at 0: not tried, the Ritz value θ = {top.theta:.6g} > 0 of (sym A, sym B) is a "
                      "Rayleigh quotient: sym(A) is not negative definite")
    at_zero = pencil_bound(pen, 0.0)
    log.info("divergence: Rayleigh bound at 0 %s (%.2f s)", "proved" if at_zero.proved else "not proved",
             time.perf_counter() - started)
    if not at_zero.proved:
        return None, f"Rayleigh bound at 0: {at_zero.reason}"
    text = (f"Rayleigh bound (LDLᵀ inertia): {at_zero.reason}; every MEiCP solution has σ = "
            "xᵀsym(A)x / xᵀsym(B)x < 0 (a proof)")
    return DivergenceVerdict([], True, text, None, _window_proof("rayleigh-inertia", text, (0.0, math.inf), None)), ""


def mode_found(outcome: SearchOutcome, sigma_window) -> DivergenceVerdict:
    """2. and 5. A search found a certified mode: divergence."""
    text = (f"search from σ = {outcome.target:.6g}: a certified divergence mode after "
            f"{outcome.tally.eigen_solves} eigen-solve(s), {outcome.tally.supports_visited} support(s)"
            f"{outcome.modes.note}")
    return DivergenceVerdict(outcome.modes.listed, False, text, outcome.eicp,
                             _window_proof("certified-mode", text, sigma_window, outcome))


def condensed_proof(pen, comm, tol: float, prove, started: float):
    """3. The condensed proof on [0, ∞) (:func:`.condensed.prove_no_divergence`): its last
    window [σ_a, ∞) costs no more condensations than one ending at a certified σ_max, which
    would cost a Lanczos run and an LDLᵀ first (docs/benchmarks-notes.md, "condensed proof")."""
    condensed = prove(comm, pen, math.inf, tol=tol)
    log.info("divergence: condensed proof %s, %d condensation(s) (%.2f s%s)",
             "holds" if condensed.proved else "stopped", condensed.samples, time.perf_counter() - started,
             "".join(f", {k} {v:.1f}" for k, v in condensed.seconds.items()))
    return condensed


def _eicp(outcome: SearchOutcome | None):
    return None if outcome is None else outcome.eicp


def proved_by_condensation(condensed, first: SearchOutcome | None) -> DivergenceVerdict:
    """3. The condensed proof holds on [0, ∞): no divergence (``first``: the first search,
    None when it was not made)."""
    text = f"{condensed.statement} (a proof)"
    return DivergenceVerdict([], True, text, _eicp(first), _window_proof(
        condensed.test, text, (0.0, math.inf), first, margin=condensed.margin))


def covered_by_condensation(condensed) -> float:
    """The σ up to which the stopped condensed proof covered [0, ·] (−∞: not even σ = 0)."""
    return condensed.window[1] if condensed.window else -math.inf


def completed_by_sigma_max(condensed, sigma_max: float, first: SearchOutcome | None) -> DivergenceVerdict:
    """4. No solution above σ_max (Rayleigh bound) and none in [0, c ≥ σ_max] (condensed)."""
    covered = covered_by_condensation(condensed)
    text = (f"no solution above σ_max = {sigma_max:.6g} (Rayleigh bound, LDLᵀ inertia) and none in "
            f"[0, {covered:.6g}] by the condensed windows ({condensed.statement}) (a proof)")
    return DivergenceVerdict([], True, text, _eicp(first), _window_proof(
        "rayleigh-window+condensed-windows", text, (0.0, sigma_max), first, margin=condensed.margin))


def undecided(pen, top: TopEstimate, reasons: list[str], last: SearchOutcome, sigma_window,
              started: float) -> DivergenceVerdict:
    """6. Undecided, saying what was proved: the window, the supports visited, why each proof
    stopped, and the friction up to which these contact states are proved free of divergence
    (:mod:`..friction_range`: the Rayleigh bound along μ)."""
    t = time.perf_counter()
    if top.b_definite:
        # the first bound (when tried) spared the inertia that tells "within rounding of 0" (rigid
        # motions, a borderline μ) from a clear failure; an undecided verdict says which
        reasons = [f"Rayleigh bound at 0: {rayleigh_bound(pen.A, pen.B, 0.0).reason}", *reasons[1:]]
    reach = proved_friction_range(pen)
    log.info("divergence: friction range proved up to %.4g× the scene's (%d inertias, %.2f s)", reach.scale,
             reach.factorisations, time.perf_counter() - t)
    text = "undecided: " + "; ".join(reasons) + f"; {reach.statement}"
    return DivergenceVerdict([], None, text, last.eicp, _window_proof(
        "", text, sigma_window, last, stable_friction_scale=reach.scale, stable_friction=dict(reach.friction)))

