"""The damped flutter search past the dense limit (docs/damping.md, "damped flutter at scale"):
complex shift-and-invert on the companion form of the quadratic sliding pencil
``Q(λ) = λ²B + λD − A`` (:mod:`meicp.petsc.flutter_quadratic`) at targets λ₀ from the damped
contact-strip proxy (:func:`~.flutter_proxy.proxy_targets`, σ = λ₀²), else on the line
Re λ = 0.05.

A pair counts as a flutter mode when its backward error on Q is at most
:data:`~.flutter_verdict.RESIDUAL_TOL` and both Re λ and |Im λ| exceed the margin
``MARGIN·η·(|λ|²‖B‖ + |λ|‖D‖ + ‖A‖)/(2|λ|‖B‖ + ‖D‖)`` — the first-order change of λ under a
backward error η (‖Q'(λ)‖ ≈ 2|λ|‖B‖ + ‖D‖), with the searches' :data:`~.flutter_verdict.MARGIN`
standing for the unknown condition number (with D = 0 it is that search's σ-margin over 2|λ|),
raised where the eigenvector is nearly real (:func:`lambda_margin`).
Like the undamped search it proves flutter, never its absence; the growth bracket has the
fastest certified mode below and a proved but loose ceiling above (:func:`growth_ceiling`,
Bendixson's rectangle carried over to the quadratic pencil).  Collective.
"""

from __future__ import annotations

import logging

import numpy as np

from ..core import limits
from ..core.comm import mpi_comm
from ..petsc.flutter import SlidingPencilOps
from ..petsc.flutter_quadratic import QuadraticPencilOps, quadratic_shift_solve
from ..petsc.mat import distributed
from .flutter_dense import _fastest_first, _normalise
from .damped_flutter_free import damped_flutter_free
from .flutter_growth import FlutterGrowth, quadratic_ceiling, search_growth
from .flutter_proxy import (LINE_FREQUENCIES, LINE_GROWTH, LINE_WHY, OFF_CLUSTER_TRIES,
                            depth_note, depth_used, off_cluster, proxy_targets)
from .flutter_verdict import (GIVE_UP_BUDGET, GIVE_UP_RESTARTS, MARGIN, RESIDUAL_TOL, SAME, FlutterCandidate,
                             PencilFlutter, RejectedPair, gated_partners, memory_refusal, partner_condition,
                             real_ritz_note, search_conclusion)
from .lines import BASE
from .on_root import on_root
from .proxy import PROXY_NX, PROXY_ROWS

log = logging.getLogger("meicp")

#: eigenpairs per target and the Krylov basis (complex; SLEPc's real form has twice both): at
#: 10⁶ DOFs a basis of 24 for one pair cost the same
#: (docs/benchmarks-notes.md, "damped flutter search")
SEARCH_NEV = 2
SEARCH_NCV = 12


def lambda_margin(ops: QuadraticPencilOps, lam: complex, residual: float, x, partners=()) -> float:
    """How far λ (eigenvector x) may be from the exact eigenvalue (module docstring): MARGIN·η·
    scale(λ) times the larger lower bound of its condition number ‖x‖‖y‖/|yᴴQ'(λ)x|, 1/‖Q'(λ)‖
    or :func:`~.flutter_verdict.partner_condition`'s from the conjugate pair and the other
    pairs ``partners`` ((λ₂, x₂)) — a search once certified three "modes" within 2e-8 of a real
    λ = 0.0045 under dashpots of η = 1e5, and one at Re λ = 5e-9 of a double eigenvalue on the
    imaginary axis."""
    _, norm_B, norm_D = ops.norms
    tiny = np.finfo(float).tiny

    def spread(l1, l2):
        return abs(l1 + l2) * norm_B + norm_D, abs(l1 - l2) * norm_B

    kappa = max(1.0 / max(2 * abs(lam) * norm_B + norm_D, tiny), partner_condition(lam, x, partners, spread))
    return MARGIN * residual * ops.scale(lam) * kappa


def zero_reach(ops: QuadraticPencilOps, residual: float) -> float:
    """How far from 0 rounding can carry an eigenvalue split off a double λ = 0: a motion that
    neither the stiffness nor the damping resists (a rigid slide, Av = Dv = 0) makes λ = 0 a
    Jordan block, which a backward error η splits by ~√η, not η (a scene with free sides and
    Kelvin–Voigt damping gave three "modes" at |λ| ≈ 6e-8).  ``s·√(MARGIN·η)`` with s = √(‖A‖/‖B‖)
    the pencil's λ scale; a pair nearer 0 is not certified."""
    norm_A, norm_B, _ = ops.norms
    return float(np.sqrt(MARGIN * residual * norm_A / max(norm_B, np.finfo(float).tiny)))


def moved_off(lam0: complex, attempt: int) -> complex:
    """λ₀ moved up off a cluster as the undamped search moves σ (:func:`~.flutter_proxy.off_cluster`
    of σ₀ = λ₀²)."""
    return complex(np.sqrt(off_cluster(complex(lam0) ** 2, attempt)))


#: why no target is searched when the damped proxy has no flutter
PROXY_FREE = (f": the {PROXY_NX}-column, {PROXY_ROWS}-row damped contact-strip proxy has no flutter mode (dense "
              "companion QZ: every eigenvalue real or decaying, a proof for the proxy, not for the lattice), so no "
              "target is searched: guesses on a λ-line found nothing there at 10⁶ DOFs, at 15 eigen-solves' cost "
              "(docs/benchmarks.md, \"Damping at scale\")")


def damped_targets(scene, lines, n: int) -> tuple[list[complex], str]:
    """``(λ₀ targets, why)`` for a pencil of ``n`` retained DOFs: the damped proxy's fastest
    flutter modes (λ = √σ) — a base proxy's moved up off its cluster first from
    ``limits.FLUTTER_OFF_CLUSTER_FROM`` DOFs, as the undamped search does — none when the
    damped proxy is proved free of flutter, else the λ-line."""
    sigmas, proxy_flutter = proxy_targets(scene, lines, 1 if n >= limits.FLUTTER_SEARCH_LARGE else 3,
                                          with_verdict=True, depth=depth_used(n))
    if sigmas:
        targets = [complex(np.sqrt(complex(s))) for s in sigmas]
        why = (f" from a {PROXY_NX}-column, {PROXY_ROWS}-row damped contact-strip proxy"
               f"{depth_note(scene, lines, n)} (dense companion QZ)")
        if n >= limits.FLUTTER_OFF_CLUSTER_FROM and any(line.name == BASE for line in lines):
            moved = [moved_off(t, 0) for t in targets]
            why += (", each moved up off its cluster before the first solve: "
                    + ", ".join(f"{t:.4g} → {m:.4g}" for t, m in zip(targets, moved)))
            targets = moved
        return targets, why
    if proxy_flutter is False:
        # measured at 10⁶ DOFs (μ = 0.05): three λ-line targets, each given up after 11 restarts,
        # 376 s for nothing (docs/benchmarks.md, "Damping at scale")
        return [], PROXY_FREE
    return [complex(LINE_GROWTH, w) for w in LINE_FREQUENCIES], LINE_WHY


def search_damped_flutter(pen, scene, comm=None, *, targets=None, nev: int = SEARCH_NEV,
                          ncv: int | None = SEARCH_NCV, tol: float = 1e-12, low_rank: float | None = None,
                          strict_tol: float | None = None, options: dict | None = None) -> PencilFlutter:
    """Damped flutter modes of the (distributed or SciPy) sliding pencil ``pen`` near the
    complex λ-``targets`` (default: :func:`damped_targets`): True with certified modes, else
    None — never a proof of absence.  Collective."""
    comm = mpi_comm(comm)
    n = int(pen.maps.retained.size)
    # the companion form: twice the basis
    refused = memory_refusal(comm, 2 * limits.FLUTTER_SEARCH_BYTES_PER_DOF * n,
                             f"the damped flutter search of {n:,} retained DOFs")
    if refused is not None:
        return refused
    why = ""
    if targets is None:
        targets, why = on_root(comm, lambda: damped_targets(scene, pen.lines, n))  # one answer on every rank
        if not targets:
            return no_target(pen, why)
    return _search(pen, pen.damping(), targets, why, nev=nev, ncv=ncv, tol=tol, low_rank=low_rank,
                   strict_tol=strict_tol, options=options)


def no_target(pen, why: str) -> PencilFlutter:
    """The verdict when the damped proxy gives no target — it is proved free of flutter
    (:func:`damped_targets`, ``why``): the damped flutter-free proof of the lattice itself
    (:func:`~.damped_flutter_free.damped_flutter_free`: one LDLᵀ), else undecided.  Collective."""
    proved, statement = damped_flutter_free(pen)
    log.info("damped flutter: %s", statement)
    if proved:
        return PencilFlutter(False, [], f"damped: {statement}; the damped proxy had no flutter either",
                             counts={"targets": 0}, growth=FlutterGrowth(0.0, 0.0, statement))
    return PencilFlutter(None, [], f"damped: no target searched{why}; {statement}" + search_conclusion([]),
                         counts={"targets": 0},
                         growth=search_growth([], "the damped search computes only the eigenvalues near its targets, "
                                                  "and had none"))


def _search(pen, D, targets, why: str, **solve) -> PencilFlutter:
    # a serial SciPy pencil gets PETSc Mats of its own for the search
    with distributed(pen.comm, pen.A, pen.B, D) as (A, B, D), QuadraticPencilOps(A, B, D) as ops:
        return _at_targets(ops, targets, why, growth_ceiling(ops), **solve)


def growth_ceiling(ops: QuadraticPencilOps) -> tuple[float, str] | None:
    """``(upper, how)``: no eigenvalue of ``λ²B + λD − A`` grows faster than ``upper``
    (:func:`~meicp.contact.flutter_growth.quadratic_ceiling` on Gershgorin's and the
    skew-part bounds of A and D scaled by B, from the rows ``ops`` holds), or None when B is
    not diagonal.  Collective."""
    with (SlidingPencilOps(ops.A, ops.B, ops.A_local, ops.B_local) as on_a,
          SlidingPencilOps(ops.D, ops.B, ops.D_local, ops.B_local) as on_d):
        gamma, beta = on_a.real_part_bound(), on_a.skew_bound()
        if gamma is None or beta is None:
            return None
        low, delta = on_d.lowest_real_part(), on_d.skew_bound()
    nu = max(0.0, -low)
    upper = quadratic_ceiling(gamma, beta, nu, delta)
    return upper, (f"for every eigenvector, Re xᴴAx/xᴴBx ≤ {gamma:.4g} and |Im| ≤ {beta:.4g}, Re xᴴDx/xᴴBx ≥ "
                   f"{-nu:.4g} and |Im| ≤ {delta:.4g} (Gershgorin's discs and the skew-part bounds, B diagonal), so "
                   "λ² + dλ − a = 0 bounds Re λ")


def _at_targets(ops: QuadraticPencilOps, targets, why: str, ceiling=None, **solve) -> PencilFlutter:
    modes, rejected, disks, borderline, moved, real_ritz = [], [], [], 0, [], 0
    for lam0 in targets:
        lam0 = complex(lam0)
        lam0 = lam0.conjugate() if lam0.imag < 0 else lam0
        for attempt in range(OFF_CLUSTER_TRIES + 1):
            pairs, info = quadratic_shift_solve(ops, lam0, gate=RESIDUAL_TOL,
                                                give_up=(GIVE_UP_RESTARTS, GIVE_UP_BUDGET), **solve)
            passed = sum(res <= RESIDUAL_TOL for _, _, res in pairs)
            real_ritz += info.get("real_ritz", 0)
            disks.append((lam0, info["radius"], len(pairs), passed, info["iterations"], info["gave_up"]))
            for lam, x, res in pairs:
                if res > RESIDUAL_TOL:
                    rejected.append(RejectedPair(lam * lam, res))
                    continue
                r = lambda_margin(ops, lam, res, x, gated_partners(pairs, lam, RESIDUAL_TOL))
                if lam.imag > r and lam.real > r and abs(lam) > zero_reach(ops, res):
                    if not any(abs(lam * lam - m.sigma) <= SAME * abs(m.sigma) for m in modes):
                        modes.append(FlutterCandidate(lam * lam, _normalise(x), res, 2 * abs(lam) * r + r * r,
                                                      f"companion shift-invert at λ₀ = {lam0:.6g}"))
                elif lam.imag != 0 and lam.real > -r:
                    borderline += 1
            log.info("damped flutter: %d pair(s) near λ₀ = %s, %d passing the residual gate (%d restarts)",
                     len(pairs), f"{lam0:.6g}", passed, info["iterations"])
            # pseudo-pairs, or none converged: a target inside a cluster of ill-conditioned
            # eigenvalues (as in the undamped search); moved up off it — unless the solve was
            # given up (nothing grows near it, or nothing converges): a move would pay the
            # factor and the restarts again for the same
            if passed or attempt == OFF_CLUSTER_TRIES or info["gave_up"]:
                break
            moved.append((lam0, moved_off(lam0, attempt)))
            lam0 = moved[-1][1]
    counts = {"targets": len(disks), "rejected": len(rejected), "borderline": borderline, "moved": len(moved),
              "real_ritz": real_ritz}
    text = "; ".join(f"|λ − ({t.real:.4g}{t.imag:+.4g}i)| ≤ {r:.3g} ({k} λ, {p} passing the residual gate, "
                     f"{it} restarts" + (f", given up: {gave_up}" if gave_up else "") + ")"
                     for t, r, k, p, it, gave_up in disks)
    off = "".join(f"; no pair near λ₀ = {a:.4g} passed the residual gate, so the target moved off its cluster to "
                  f"{b:.4g}" for a, b in moved)
    evidence = (f"damped: complex shift-and-invert on the companion form of λ²B + λD − A at {len(disks)} target(s)"
                f"{why}{off}: the eigenvalues SLEPc converged in {text}"
                + (f"; {len(rejected)} pair(s) failed the residual gate {RESIDUAL_TOL:g}" if rejected else "")
                + real_ritz_note(real_ritz, "λ − λ₀"))
    evidence += search_conclusion(modes)
    growth = search_growth(modes, "the damped search computes only the eigenvalues near its targets",
                           ceiling=ceiling)
    return PencilFlutter(True if modes else None, _fastest_first(modes), evidence, counts=counts, rejected=rejected,
                         growth=growth)
