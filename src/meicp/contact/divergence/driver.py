"""The divergence verdict of one contact state's MEiCP (docs/design.md §8): its certified
modes with σ ≥ 0, or a proof that none exists, or *undecided* with what was established.

Small reduced problems are enumerated (:mod:`.enumeration`).  Larger ones go through the
window procedure, cheapest first, one step each (:mod:`.steps`):

1. **Rayleigh bound at 0** (one LDLᵀ), unless a short Lanczos run on (sym A, sym B), made
   first (:func:`.sigma_window.probe_top`), has a Ritz value θ > 0.
2. **First search**: a short active-set search (:mod:`.search`) from the contact-strip
   proxy's rightmost real σ (times :data:`.search.PROXY_SHIFT`) when below the window's top θ,
   else from θ; only when θ > 0 beyond rounding: with the top at or below 0 it starts in the cluster of
   slow vibrations and gives up after one restart
   (docs/benchmarks-notes.md, "first search only above 0"), so the proof comes first and the
   whole search after it; and not when the proxy has no real σ above 0 (it found nothing from
   the top on every scene measured: "no first search without a proxy mode").
3. **Condensed proof** on [0, ∞) (:func:`.condensed.prove_no_divergence`).  Where it cannot
   exclude σ = 0 itself and the first search found nothing, short searches from shifts below
   the first one (:func:`.search.searches_below`): a mode just above 0 sits among the slow
   vibrations seen from the top, where the whole search reaches it last.
4. **σ-window**, only where that proof stopped at some σ = c: a certified σ_max
   (:mod:`.sigma_window`); ``σ_max ≤ c`` completes the proof, else the search goes on from σ_max.
5. **Whole search** with its whole budget; then, only if the caller or the scene asked
   ``nev`` > 1 and it found nothing, the same search with ``nev`` eigenpairs per solve (every
   search before follows one: :mod:`.search`).
6. Otherwise **undecided**, saying what was proved, with the friction up to which these
   contact states are proved free of divergence.

Why a short search before the proof and the whole one after: a mode on the full support, or
one support update away, is found at once, while on a stable lattice a long search finds
nothing and costs more than the proof (docs/benchmarks-notes.md, "search before proof").
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass
from typing import Callable

from ...scene import Scene
from ..problem import Pencil
from . import steps
from .condensed import prove_no_divergence
from .enumeration import enumeration_is_small, named_method_verdict
from .search import Tally, first_search, search_settings, searches_below, whole_search, widened_search
from .sigma_window import certified_sigma_max, no_sigma_max, probe_top, ritz_estimate
from .verdict import DivergenceVerdict

log = logging.getLogger("meicp")


@dataclass(frozen=True)
class Procedures:
    """The two computations of the window procedure that a caller (a test) may replace to
    reach a branch: ``estimate_top(A, B, *, max_it) -> (θ, converged, restarts)``, the
    Lanczos estimate of λ_max(sym A, sym B); ``prove(comm, pen, sigma_max, *, tol)``, the
    condensed proof (a :class:`~.condensed.CondensedProof`)."""

    estimate_top: Callable = ritz_estimate
    prove: Callable = prove_no_divergence


#: the procedures a verdict runs unless told otherwise
PROCEDURES = Procedures()


def divergence_of(pen: Pencil, scene: Scene, comm, method, lam_min: float, tol: float, options, *,
                  procedures: Procedures = PROCEDURES) -> DivergenceVerdict:
    """The :class:`~.verdict.DivergenceVerdict` of one pencil: its certified modes with
    σ ≥ lam_min and the verdict on σ ≥ 0.  method: ``"enumerate"``, ``"active-set"`` (the
    window procedure), another :func:`~meicp.eicp.solve.solve_eicp` method, or None /
    ``"auto"`` (enumeration when small).  options: the caller's solver keywords.  Collective
    on ``comm``."""
    red = pen.maps
    small = enumeration_is_small(red.retained.size, red.J.size)
    chosen = method if method not in (None, "auto") else ("enumerate" if small else "active-set")
    if chosen == "active-set":
        return window_verdict(pen, scene, comm, lam_min, tol, options, procedures)
    return named_method_verdict(pen, comm, chosen, lam_min, tol, options)


def window_verdict(pen: Pencil, scene: Scene, comm, lam_min: float, tol: float, options,
                   procedures: Procedures = PROCEDURES) -> DivergenceVerdict:
    """The window procedure, steps 1–6 of the module's docstring.  Collective on ``comm``."""
    A, B = pen.A, pen.B
    started = time.perf_counter()
    top = probe_top(A, B, procedures.estimate_top)
    verdict, why = steps.bound_at_zero(pen, top, started)
    if verdict is not None:
        return verdict
    reasons = [why]
    settings = search_settings(pen, scene, comm, lam_min, tol, options, top.shift, started)
    first = first_search(settings, scene) if top.positive else None
    if first is not None and first.found:
        return steps.mode_found(first, None)
    condensed = steps.condensed_proof(pen, comm, tol, procedures.prove, started)
    if condensed.proved:
        return steps.proved_by_condensation(condensed, first)
    if first is not None and not first.found and steps.covered_by_condensation(condensed) == -math.inf:
        # σ = 0 itself not excluded and nothing at the first shift: a slow mode just above 0,
        # which the whole search from the top reaches last (docs/benchmarks-notes.md, "slow mode")
        first, shifts = searches_below(settings.from_shift(first.target), first)
        if first.found:
            return steps.mode_found(first, None)
        reasons.append(f"short searches from σ = {', '.join(f'{s:.3g}' for s in shifts)} found no mode")
    sigma_max, top = certified_sigma_max(A, B, top, procedures.estimate_top)
    log.info("divergence: σ-window [0, %s] (%.2f s)", "?" if sigma_max is None else f"{sigma_max:.6g}",
             time.perf_counter() - started)
    if sigma_max is not None and sigma_max <= steps.covered_by_condensation(condensed):
        return steps.completed_by_sigma_max(condensed, sigma_max, first)
    if sigma_max is None:
        reasons.append(no_sigma_max(top))
    else:
        settings = settings.from_shift(sigma_max)  # the whole search from the certified top
    reasons.append(f"condensed test: {condensed.statement}")
    window = tuple(float(v) for v in condensed.window) if condensed.window else None
    last = first
    if first is None or settings.whole_search_left:
        last = whole_search(settings, Tally() if first is None else first.tally)
        if last.found:
            return steps.mode_found(last, window)
    origin = last.target  # the whole search's shift, or the first search's when it was the last
    lower = []
    if last.eicp.status == "not_converged":
        last, lower = searches_below(settings, last)
        if last.found:
            return steps.mode_found(last, window)
    if settings.widened_nev:
        last = widened_search(settings, last.tally)
        if last.found:
            return steps.mode_found(last, window)
    below = f" and from {len(lower)} lower shift(s) down to {lower[-1]:.3g}" if lower else ""
    widened = f", the last with nev = {settings.widened_nev}," if settings.widened_nev else ""
    reasons.append(f"the search from σ = {origin:.6g}{below}{widened} over {last.tally.supports_visited} "
                   f"support(s) found no mode ({last.eicp.status})")
    if settings.full_budget is not None and (not settings.whole_search_left or last.eicp.status == "max_iterations"):
        # the caller's or the scene's budget, not the search, ended it: say which option
        why = (f"max_iterations = {settings.full_budget} (the [solver] table or the caller) ended the search "
               f"after {last.tally.supports_visited} support(s): without it the search has its own budget")
        log.warning("divergence undecided: %s", why)
        reasons.append(why)
    return steps.undecided(pen, top, reasons, last, window, started)
