"""The critical friction past the enumeration limit, as a certified bracket: the lower end
a proof on the condensed ``S + μR`` (:mod:`..mu_bracket`), the upper end a σ = 0 mode found
by a search on the condensed problem, lifted and certified on the whole reduced lattice
(docs/critical-friction.md).  The condensation is :class:`~..condenser.Condenser`'s, by MUMPS,
collective on ``comm``; the dense work runs on rank 0."""

from __future__ import annotations

import logging
import time

import numpy as np

from ...core import limits
from ...core.errors import ConvergenceError, ProblemError
from ...eicp.problem import EiCPProblem, certify_pair
from ..condensation import lift
from ..condenser import Condenser
from ..mu_bracket import extend_lower, lower_end, lower_from_mode, upper_candidates
from ..on_root import on_root
from .enumerated import singular_message
from .result import EXACT_WIDTH

log = logging.getLogger("meicp")

#: certificate residual of a σ = 0 mode lifted to the whole reduced lattice
MODE_TOL = 1e-9
#: the search stops once a mode within this relative distance of the proved lower end is found
SEARCH_CLOSE = 1e-3
#: condensed candidates lifted (one solve each) before the upper end is given up
MAX_LIFTS = 20


def bracket(comm, red, K, M, A1, B1, mu_max: float) -> tuple[float, float, str]:
    """``(lower, upper, evidence)`` of one grazing case's reduced system ``red`` (K, M the
    lattice's SciPy matrices, A′ and B′ its EiCP in μ); collective."""
    with Condenser(comm, red, K, M, friction="unit") as cond:
        low, upper, mode_text = _ends(comm, cond, red, A1, B1, mu_max)
        error_text = cond.error_text()
    lower = min(low.mu, upper)
    text = f"|J| = {red.J.size}: lower end {low.evidence}; upper end {mode_text}; {error_text}"
    return lower, upper, text


def _ends(comm, cond, red, A1, B1, mu_max: float):
    """The proved lower end (a :class:`~..mu_bracket.LowerEnd`), the certified upper end and
    its sentence (collective; the dense work on rank 0)."""
    clock = time.perf_counter()

    def lap(name):
        nonlocal clock
        now = time.perf_counter()
        cond.seconds[name] = cond.seconds.get(name, 0.0) + now - clock
        clock = now

    if not cond.prepare(need_tau=False, keep_factor=True):
        raise ProblemError(singular_message(cond.why))
    clock = time.perf_counter()  # prepare timed its own steps (held, probe)
    c0 = cond.at(0.0, xi=False)
    lap("condense")
    S, R, eS, eR = c0.S, c0.R, c0.error_S, c0.error_R

    def dense_ends():
        low = lower_end(S, R, eS, eR, mu_max=mu_max)
        lap("lower")
        candidates = upper_candidates(S, R, near=max(low.mu, low.mu_pd), mu_max=mu_max, d=low.d,
                                      good_enough=low.mu * (1 + SEARCH_CLOSE), seconds=limits.CRITICAL_DENSE_SECONDS)
        lap("search")
        return low, candidates

    low, candidates = on_root(comm, dense_ends)
    upper, mode_x = np.inf, None
    mode_text = f"no σ = 0 mode found up to μ = {mu_max:g} ({len(candidates)} condensed candidates)"
    problem = EiCPProblem.from_data(A1, B1, red.J)
    with cond.factor_FF(0.0) as solve:
        for mu, xJ in candidates[:MAX_LIFTS]:
            if mu >= upper:
                break
            sol = certify_pair(problem, mu, lift(cond.pieces, 0.0, xJ, solve))
            if sol.residual <= MODE_TOL:
                upper, mode_x = mu, xJ
                mode_text = (f"σ = 0 mode at μ = {mu:.10g} on {sol.support.size} of {red.J.size} contact DOFs, "
                             f"certified on the whole reduced lattice (residual {sol.residual:.1e})")
    lap("lift")
    if low.mu > upper * (1 + 1e-12):
        raise ConvergenceError(f"critical_friction: proof of no σ = 0 mode up to μ = {low.mu:.10g} above the "
                               f"certified mode at μ = {upper:.10g}: a rounding blunder, no bracket")

    def refine(low):
        if mode_x is not None and upper - low.mu > EXACT_WIDTH * upper:
            low = lower_from_mode(low, S, R, eS, eR, upper, mode_x)
        if not np.isfinite(upper) or upper - low.mu > EXACT_WIDTH * upper:
            low = extend_lower(low, S, R, eS, eR, mu_cap=min(upper, mu_max), seconds=limits.CRITICAL_DENSE_SECONDS)
        return low

    low = on_root(comm, lambda proved=low: refine(proved))
    lap("refine")
    log.info("critical_friction: |J| = %d, %s", red.J.size,
             ", ".join(f"{k} {v:.1f} s" for k, v in cond.seconds.items()))
    return low, upper, mode_text
