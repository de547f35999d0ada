"""Flutter of steady sliding (docs/flutter.md): non-real eigenvalues of the sliding pencil.

With the slipping contacts sliding on, the linearised motion is ``(σB − A)x = 0`` on the
retained DOFs: the MEiCP's pencil ``A = −P̃KQ̃``, ``B = P̃MQ̃`` with every slip row an
equality (the slip rate free in sign while sliding goes on).  A is nonsymmetric once μ > 0,
and a non-real σ gives λ = √σ with Re λ > 0: a growing oscillation.  Which contacts count:
slipping ones (base and frictional interfaces) slide, sticking ones are held, separated
ones are free; a grazing contact has no linearisation, so two branches bracket it
(:func:`grazing_branches`): ``separated`` and ``sliding`` — flutter is claimed only when
every branch has it, excluded only when none has it.

Two paths, both ending in :class:`~meicp.contact.result.FlutterMode` s with their
backward errors (a mode above :data:`RESIDUAL_TOL` is never reported):

- **dense** (retained DOFs ≤ :data:`~meicp.core.limits.FLUTTER_DENSE_MAX`): every eigenvalue
  by LAPACK with its rounding radius, a proof either way unless borderline
  (:mod:`.flutter_dense`).
- **search** (larger): complex shift-and-invert (:mod:`meicp.petsc.flutter`) at targets
  taken from a dense *contact-strip proxy* of the scene (:mod:`.flutter_proxy`), or on a
  λ-line when no proxy exists.  It can prove flutter (a certified mode), never its absence:
  flutter is True or None, and the evidence says which disks of the σ-plane were searched;
  its growth bracket is the fastest certified mode below and Bendixson's rectangle above.
"""

from __future__ import annotations

import itertools
import logging
import time

import numpy as np

from ..core import limits
from ..core.comm import mpi_comm
from ..core.errors import ConvergenceError
from ..core.matrix import to_dense
from ..core.validation import as_flag
from ..petsc.flutter import SlidingPencilOps, complex_shift_solve
from ..petsc.mat import distributed
from ..petsc.flutter_quadratic import QuadraticPencilOps
from .damped import damped_flutter
from .damped_proportional import mapped_flutter, proportional_damping
from .damped_search import damped_targets, growth_ceiling, lambda_margin, no_target, search_damped_flutter
from .flutter_dense import NO_FLUTTER, _fastest_first, _normalise, dense_flutter
from .flutter_growth import combine_growths, search_growth
from .flutter_proxy import (LINE_FREQUENCIES, LINE_GROWTH, LINE_WHY, OFF_CLUSTER_TRIES,
                            SEARCH_TARGETS, depth_note, depth_used, off_cluster, proxy_targets)
from .flutter_verdict import (GIVE_UP_BUDGET, GIVE_UP_RESTARTS, MARGIN, RESIDUAL_TOL, SAME, FlutterCandidate,
                             FlutterVerdict, PencilFlutter, RejectedPair, gated_partners, memory_refusal,
                             partner_condition, real_ritz_note, search_conclusion)
from .lines import BASE, ContactState
from .on_root import on_root
from .problem import pencil_of
from .proxy import PROXY_NX, PROXY_ROWS
from .result import FlutterMode

log = logging.getLogger("meicp")

#: large-scale path defaults: eigenpairs per target, Krylov basis (|Im σ| must exceed
#: MARGIN·η·(‖A‖₁/‖B‖₁ + |σ|) to count as non-real: :data:`~.flutter_verdict.MARGIN`)
SEARCH_NEV = 4
SEARCH_NCV = 16
OFF_CLUSTER_NCV = 16
#: an interface-strip proxy's target at that size is searched where it is, for one eigenpair
#: with a basis of INTERFACE_NCV: on the seeds' scene (extensive_interface.toml) coarsened to
#: 3·10⁵ DOFs, 1 restart and 38 s against 6 restarts and 66 s moved off with OFF_CLUSTER_NCV
#: (docs/benchmarks-notes.md, "INTERFACE_NCV")
INTERFACE_NCV = 24
#: SLEPc restarts at a target that may still be moved off its cluster, and at the last one
#: (SLEPc's own default before either was named).  With a narrow basis at the next target a
#: cap of 40 before a move did not pay; with RETRY_NCV there, 20 restarts bound what a target
#: that converges nothing costs (docs/benchmarks-notes.md, "SEARCH_RESTARTS", "RETRY_NCV")
SEARCH_RESTARTS = 20
LAST_RESTARTS = 500
#: a target moved off its cluster is searched with a Krylov basis of at least RETRY_NCV: the
#: cluster's top edge holds many eigenvalues at nearly one distance from it, which a narrow
#: basis cannot separate — on a two-layer lattice outside the benchmark family (10⁶ DOFs,
#: μ = 2, slip−, shear −0.3) 60 restarts with a basis of 16 converged nothing where one of 48
#: converged certified pairs in one (docs/benchmarks-notes.md, "RETRY_NCV")
RETRY_NCV = 48
#: from limits.FLUTTER_SEARCH_LARGE retained DOFs the shifted pencil is factored block-low-rank at this
#: dropping tolerance (MUMPS CNTL(7)): faster, with the certified pairs' backward errors as
#: without it (docs/benchmarks-notes.md, "LOW_RANK_TOL")
LOW_RANK_TOL = 1e-10
#: from limits.FLUTTER_SEARCH_LARGE retained DOFs SLEPc converges the pairs to LARGE_EPS_TOL,
#: and solves again to STRICT_EPS_TOL only when none then passes the residual gate on (A, B):
#: SLEPc's residual is that of the shifted inverse, which the backward error on (A, B) shrinks
#: (on extensive_interface.toml one restart at 1e-8 gave a pair at 2.7e-11, where 1e-10 took
#: two: docs/benchmarks-notes.md, "LARGE_EPS_TOL")
LARGE_EPS_TOL = 1e-8
STRICT_EPS_TOL = 1e-10



def lambda_line_targets(growth: float, frequencies) -> list[complex]:
    """Targets σ = (g + iω)² on the vertical line Re λ = g of the λ-plane: a sweep that needs
    no proxy (the large-scale path without one, and the benchmark's independent check)."""
    return [complex((growth + 1j * w) ** 2) for w in frequencies]


def _real_part_bound(ops: SlidingPencilOps, given: tuple | None) -> tuple[float | None, str]:
    """``(γ, how)``: Re σ ≤ γ for every eigenvalue of a pencil with a diagonal B — the
    caller's certified bound or Gershgorin's on the scaled symmetric part, the smaller."""
    gershgorin = (ops.real_part_bound(), "Gershgorin's discs of D^-1/2 sym(A) D^-1/2")
    return gershgorin if given is None or given[0] >= gershgorin[0] else given


def search_flutter(A, B, targets, comm=None, *, nev: int = SEARCH_NEV, ncv: int | None = SEARCH_NCV,
                   tol: float = 1e-12, residual_tol: float = RESIDUAL_TOL, options: dict | None = None,
                   why_targets: str = "", off_cluster_tries: int = OFF_CLUSTER_TRIES,
                   low_rank: float | None = None, strict_tol: float | None = None,
                   real_bound: tuple | None = None) -> PencilFlutter:
    """Flutter modes of (A, B) (PETSc Mats, or SciPy distributed here over ``comm``) near the
    complex ``targets``: True with certified modes, else None — never a proof of absence.
    A target whose converged pairs all fail the residual gate is retried off the cluster
    (:func:`off_cluster`), at most ``off_cluster_tries`` times.  ``low_rank``: the MUMPS
    block-low-rank tolerance of the factor (None: full rank).  ``tol``: SLEPc's; with
    ``strict_tol``, a solve none of whose pairs passes the residual gate is made again at
    ``strict_tol`` before the target counts as failed.  ``real_bound``: ``(γ, how)``, a
    certified Re σ < γ for every eigenvalue known to the caller (the divergence verdict's
    Rayleigh bound), used when it is below Gershgorin's; with the skew-part bound it bounds
    the growth from above (:func:`~.flutter_growth.search_growth`).  Collective."""
    with distributed(mpi_comm(comm), A, B) as (A, B), SlidingPencilOps(A, B) as ops:
        if ops.symmetric_with_diagonal_mass():
            return PencilFlutter(False, evidence="symmetric A and diagonal positive B: every σ is real — "
                                                 "a proof", growth=NO_FLUTTER)
        bound = ops.skew_bound()
        real_max, real_how = _real_part_bound(ops, real_bound) if bound is not None else (None, "")
        modes, rejected, disks, borderline, moved, real_ritz, failed = [], [], [], 0, [], 0, []
        for tau in targets:
            tau = complex(tau)
            tau = tau.conjugate() if tau.imag < 0 else tau
            for attempt in range(off_cluster_tries + 1):
                last = attempt == off_cluster_tries
                basis = ncv if attempt == 0 else max(ncv or 0, RETRY_NCV)
                try:
                    pairs, info = complex_shift_solve(ops, tau, nev=nev, ncv=basis, tol=tol, low_rank=low_rank,
                                                      max_it=LAST_RESTARTS if last else SEARCH_RESTARTS,
                                                      options=options, gate=residual_tol, strict_tol=strict_tol,
                                                      give_up=(GIVE_UP_RESTARTS, GIVE_UP_BUDGET))
                except ConvergenceError as err:  # the same on every rank: the solve is collective
                    failed.append(str(err))
                    break
                passed = sum(res <= residual_tol for _, _, res in pairs)
                real_ritz += info.get("real_ritz", 0)
                disks.append((tau, info["radius"], len(pairs), passed, info["iterations"]))
                if info.get("gave_up"):
                    failed.append(f"the solve at τ = {tau:.6g} was stopped after {info['iterations']} restarts, "
                                  f"{info['gave_up']}")
                for sigma, x, res in pairs:
                    if res > residual_tol:
                        rejected.append(RejectedPair(sigma, res))
                        continue
                    kappa = max(1.0, partner_condition(sigma, x, gated_partners(pairs, sigma, residual_tol),
                                                       lambda s1, s2: (1.0, 0.0)))
                    margin = MARGIN * kappa * res * (ops.norm_A / ops.norm_B + abs(sigma))
                    if abs(sigma.imag) > margin:
                        if not any(abs(sigma - m.sigma) <= SAME * abs(m.sigma) for m in modes):
                            modes.append(FlutterCandidate(sigma, _normalise(x), res, margin,
                                                          f"shift-invert at τ = {tau:.6g}"))
                    elif sigma.imag != 0:
                        borderline += 1
                # nothing certified — pseudo-pairs, or none converged within the restarts — is
                # what a target inside a cluster of ill-conditioned eigenvalues gives
                if passed or last:
                    break
                moved.append((tau, off_cluster(tau, attempt)))
                log.info("flutter: no pair at τ = %s passed the residual gate (%d converged in %d restarts); "
                         "retrying off the cluster at τ = %s", f"{tau:.6g}", len(pairs), info["iterations"],
                         f"{moved[-1][1]:.6g}")
                tau = moved[-1][1]
    counts = {"targets": len(disks), "rejected": len(rejected), "borderline": borderline, "moved": len(moved),
              "real_ritz": real_ritz}
    text = "; ".join(f"|σ − ({t.real:.4g}{t.imag:+.4g}i)| ≤ {r:.3g} ({k} σ, {p} passing the residual gate, "
                     f"{it} restarts)" for t, r, k, p, it in disks)
    off = "".join(f"; no pair near τ = {a.real:.4g}{a.imag:+.4g}i passed the residual gate (pseudo-pairs or none "
                  f"converged, as shift-and-invert gives inside a cluster of ill-conditioned eigenvalues), so the "
                  f"target moved off it to {b.real:.4g}{b.imag:+.4g}i, searched with a basis of at least {RETRY_NCV} "
                  "(unless the options set eps_ncv)"
                  for a, b in moved)
    evidence = (f"complex shift-and-invert at {len(disks)} target(s){why_targets}{off}: the eigenvalues SLEPc "
                    f"converged in {text}"
                    + (f"; |Im σ| ≤ {bound:.4g} everywhere (skew-part bound)" if bound is not None else "")
                    + (f"; {len(rejected)} pair(s) failed the residual gate {residual_tol:g}" if rejected else "")
                    + real_ritz_note(real_ritz, "σ − τ")
                    + "".join(f"; {why}" for why in failed))
    evidence += search_conclusion(modes)
    rectangle = None if bound is None or real_max is None else (real_max, bound, real_how)
    growth = search_growth(modes, "shift-and-invert computes only the eigenvalues near its targets", rectangle)
    return PencilFlutter(True if modes else None, _fastest_first(modes), evidence, counts=counts, rejected=rejected,
                         growth=growth)


# -- the scene level: branches, proxy, the choice of path -------------------------------------

def _sliding_signs(states) -> list:
    signs = sorted({s for s in states if s.slip_sign}, key=lambda s: -s.slip_sign)
    return signs if len(signs) == 1 else [ContactState.SLIP_PLUS, ContactState.SLIP_MINUS]


def grazing_branches(lines) -> list[tuple[str, list]]:
    """[(label, contact lines with every grazing state replaced)]: one entry labelled ""
    without grazing contacts; else ``separated`` (the open side: free) and ``sliding`` (the
    loaded side: v_n = 0 and the friction row in the sliding direction of that contact line —
    the sign its slipping contacts share, each sign in turn when they disagree or none
    slips)."""
    GRAZING = ContactState.GRAZING

    def replaced(line, state):
        return line.in_states(tuple(state if s is GRAZING else s for s in line.states))

    if not any(GRAZING in line.states for line in lines):
        return [("", list(lines))]
    branches = [("separated", [replaced(line, ContactState.SEPARATED) for line in lines])]
    choices = [_sliding_signs(line.states) if GRAZING in line.states else [None] for line in lines]
    for choice in itertools.product(*choices):
        branch = [line if sign is None else replaced(line, sign) for line, sign in zip(lines, choice)]
        label = "sliding " + ",".join(f"{line.name}:{c.value}" for line, c in zip(lines, choice) if c is not None)
        branches.append((label, branch))
    return branches


def combine_branches(flags) -> bool | None:
    """Flutter over grazing branches: True if every branch has it, False if none can."""
    flags = list(flags)
    if all(f is True for f in flags):
        return True
    if all(f is False for f in flags):
        return False
    return None


def pencil_flutter(pen, scene, comm=None, *, dense_max: int | None = None, options: dict | None = None,
                   targets=None, **search) -> PencilFlutter:
    """The flutter analysis of one sliding pencil ``pen`` (a
    :class:`~meicp.contact.problem.Pencil`, every contact state resolved): dense up to
    ``dense_max`` retained DOFs (on rank 0, broadcast), else the search at ``targets`` (default:
    the proxy's, else a λ-line).  Collective."""
    comm = mpi_comm(comm)
    n = int(pen.maps.retained.size)
    if n == 0:
        return PencilFlutter(False, evidence="every DOF is held: nothing can move (a proof)", complete=True,
                             growth=NO_FLUTTER)
    dense = n <= (limits.FLUTTER_DENSE_MAX if dense_max is None else dense_max)
    if pen.damped:  # the quadratic pencil: its dense companion QZ, or the search at scale
        if dense:
            return damped_flutter(pen, comm, dense_max=dense_max)
        search.pop("real_bound", None)  # the undamped pencil's Re σ bound says nothing of λ here
        proportional = proportional_damping(pen.model) if targets is None else None
        if proportional is not None:
            return proportional_search(pen, scene, comm, proportional, options, search)
        if n >= limits.FLUTTER_SEARCH_LARGE:
            search = {"tol": LARGE_EPS_TOL, "strict_tol": STRICT_EPS_TOL, "low_rank": LOW_RANK_TOL, **search}
        return search_damped_flutter(pen, scene, comm, targets=targets, options=options, **search)
    if dense:
        A, B = (to_dense(pen.A), to_dense(pen.B)) if pen.distributed else (pen.A, pen.B)
        return on_root(comm, lambda: dense_flutter(A, B))
    refused = memory_refusal(comm, limits.FLUTTER_SEARCH_BYTES_PER_DOF * n,
                             f"the complex shift-and-invert of {n:,} retained DOFs")
    if refused is not None:
        return refused
    why = ""
    if targets is None:
        count = 1 if n >= limits.FLUTTER_SEARCH_LARGE else SEARCH_TARGETS
        # one answer on every rank: the shift of the collective factor
        targets = on_root(comm, lambda: proxy_targets(scene, pen.lines, count, depth=depth_used(n)))
        why = (f" from a {PROXY_NX}-column, {PROXY_ROWS}-row contact-strip proxy"
               f"{depth_note(scene, pen.lines, n)} (dense QZ)")
        interface = not any(line.name == BASE for line in pen.lines)
        if targets and n >= limits.FLUTTER_OFF_CLUSTER_FROM and interface:
            why += _large_settings(n, pen.lines, search, proxy=True)
        elif targets and n >= limits.FLUTTER_OFF_CLUSTER_FROM:
            moved = [off_cluster(t, 0) for t in targets]
            why += (f", each moved up off its cluster before the first solve ({n:,} ≥ "
                    f"{limits.FLUTTER_OFF_CLUSTER_FROM:,} retained "
                    "DOFs: the proxy's σ lies inside a cluster of ill-conditioned eigenvalues at this size): "
                    + ", ".join(f"{t.real:.4g}{t.imag:+.4g}i → {m.real:.4g}{m.imag:+.4g}i"
                                for t, m in zip(targets, moved)))
            targets = moved
            _large_settings(n, pen.lines, search, moved=True)
        if not targets:
            targets, why = lambda_line_targets(LINE_GROWTH, LINE_FREQUENCIES), LINE_WHY
    _large_settings(n, pen.lines, search)
    return search_flutter(pen.A, pen.B, targets, comm, options=options, why_targets=why, **search)


def _large_settings(n: int, lines, search: dict, *, proxy: bool = False, moved: bool = False) -> str:
    """The search's defaults for ``n`` retained DOFs (``search`` filled in place, the caller's
    own kept) and what they add to the evidence: an interface-strip ``proxy``'s target searched
    where it is for one pair, a target ``moved`` off its cluster with OFF_CLUSTER_NCV; from
    FLUTTER_SEARCH_LARGE the tolerances and the block-low-rank factor."""
    why = ""
    if proxy and n >= limits.FLUTTER_OFF_CLUSTER_FROM and not any(line.name == BASE for line in lines):
        search.setdefault("nev", 1)
        search.setdefault("ncv", INTERFACE_NCV)
        why = f", searched at its σ for {search['nev']} eigenpair(s) with a basis of {search['ncv']}"
    elif n >= limits.FLUTTER_OFF_CLUSTER_FROM and moved:
        search.setdefault("ncv", OFF_CLUSTER_NCV)
    if n >= limits.FLUTTER_SEARCH_LARGE:
        search.setdefault("nev", 2)
        search.setdefault("ncv", 12)
        search.setdefault("tol", LARGE_EPS_TOL)
        search.setdefault("strict_tol", STRICT_EPS_TOL)
        search.setdefault("low_rank", LOW_RANK_TOL)
    return why


def proportional_search(pen, scene, comm, damping, options, search: dict) -> PencilFlutter:
    """The damped flutter search past the dense limit when the damping is proportional to
    stiffness and mass (:mod:`.damped_proportional`): every eigenvalue λ of λ²B + λD − A
    solves ``λ² + (α − cσ)λ − σ = 0`` at an eigenvalue σ of (A, B), so the undamped search
    (:func:`search_flutter`, on the 2n real form, not the companion's 4n) runs at σ₀ = σ(λ₀)
    of the damped proxy's targets λ₀, and each certified σ gives its growing λ, certified
    again on the quadratic pencil.  Collective."""
    n = int(pen.maps.retained.size)
    refused = memory_refusal(comm, limits.FLUTTER_SEARCH_BYTES_PER_DOF * n,
                             f"the flutter search of {n:,} retained DOFs")
    if refused is not None:
        return refused
    lam_targets, why = on_root(comm, lambda: damped_targets(scene, pen.lines, n))  # one answer on every rank
    if not lam_targets:
        return no_target(pen, why)
    targets = [complex(damping.sigma_of(complex(t))) for t in lam_targets]
    why += (", as σ₀ = (λ₀² + αλ₀)/(1 + cλ₀) = " + ", ".join(f"{t.real:.4g}{t.imag:+.4g}i" for t in targets)
            + _large_settings(n, pen.lines, search, proxy=True, moved=True))
    undamped = search_flutter(pen.A, pen.B, targets, comm, options=options, why_targets=why, **search)
    with distributed(comm, pen.A, pen.B, pen.damping()) as mats, QuadraticPencilOps(*mats) as ops:
        modes, rejected, held = mapped_flutter(ops, damping, undamped.modes, lambda lam, res, x: lambda_margin(ops, lam, res, x))
        ceiling = growth_ceiling(ops)
    evidence = (f"damped, {damping.describe()}: every eigenvalue λ of λ²B + λD − A solves λ² + (α − cσ)λ − σ = 0 at "
                f"an eigenvalue σ of (A, B), so the undamped search ran — "
                f"{undamped.evidence.removesuffix(search_conclusion(undamped.modes))} — and its {len(undamped.modes)} "
                f"certified σ give {len(modes)} growing λ certified on λ²B + λD − A"
                + (f", {held} held by the damping (Re λ within its margin of 0 or below)" if held else "")
                + (f", {len(rejected)} failing the residual gate {RESIDUAL_TOL:g} there" if rejected else "")
                + search_conclusion(modes))
    counts = dict(undamped.counts or {}, mapped=len(undamped.modes), held=held)
    growth = search_growth(modes, "the search computes only the eigenvalues near its targets", ceiling=ceiling)
    return PencilFlutter(True if modes else None, _fastest_first(modes), evidence, counts=counts,
                         rejected=list(undamped.rejected or []) + rejected, growth=growth)


def _to_mode(candidate: FlutterCandidate, maps, branch: str) -> FlutterMode:
    u = maps.Q @ candidate.x
    support, interface = [], {}
    for name, idx, kind in maps.pair_of:
        if kind == "t":
            (support if name == "base" else interface.setdefault(name, [])).append(idx)
    return FlutterMode(candidate.sigma, _normalise(u), candidate.residual, np.unique(np.array(support, dtype=np.int64)),
                       {k: np.unique(v) for k, v in interface.items()}, candidate.radius, branch, candidate.found_by)


def analyze_flutter(lattice, lines, scene, *, pencil=None, static=None, options: dict | None = None,
                    **kwargs) -> FlutterVerdict:
    """The flutter verdict of a scene's steady sliding: one pencil per grazing branch, reduced
    from the assembled ``lattice`` (:class:`~meicp.petsc.assembly.LatticeMatrices`;
    ``pencil``: the MEiCP's own, reused when no contact grazes), the verdicts combined.
    Collective on the lattice's communicator."""
    comm = lattice.comm
    t0 = time.perf_counter()
    verdicts, modes, evidences, growths = [], [], [], []
    for label, branch in grazing_branches(lines):
        own = pencil is None or label
        pen = pencil_of(lattice, branch, (), static) if own else pencil
        try:
            part = pencil_flutter(pen, scene, comm, options=options, **kwargs)
            modes += [_to_mode(m, pen.maps, label) for m in part.modes]
        finally:
            if own:
                pen.destroy()
        verdicts.append(part.flutter)
        growths.append(part.growth)
        evidences.append((f"[{label}] " if label else "") + part.evidence)
    modes.sort(key=lambda m: (-m.growth_rate, -abs(m.sigma.imag)))
    evidence = " | ".join(evidences)
    if len(verdicts) > 1:
        evidence = ("grazing contacts, bracketed by a separated and a sliding branch (flutter only if every "
                    "branch has it): " + evidence)
    return FlutterVerdict(combine_branches(verdicts), modes, evidence, time.perf_counter() - t0,
                          combine_growths(growths))


def flutter_asked(scene, flutter) -> bool:
    """Whether to decide flutter: ``flutter`` checked (True or False; None: the scene's
    ``[solver] flutter``), a ProblemError naming it otherwise."""
    flag = as_flag(flutter, "flutter", allow_none=True)
    return bool(scene.solver.flutter) if flag is None else flag


def not_analysed(reason: str) -> FlutterVerdict:
    """The verdict when flutter was not looked at (``flutter=False`` in ``analyze``)."""
    return FlutterVerdict(None, [], f"not analysed ({reason}): undecided")


__all__ = ["RESIDUAL_TOL", "FlutterCandidate", "FlutterVerdict", "PencilFlutter", "RejectedPair",
           "analyze_flutter", "dense_flutter", "grazing_branches", "lambda_line_targets", "pencil_flutter",
           "proxy_targets", "search_flutter"]
