"""The divergence verdict of one contact state's MEiCP (docs/design.md §8): its certified
modes with σ ≥ 0, or a proof that none exists, or *undecided* with what was established.

Small reduced problems are enumerated (every support: the modes, or a proof of none); an
enumeration asked for by name is refused past ``ENUMERATE_J`` pairs unless ``max_j`` raises
the limit, or past ``ENUMERATE_MAX_FLOPS`` of work (2^|J|·r³, about an hour) unless ``max_j``
is given (:func:`check_enumeration_size`).  Larger ones are decided, cheapest first:

1. **Rayleigh bound at 0** — complementarity gives ``xᵀw = 0``, so every solution has
   ``σ = xᵀsym(A)x / xᵀsym(B)x``: ``sym(A) ≺ 0`` with ``sym(B) ≻ 0`` (LDLᵀ inertias with a
   margin above rounding, :func:`meicp.petsc.inertia.rayleigh_bound`) proves that no σ ≥ 0
   exists.  One factorisation; it holds for any pencil, interfaces included.  Not tried
   when a short Lanczos run on (sym A, sym B), made first, has a Ritz value θ > 0: θ is
   itself a Rayleigh quotient, so sym(A) is not negative definite.
2. **Modes from the top**: the SLEPc active-set search (:mod:`meicp.eicp.active_set`) with
   its shift at the short run's estimate θ of λ_max(sym A, sym B) — it bounds the real part
   of every eigenvalue of every support's pencil — so the first pair it takes is the
   rightmost eigenvalue of the full support S = J, never the slow vibrations clustered just
   below 0 that a shift at 0 returns; each support update follows that pair.  A returned
   mode is certified on the whole reduced problem.  First a short search (``FIRST_SEARCH``
   support updates, ``FIRST_EPS_MAX_IT`` restarts each), given up after ``FIRST_GIVE_UP``
   restarts when every Ritz value estimates an eigenvalue below 0.
3. **Condensed proof**: no mode found ⇒ ``G(σ) ∈ R₀`` on every window of ``[0, ∞)``
   (:func:`meicp.contact.divergence_proof.prove_no_divergence`).
4. **The σ-window**, only where that proof stopped at some σ = c: ``σ_max`` placed by Lanczos
   on ``(sym A, sym B)`` (:func:`meicp.petsc.window.rayleigh_estimate`) and certified by the
   bound of step 1 at ``τ = σ_max`` (no solution above it); ``σ_max ≤ c`` completes the
   proof.  Not looked for when the short run found no Ritz value above 0 (the top then sits
   in the cluster of slow vibrations, where Lanczos stalls).  Otherwise the search again,
   from σ_max, with its whole budget.
5. Otherwise **undecided**, saying what was proved: the window, the supports visited, why
   each proof stopped, and the friction up to which these contact states are proved free
   of divergence (:mod:`.friction_range`: the Rayleigh bound along μ).

A verdict is returned with a structured ``proof`` dict (test, statement, sigma_window,
supports_visited, eigen_solves) besides the evidence sentence.
"""

from __future__ import annotations

import logging
import math
import time

import numpy as np

from ..core.errors import PetscOptionError, ProblemError
from ..core.matrix import max_abs_entry
from ..core.validation import as_int
from ..eicp.budget import check_enumeration_work
from ..eicp.problem import MAX_ENUMERATED, lam_floor
from ..eicp.solve import solve_eicp
from ..petsc.inertia import rayleigh_bound, symmetric_part_definite
from ..petsc.window import rayleigh_estimate
from ..scene import Scene
from .divergence_proof import prove_no_divergence
from .friction_range import proved_friction_range
from .problem import Pencil
from .result import Mode

#: reduced problems are enumerated when 2^|J| dense eigen-solves of size r cost at most
#: about this many flops (2^|J|·r³), with r ≤ ENUMERATE_N and |J| ≤ ENUMERATE_J.  ENUMERATE_J
#: also bounds ``method="enumerate"`` asked for by name (unless ``max_j`` raises it): 22
#: pairs on 110 retained DOFs measured 3.4 h, and hours grow to days with the lattice; the
#: work of one by name is bounded too (meicp.eicp.budget.ENUMERATE_MAX_FLOPS: 16 pairs on
#: 2,000 retained DOFs are days)
ENUMERATE_FLOPS = 2e9
ENUMERATE_N = 600
ENUMERATE_J = 16
#: a Ritz value of (sym A, sym B) above this multiple of max|A|/max|B| is positive beyond
#: rounding: the Rayleigh bound at 0 is then not tried
RITZ_POSITIVE = 1e-8
#: Lanczos restarts of the short run that decides whether the Rayleigh bound at 0 is tried
#: (an isolated positive top shows a positive Ritz value within a few restarts)
PROBE_RESTARTS = 5
#: σ_max candidates tried above the Lanczos estimate θ: τ = θ⁺·(1 + GAP·4^k) + floor
WINDOW_GAP = 1e-3
WINDOW_TRIES = 3
#: support updates of the first, short search from the window's top (before the proof), and
#: the Krylov–Schur restarts each of its eigen-solves may take: a rightmost eigenvalue that is
#: a mode stands apart and converges in a few (3 to 5 on the two-layer family from 24,000 to
#: 10⁶ DOFs; near μ_c one took 10 and others 22 to 51, found by the full search after the
#: proof stopped); one inside the cluster of slow vibrations took 273 s at 10⁶ DOFs and was
#: no mode, and a stable lattice spends the whole budget here
FIRST_SEARCH = 3
FIRST_EPS_MAX_IT = 6
#: ... and it gives up after this many restarts when every Ritz value estimates an eigenvalue
#: below 0: on a stable lattice all sit in the cluster of slow vibrations from the first
#: restart on (10⁶ DOFs, slip+ μ = 1: the largest −6e-5 in all six restarts, 18 s of
#: solves), while a mode shows above 0 at once (slip− μ = 3: σ = 0.32552 after the first
#: restart, converged in the fourth); the proof, or the whole search after it, decides
FIRST_GIVE_UP = 1

log = logging.getLogger("meicp")


def enumeration_is_small(r: int, n_j: int) -> bool:
    """Whether 2^|J| dense eigen-solves of size r are within the enumeration budget
    (``analyze``'s ``auto`` choice, and ``critical_friction``'s bisection check)."""
    return r <= ENUMERATE_N and n_j <= ENUMERATE_J and 2.0 ** n_j * r ** 3 <= ENUMERATE_FLOPS


def check_enumeration_size(n_j: int, r: int, options: dict) -> None:
    """ProblemError when an enumeration of 2^n_j supports of order up to r is past the
    limit: ENUMERATE_J pairs, or the ``max_j`` keyword's (at most MAX_ENUMERATED) when the
    caller raised it; and, unless ``max_j`` was given (the caller then accepts the cost),
    ENUMERATE_MAX_FLOPS of work.  The error names the limit and the methods that decide
    past it."""
    given = options.get("max_j")
    limit = ENUMERATE_J if given is None else as_int(given, "max_j", minimum=0, maximum=MAX_ENUMERATED)
    if n_j <= limit:
        if given is None:  # the pair count is not the work: 16 pairs on 2,000 DOFs are days
            check_enumeration_work(n_j, r, f"analyze(..., max_j={max(n_j, 1)}) from Python")
        return
    name = (f"max_j = {limit}" if given is not None
            else f"the limit of {limit} pairs ({2 ** limit:,} supports, meicp.contact.divergence.ENUMERATE_J)")
    raise_it = (f", or raise the limit with analyze(..., max_j={n_j}) from Python" if n_j <= MAX_ENUMERATED
                else f"; max_j cannot exceed {MAX_ENUMERATED}")
    raise ProblemError(f"method 'enumerate' visits all 2^|J| supports: |J| = {n_j} complementarity pairs is "
                       f"{2 ** n_j:,} supports, past {name}; each pair more doubles the time; use method='auto' "
                       f"or method='active-set', which decide past it with proofs that scale{raise_it}")


def divergence_of(pen: Pencil, scene: Scene, comm, method, lam_min: float, tol: float, options):
    """``(modes, evidence, stable, eicp, proof)`` of one pencil: its certified modes with
    σ ≥ lam_min, the evidence sentence, the verdict on σ ≥ 0 (True proved stable, False a
    mode, None undecided), the raw EiCP result (None when a proof needed no search) and the
    structured ``proof`` dict.  Collective on ``comm``."""
    red = pen.maps
    small = enumeration_is_small(red.retained.size, red.J.size)
    chosen = method if method not in (None, "auto") else ("enumerate" if small else "active-set")
    if chosen == "active-set":
        return _window_verdict(pen, scene, comm, lam_min, tol, options)
    if chosen == "enumerate":  # before any work: an enumeration by name may not start a days-long run
        check_enumeration_size(int(red.J.size), int(red.retained.size), options)
    kwargs = dict(options)
    eicp = solve_eicp(pen.A, pen.B, J=red.J, method=chosen, lam_min=0.0, tol=tol, comm=comm, **kwargs)
    modes, found, left_out = _modes(eicp, pen, lam_min)
    cover = eicp.coverage.get("supports", 0)
    proof = {"test": chosen, "supports_visited": int(cover)}
    if chosen == "enumerate":
        if found:
            return modes, (f"enumeration of all {cover} supports: {len(found)} divergence mode(s) with "
                           f"σ ≥ 0{left_out}"), False, eicp, dict(proof, statement="certified mode(s)")
        if eicp.status == "no_solution":
            text = f"enumeration of all {cover} supports: no solution with σ ≥ 0 (a proof)"
            return [], text, True, eicp, dict(proof, statement=text)
        text = (f"enumeration of all {cover} supports found no mode, but this is not a proof "
                f"({eicp.status}): {eicp.message}")
        return [], text, None, eicp, dict(proof, test="", statement=text)
    if found:
        return modes, f"{chosen}: {len(found)} certified divergence mode(s){left_out}", False, eicp, \
            dict(proof, statement="certified mode(s)")
    text = f"{chosen} found no mode with σ ≥ 0 ({eicp.status}); this is not a proof of stability"
    return [], text, None, eicp, dict(proof, test="", statement=text)


def _window_verdict(pen: Pencil, scene: Scene, comm, lam_min: float, tol: float, options):
    A, B, red = pen.A, pen.B, pen.maps
    proof = {"test": "", "statement": "", "sigma_window": None, "supports_visited": 0, "eigen_solves": 0}
    t0 = time.perf_counter()
    # 1. a short Lanczos run on (sym A, sym B) first: a Ritz value θ > 0 is a Rayleigh quotient,
    # so sym(A) is not negative definite and the bound at 0 — one LDLᵀ of the whole pencil, 7 s
    # at 10⁶ DOFs — cannot prove anything.  Short, because where sym(A) ≺ 0 the top sits among
    # the slow vibrations just below 0 and a full run stalls for its whole budget (6.5 s at 10⁶
    # DOFs, μ = 0.01) before the bound proves stability anyway.  Its options: -meicp_window_*
    # on the command line; without sym(B) ≻ 0 (a frictional interface at large μ) no Rayleigh
    # quotient bounds σ and Lanczos would break down
    petsc_options = dict(scene.petsc)
    b_definite, _ = symmetric_part_definite(B)
    theta, converged = (rayleigh_estimate(A, B, max_it=PROBE_RESTARTS)[:2] if b_definite else (math.nan, False))
    scale = max_abs_entry(A) / max(max_abs_entry(B), 1e-300)
    # 2. the Rayleigh bound at 0, unless θ already rules it out
    if theta > RITZ_POSITIVE * scale:
        stopped = [f"Rayleigh bound at 0: not tried, the Ritz value θ = {theta:.6g} > 0 of (sym A, sym B) is a "
                   "Rayleigh quotient: sym(A) is not negative definite"]
    else:
        at_zero = rayleigh_bound(A, B, 0.0, decisive=False)
        log.info("divergence: Rayleigh bound at 0 %s (%.2f s)", "proved" if at_zero.proved else "not proved",
                 time.perf_counter() - t0)
        if at_zero.proved:
            text = (f"Rayleigh bound (LDLᵀ inertia): {at_zero.reason}; every MEiCP solution has σ = "
                    "xᵀsym(A)x / xᵀsym(B)x < 0 (a proof)")
            return [], text, True, None, dict(proof, test="rayleigh-inertia", statement=text,
                                              sigma_window=(0.0, math.inf))
        stopped = [f"Rayleigh bound at 0: {at_zero.reason}"]
    # 3. modes from the estimated top of the σ-window: a short search first (a mode on the full
    # support, or one support update away, is found at once), then the condensed proof, then —
    # neither decided — the whole search; on a stable lattice a long search finds nothing and
    # costs more than the proof (10⁶ DOFs, slip+, μ = 1: 273 s of search, 76 s of proof).  The
    # top is the short run's Ritz value: placing the shift needs no certificate, and the proof
    # needs σ_max only where it stops short of ∞ (step 5)
    stalls = not theta > RITZ_POSITIVE * scale
    solver = scene.solver
    kwargs = dict(options)
    top = max(theta if math.isfinite(theta) else 0.0, 0.0) * 1.001 + 1e-10 * scale
    kwargs.setdefault("target", top)
    kwargs.setdefault("nev", solver.nev or 1)
    kwargs.setdefault("options", petsc_options)
    full_budget = kwargs.pop("max_iter", solver.max_iterations or None)

    def search(max_iter, first=False):
        budget = {} if max_iter is None else {"max_iter": max_iter}
        if first:
            budget["options"] = {"eps_max_it": FIRST_EPS_MAX_IT, **kwargs["options"]}
            budget["give_up_after"] = FIRST_GIVE_UP
        eicp = solve_eicp(A, B, J=red.J, method="active-set", lam_min=0.0, tol=tol, comm=comm,
                          **{**kwargs, **budget})
        if eicp.coverage.get("option_error"):  # a [petsc] / command-line value PETSc rejects: bad input
            raise PetscOptionError(eicp.message)
        proof["supports_visited"] += int(eicp.coverage.get("supports_visited", 0))
        proof["eigen_solves"] += int(eicp.coverage.get("eigen_solves", 0))
        modes, found, left_out = _modes(eicp, pen, lam_min)
        log.info("divergence: search from σ = %.6g, %d mode(s), %s Krylov–Schur restart(s)%s (%.2f s)",
                 kwargs["target"], len(found), eicp.coverage.get("eps_iterations", "?"),
                 ", given up: no Ritz value above 0" if eicp.coverage.get("gave_up") else "", time.perf_counter() - t0)
        if not found:
            return eicp, None
        text = (f"search from σ = {kwargs['target']:.6g}: a certified divergence mode after "
                f"{proof['eigen_solves']} eigen-solve(s), {proof['supports_visited']} support(s){left_out}")
        return eicp, (modes, text, False, eicp, dict(proof, test="certified-mode", statement=text))

    short = FIRST_SEARCH if full_budget is None else min(FIRST_SEARCH, full_budget)
    eicp, verdict = search(short, first=True)
    if verdict is not None:
        return verdict
    # 4. condensed proof on [0, ∞): its last window [σ_a, ∞) costs no condensation more than
    # one ending at a certified σ_max (10⁶ DOFs, μ = 1 and 3: 5 and 8 either way), and σ_max
    # costs a Lanczos run and an LDLᵀ (5.5 s at 10⁶; where Lanczos stalls in the cluster of
    # slow vibrations, 9 s for nothing)
    condensed = prove_no_divergence(comm, pen, math.inf, tol=tol)
    log.info("divergence: condensed proof %s, %d condensation(s) (%.2f s%s)",
             "holds" if condensed.proved else "stopped", condensed.samples, time.perf_counter() - t0,
             "".join(f", {k} {v:.1f}" for k, v in condensed.seconds.items()))
    if condensed.proved:
        text = f"{condensed.statement} (a proof)"
        return [], text, True, eicp, dict(proof, test=condensed.test, statement=text, sigma_window=(0.0, math.inf),
                                          margin=condensed.margin)
    # 5. the proof stopped at σ = covered: a certified σ_max ≤ covered (no solution above it,
    # by the Rayleigh bound) completes it.  The whole Lanczos run only after a positive Ritz
    # value: with none in the short run the top sits in the cluster of slow vibrations (the
    # bound at 0 failed on it) and the run stalls for its whole budget (8.8 s at 10⁶ DOFs)
    covered = condensed.window[1] if condensed.window else -math.inf
    sigma_max = None
    if b_definite and not stalls:
        if not converged:
            theta, converged = rayleigh_estimate(A, B)[:2]
        # an unconverged Ritz value lies below λ_max: certifying above it wastes factorisations
        sigma_max = _certified_top(A, B, theta, scale) if converged else None
    log.info("divergence: σ-window [0, %s] (%.2f s)", "?" if sigma_max is None else f"{sigma_max:.6g}",
             time.perf_counter() - t0)
    if sigma_max is not None and sigma_max <= covered:
        text = (f"no solution above σ_max = {sigma_max:.6g} (Rayleigh bound, LDLᵀ inertia) and none in "
                f"[0, {covered:.6g}] by the condensed windows ({condensed.statement}) (a proof)")
        return [], text, True, eicp, dict(proof, test="rayleigh-window+condensed-windows", statement=text,
                                          sigma_window=(0.0, sigma_max), margin=condensed.margin)
    if sigma_max is None:
        stopped.append("no σ-window (λ_max(sym A, sym B) not estimated)" if not math.isfinite(theta) else
                       f"no σ_max: no Ritz value of (sym A, sym B) above 0 in {PROBE_RESTARTS} Lanczos restarts "
                       f"(largest {theta:.6g}; the top lies among the slow vibrations, where Lanczos stalls)"
                       if stalls and not converged else
                       f"no σ_max certified above the estimate {theta:.6g} of λ_max(sym A, sym B)")
    else:
        kwargs["target"] = sigma_max  # the whole search from the certified top
    stopped.append(f"condensed test: {condensed.statement}")
    if condensed.window:
        proof["sigma_window"] = tuple(float(v) for v in condensed.window)
    if full_budget is None or full_budget > short:
        eicp, verdict = search(full_budget)
        if verdict is not None:
            return verdict
    stopped.append(f"the search from σ = {kwargs['target']:.6g} over {proof['supports_visited']} support(s) found "
                   f"no mode ({eicp.status})")
    # 6. undecided, with what was established: the window, the supports, and the friction up
    # to which these contact states are proved stable
    t = time.perf_counter()
    if b_definite:
        # the first bound (when tried) spared the inertia that tells "within rounding of 0" (rigid
        # motions, a borderline μ) from a clear failure; an undecided verdict says which
        stopped[0] = f"Rayleigh bound at 0: {rayleigh_bound(A, B, 0.0).reason}"
    reach = proved_friction_range(pen)
    log.info("divergence: friction range proved up to %.4g× the scene's (%d inertias, %.2f s)", reach.scale,
             reach.factorisations, time.perf_counter() - t)
    text = "undecided: " + "; ".join(stopped) + f"; {reach.statement}"
    return [], text, None, eicp, dict(proof, statement=text, stable_friction_scale=reach.scale,
                                      stable_friction=dict(reach.friction))


def _certified_top(A, B, theta: float, scale: float) -> float | None:
    """The smallest τ tried above the estimate θ of λ_max(sym A, sym B) that the Rayleigh
    bound certifies (no MEiCP solution has σ ≥ τ), or None."""
    if not math.isfinite(theta):
        return None
    for k in range(WINDOW_TRIES):
        tau = max(theta, 0.0) * (1.0 + WINDOW_GAP * 4 ** k) + 1e-10 * scale * 4 ** k
        if rayleigh_bound(A, B, tau, decisive=False).proved:
            return tau
    return None


def _modes(eicp, pen: Pencil, lam_min: float):
    """The certified modes with σ ≥ lam_min, every one with σ ≥ 0, and a note on those left out."""
    red = pen.maps
    # a σ below 0 (even by 5e-11 just below μ_c) is not a divergence mode, but an exact σ = 0
    # (a block free to slide as a whole) computed a few ulps below it is (eicp.problem.lam_floor)
    scales = (max_abs_entry(pen.A), max_abs_entry(pen.B))
    found = [_mode(sol, red) for sol in eicp.solutions if sol.lam >= lam_floor(0.0, scales)]
    modes = [m for m in found if lam_min == 0 or m.sigma >= lam_floor(lam_min, scales)]
    left_out = (f"; {len(found) - len(modes)} with 0 ≤ σ < lam_min = {lam_min:g} not listed"
                if len(modes) < len(found) else "")
    if any(m.sigma < 0 for m in found):
        left_out += (f"; σ = {min(m.sigma for m in found):.2g} is 0 within rounding "
                     f"(≥ {lam_floor(0.0, scales):.2g}): an exact σ = 0 mode")
    return modes, found, left_out


def _mode(sol, red) -> Mode:
    u = red.Q @ sol.x
    nrm = np.linalg.norm(u)
    u = u / nrm if nrm > 0 else u
    base_support, interface_support = [], {}
    for j in sol.support:
        name, idx, _ = red.pair_of[int(np.flatnonzero(red.J == j)[0])]
        if name == "base":
            base_support.append(idx)
        else:
            interface_support.setdefault(name, []).append(idx)
    return Mode(float(sol.lam), u, np.unique(np.array(base_support, dtype=np.int64)), float(sol.residual),
                {k: np.unique(v) for k, v in interface_support.items()})
