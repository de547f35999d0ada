"""The flutter onset μ_f: the smallest μ at which the sliding pencil of the scene's contact
states has a non-real σ, as a certified bracket (docs/critical-friction.md, "The flutter
onset"; docs/flutter.md §6).

Flutter need not be monotone in μ, so a bisection on the verdict alone proves nothing about
"smallest".  The lower end is an interval cover: every μ in [0, lower] lies in an interval
proved flutter-free by one dense eigen-decomposition (:func:`~meicp.contact.flutter_cover.cover_step`);
the upper end is a μ with a certified non-real σ (:func:`~meicp.contact.flutter.dense_flutter`:
|Im σ| beyond its rounding radius, the residual gate passed).  A bisection between them asks
the verdict at the midpoint: certified flutter lowers the upper end, otherwise the cover is
extended towards the midpoint.  The cover stalls where two eigenvalues meet within rounding —
a collision, often the onset itself: the bracket is then reported as it stands.

Past :data:`~meicp.core.limits.FLUTTER_DENSE_MAX` retained DOFs only the search
(:func:`~meicp.contact.flutter.pencil_flutter`) is affordable; it proves flutter, never its
absence, so the upper end is the smallest μ tried with a certified mode and the lower end 0 —
on a damped lattice the largest μ up to which every eigenvalue is proved to decay
(:func:`~meicp.contact.damped_flutter_free.flutter_free_up_to`).
With grazing contacts every branch (:func:`~meicp.contact.flutter.grazing_branches`) has its
own pencil: flutter is certified at a μ when every branch has it, excluded where no branch
can have it, as in ``analyze``.
"""

from __future__ import annotations

import dataclasses
import logging
import time

import numpy as np

from ...core import limits
from ...core.errors import ConvergenceError
from ...eicp.quadratic import quadratic_spectrum
from ...petsc.pencil import reduced_pencil
from ..flutter import _to_mode, grazing_branches, pencil_flutter
from ..damped import classify_spectrum
from ..damped_cover import QuadraticFamily, damped_cover_step
from ..damped_flutter_free import flutter_free_up_to
from ..flutter_dense import dense_flutter
from ..flutter_cover import PencilFamily, cover_step
from ..maps import reduced_system
from ..on_root import on_root
from ..problem import pencil_of
from ..result import FlutterMode
from .result import FLUTTER_EXACT_WIDTH, Onset

log = logging.getLogger("meicp")

#: the cover has stalled at μ when its next step would be shorter than STALL·FLUTTER_EXACT_WIDTH·μ:
#: it could not narrow the bracket any more
STALL = 1e-3
#: the first μ tried for the upper end when no contact line has friction
MU_FIRST = 1.0
#: verdicts tried just past a stalled cover (at μ + scale·4^k): where two eigenvalues meet, a
#: non-real pair is often born
PROBES = 12


@dataclasses.dataclass
class Budget:
    """What one onset may spend: ``solves`` eigen-decompositions (dense) or searches (large
    pencils), and ``seconds`` of wall-clock time."""

    solves: int
    seconds: float
    used: int = 0
    start: float = dataclasses.field(default_factory=time.perf_counter)

    @property
    def out(self) -> bool:
        return self.used >= self.solves or time.perf_counter() - self.start > self.seconds

    def take(self) -> bool:
        """Spend one solve; False (nothing spent) once the budget is out."""
        if self.out:
            return False
        self.used += 1
        return True

    def text(self, what: str) -> str:
        return (f"the budget of {self.solves} {what} or {self.seconds:g} s ran out "
                f"({self.used} in {time.perf_counter() - self.start:.1f} s; meicp.core.limits)")


@dataclasses.dataclass
class Branch:
    """One sliding pencil of the scene as μ varies: its grazing ``label``, contact ``lines``
    and :class:`~meicp.contact.flutter_cover.PencilFamily`."""

    label: str
    lines: list
    family: PencilFamily


def sliding_families(lattice, lines) -> list[Branch]:
    """The sliding pencils ``(A₀ + μA₁, B₀ + μB₁)`` of the scene's states, one per grazing
    branch, every contact at the same μ (SciPy, from the lattice's K and M); on a damped
    lattice the quadratic ones, with ``D₀ + μD₁`` from its C
    (:class:`~meicp.contact.damped_cover.QuadraticFamily`)."""
    K, M = lattice.K, lattice.M
    C = lattice.damping() if lattice.model.damped else None
    out = []
    for label, branch in grazing_branches(lines):
        red = reduced_system(lattice.model, branch, ())
        A0, B0 = reduced_pencil(K, M, red.P0, red.Q, red.retained)
        A1, B1 = reduced_pencil(K, M, red.P1, red.Q, red.retained)
        if C is None:
            family = PencilFamily(A0, A1, B0, B1, red, label)
        else:
            family = QuadraticFamily(A0, A1, B0, B1, red, label, D0=(red.P0 @ C @ red.Q).tocsr(),
                                     D1=(red.P1 @ C @ red.Q).tocsr())
        out.append(Branch(label, list(branch), family))
    return out


def _damped(families) -> bool:
    return any(isinstance(f, QuadraticFamily) for f in families)


def _cover_step(family, mu: float):
    return damped_cover_step(family, mu) if isinstance(family, QuadraticFamily) else cover_step(family, mu)


def flutter_onset(lattice, lines, scene, *, mu_max: float, comm=None, options: dict | None = None) -> Onset:
    """The flutter onset of the scene's sliding pencils (``lines``: the contact lines with
    their states; ``lattice``: :class:`~meicp.petsc.assembly.LatticeMatrices`, SciPy) as an
    :class:`~.result.Onset`, searched up to ``mu_max``.  Dense (on rank 0, broadcast) up to
    ``limits.FLUTTER_DENSE_MAX`` retained DOFs, else the search.  Collective on ``comm``."""
    clock = time.perf_counter()
    branches = sliding_families(lattice, lines)
    if not any(b.family.depends_on_mu for b in branches) and all(_symmetric(b.family) for b in branches):
        damped = ("; with damping D = Q̃ᵀCQ̃ ⪰ 0, so xᴴQ(λ)x = 0 gives Re λ ≤ 0 for a non-real λ"
                  if _damped([b.family for b in branches]) else "")
        return Onset(np.inf, np.inf, True, "no contact slides: the sliding pencil does not depend on μ and "
                                           f"is symmetric with B positive definite{damped} — no flutter at any μ "
                                           "(a proof)")
    frictions = [line.friction for line in lines if line.friction and line.friction > 0]
    start = min(max(frictions, default=MU_FIRST), mu_max)
    order = max(b.family.order for b in branches)
    if order <= limits.FLUTTER_DENSE_MAX:
        onset = on_root(comm, lambda: dense_onset([b.family for b in branches], start, mu_max))
    else:
        onset = search_onset(lattice, branches, scene, comm, start, mu_max, options)
    log.info("critical_friction: flutter onset in [%.10g, %.10g]%s, %.1f s", onset.lower, onset.upper,
             " (exact)" if onset.exact else "", time.perf_counter() - clock)
    return onset


def _symmetric(family: PencilFamily) -> bool:
    """A₀ and B₀ symmetric, B₀ positive definite (diagonal positive, or a Cholesky factor of
    a small one), or of order 0: every σ of the pencil real."""
    A, B = family.A0, family.B0
    if family.order == 0:
        return True
    if (A != A.T).nnz or (B != B.T).nnz:
        return False
    if isinstance(family, QuadraticFamily):  # D = P̃₀CQ̃ is a congruence of C ⪰ 0 only when P̃₀ = Q̃ᵀ
        maps = family.maps
        if maps is None or (maps.P0 != maps.Q.T).nnz:
            return False
        return _symmetric(PencilFamily(A, family.A1, B, family.B1))
    if family.diagonal:
        return True
    if family.order > limits.FLUTTER_DENSE_MAX:
        return False
    try:
        np.linalg.cholesky(B.toarray())
    except np.linalg.LinAlgError:
        return False
    return True


def _trials(start: float, mu_max: float) -> list[float]:
    """μ tried for a first certified flutter mode: the scene's friction, doubled up to mu_max."""
    out, mu = [], start
    while mu < mu_max:
        out.append(mu)
        mu *= 2
    return out + [mu_max]


class _Cover:
    """The cover of one sliding pencil: every μ in [0, ``reached``] proved flutter-free
    (``started`` once μ = 0 is), extended by :meth:`extend`."""

    def __init__(self, family: PencilFamily):
        self.family = family
        self.reached, self.started, self.ahead, self.last, self.steps = 0.0, False, 0.0, 0.0, 0
        self.stalled = ""

    def extend(self, target: float, budget: Budget, stall: float) -> None:
        """Cover up to ``target`` (or stall: the next step shorter than ``stall``·reached, or
        run out of budget): each centre one interval ahead of the covered end, moved back
        while its interval leaves a hole."""
        while not self.started or self.reached < target:
            if not budget.take():
                self.stalled = "budget"
                return
            centre = self.reached + self.ahead if self.started else 0.0
            step = _cover_step(self.family, centre)
            self.steps += 1
            if step.radius > 0 and centre - step.radius <= self.reached:
                # the next centre where its interval, predicted from the trend of the last two,
                # just meets this one (intervals shrink geometrically towards a collision)
                trend = min(1.0, step.radius / self.last) if self.started and self.last > 0 else 1.0
                self.reached, self.started = centre + step.radius, True
                self.ahead, self.last = 0.95 * trend * step.radius, step.radius
                if self.reached < target and self.ahead < stall * self.reached:
                    self.stalled = (f"at μ = {self.reached:.10g} (intervals shorter than "
                                    f"{stall * self.reached:.1e}: two eigenvalues meet just above)")
                    return
                continue
            if not self.started:
                self.stalled = f"at μ = 0: {step.why} ({self.family.at_zero})"
                return
            hole = centre - self.reached
            self.ahead = min(0.9 * step.radius, 0.5 * hole) if step.radius > 0 else 0.25 * hole
            shortest = stall * self.reached
            if self.ahead < shortest:
                why = step.why or f"intervals shorter than {shortest:.1e}"
                self.stalled = (f"at μ = {self.reached:.10g} ({why} at μ = {centre:.10g}: two eigenvalues meet "
                                "there, where no interval of the cover can pass)")
                return


def _verdict(families, mu: float, budget: Budget):
    """(flutter, mode) of every family's dense verdict at μ: flutter True when each has a
    certified non-real σ (the mode: the first family's fastest), else False/None."""
    mode = None
    for fam in families:
        if not budget.take():
            return None, None
        if isinstance(fam, QuadraticFamily):
            A, B, D = fam.at(mu)
            part = classify_spectrum(quadratic_spectrum(A.toarray(), B.toarray(), D.toarray()))
        else:
            A, B = fam.at(mu)
            part = dense_flutter(A, B)
        if part.flutter is not True:
            return part.flutter, None
        if mode is None:
            best = part.modes[0]
            mode = (_to_mode(best, fam.maps, fam.branch) if fam.maps is not None else
                    FlutterMode(best.sigma, best.x, best.residual, radius=best.radius, found_by=best.found_by))
    return True, mode


class _DenseOnset:
    """The bracket's state during :func:`dense_onset`: the covers, the certified upper end
    and its mode, the μ tried for it."""

    def __init__(self, families, width: float):
        self.families, self.width = families, width
        self.budget = Budget(limits.FLUTTER_ONSET_SOLVES, limits.FLUTTER_ONSET_SECONDS)
        self.covers = [_Cover(f) for f in families]
        self.upper, self.mode, self.tried = np.inf, None, []

    @property
    def lower(self) -> float:
        return min(c.reached for c in self.covers)

    @property
    def stalled(self) -> bool:
        """Some cover can go no further (a collision), not for want of budget."""
        return any(c.stalled and c.stalled != "budget" for c in self.covers)

    def flutters(self, mu: float) -> bool:
        """Whether flutter is certified at μ; if so, and below the upper end, it becomes it."""
        flutter, mode = _verdict(self.families, mu, self.budget)
        self.tried.append(mu)
        if flutter and mu < self.upper:
            self.upper, self.mode = mu, mode
        return bool(flutter)

    def extend(self, target: float) -> None:
        """Every cover extended to ``target`` (or to where it stalls, or the budget ends)."""
        for cover in self.covers:
            if not cover.stalled:
                cover.extend(target, self.budget, STALL * self.width)
            if np.isfinite(self.upper) and cover.reached >= self.upper:
                raise ConvergenceError(f"critical_friction: the cover proves no flutter up to μ = {cover.reached:.10g}, "
                                       f"above the certified flutter mode at μ = {self.upper:.10g}: a rounding blunder, "
                                       "no bracket")

    def probe_past(self, mu: float, scale: float, mu_max: float) -> None:
        """Where a cover stalls two eigenvalues meet: a non-real pair may be born just past
        it.  The verdict at μ + scale·4^k, k = 0, 1, …, below the upper end and up to
        ``mu_max`` (the onset asked for), until certified."""
        for k in range(PROBES):
            q = mu + scale * 4.0 ** k
            if q >= self.upper or q > mu_max or self.budget.out or self.flutters(q):
                return


def dense_onset(families, start: float, mu_max: float, width: float = FLUTTER_EXACT_WIDTH) -> Onset:
    """The flutter onset of ``families`` (:class:`~meicp.contact.flutter_cover.PencilFamily`,
    one per grazing branch) by dense eigen-solves: the upper end a certified flutter mode
    (first at :func:`_trials`, or just past where the cover stalls, then lowered by
    bisection), the lower end an interval cover from μ = 0 (module docstring).  Serial."""
    st = _DenseOnset(families, width)
    for mu in _trials(start, mu_max):
        if st.flutters(mu) or st.budget.out:
            break
    probed = False
    if not np.isfinite(st.upper):
        st.extend(mu_max)
        if st.stalled and st.lower < mu_max:
            st.probe_past(st.lower, width * max(st.lower, start), mu_max)
            probed = True
    below = None  # once the cover stalls: the last midpoint without a certified mode
    while np.isfinite(st.upper) and not st.budget.out:
        floor = st.lower if below is None else below
        if st.upper - floor <= width * st.upper:
            break
        mid = 0.5 * (floor + st.upper)
        if st.flutters(mid):
            continue
        if below is not None or st.budget.out:
            below = mid  # the upper end alone, on the verdict: no proof below it is claimed
            continue
        st.extend(mid)
        if st.lower < mid and st.stalled:
            if not probed:
                st.probe_past(st.lower, width * max(st.lower, start), mu_max)
                probed = True
            below = None if st.upper < mid else mid
    return _dense_result(st, mu_max)


def _dense_result(st: _DenseOnset, mu_max: float) -> Onset:
    steps = sum(c.steps for c in st.covers)
    upper, width = st.upper, st.width
    lower = min(st.lower, upper, mu_max)
    damped = _damped(st.families)
    text = (f"every {'λ proved real or decaying (Re λ < 0)' if damped else 'σ proved real and simple'} for μ in "
            f"[0, {lower:.10g}] by {steps} dense eigen-decompositions (Gershgorin disks in the eigenbasis"
            f"{' of the companion form' if damped else ''}; an interval cover, a proof)")
    if st.mode is not None:
        text += f"; a certified {_mode_text(st.mode, damped)} at μ = {upper:.10g} ({st.mode.found_by})"
    else:
        shown = ", ".join(f"{m:.6g}" for m in st.tried[:8]) + (", …" if len(st.tried) > 8 else "")
        text += f"; no certified flutter mode at the {len(st.tried)} μ tried ({shown})"
    exact = (upper - lower <= width * upper) if np.isfinite(upper) else lower >= mu_max
    stalls = [c.stalled for c in st.covers if c.stalled and c.stalled != "budget"]
    if stalls and not exact:
        text += "; the cover stalls " + "; ".join(stalls) + ": undecided between the ends"
    if st.budget.out and not exact:
        text += "; " + st.budget.text("dense eigen-decompositions")
    return Onset(lower, upper, exact, text, st.mode)


def search_onset(lattice, branches, scene, comm, start: float, mu_max: float, options) -> Onset:
    """The upper end by the search (it proves flutter, never its absence): the smallest μ
    tried with a certified mode in every branch, lowered by bisection on the search's verdict
    within ``limits.FLUTTER_ONSET_SEARCHES``; the lower end 0, or on a damped lattice the
    largest μ up to which the damped flutter-free proof holds.  Collective."""
    budget = Budget(limits.FLUTTER_ONSET_SEARCHES, limits.FLUTTER_ONSET_SECONDS)

    def verdict(mu):
        mode = None
        for b in branches:
            if not budget.take():
                return None
            pen = pencil_of(lattice, b.lines, (), maps=b.family.maps.with_friction(mu))
            try:
                part = pencil_flutter(pen, scene.with_friction(mu), comm, options=options)
            finally:
                pen.destroy()
            if part.flutter is not True:
                return None
            mode = mode or _to_mode(part.modes[0], pen.maps, b.label)
        return mode

    upper, mode, tried, below = np.inf, None, [], 0.0
    for mu in _trials(start, mu_max):
        tried.append(mu)
        mode = verdict(mu)
        if mode is not None:
            upper = mu
            break
        if budget.out:
            break
    while np.isfinite(upper) and not budget.out and upper - below > FLUTTER_EXACT_WIDTH * upper:
        mid = 0.5 * (below + upper)
        tried.append(mid)
        found = verdict(mid)
        if found is not None:
            upper, mode = mid, found
        else:
            below = mid  # no certified mode there: not a proof of anything, only where to look
    lower, proof = _flutter_free_below(lattice, branches, upper if np.isfinite(upper) else mu_max, comm)
    text = (f"{_order_text(branches)}: the search proves flutter, never its absence, so "
            + (proof + "; " if lower > 0 else "nothing is proved below the upper end (lower end 0, not exact); ")
            + f"searched at μ = {', '.join(f'{m:.6g}' for m in tried)}")
    if mode is not None:
        text += f"; a certified {_mode_text(mode, _damped([b.family for b in branches]))} at μ = {upper:.10g} ({mode.found_by})"
    else:
        text += ": no certified flutter mode"
    if budget.out:
        text += "; " + budget.text("searches")
    return Onset(min(lower, upper), upper, bool(np.isfinite(upper) and upper - lower <= FLUTTER_EXACT_WIDTH * upper),
                 text, mode)


def _flutter_free_below(lattice, branches, upper: float, comm=None) -> tuple[float, str]:
    """The lower end past the dense limit of a damped lattice: the largest m ≤ ``upper`` with
    every branch's damped sliding pencil proved free of growing eigenvalues on [0, m]
    (:func:`~meicp.contact.damped_flutter_free.flutter_free_up_to`), and what it proved; 0
    undamped (no such proof there: regular lattices flutter at tiny μ)."""
    if not _damped([b.family for b in branches]) or not np.isfinite(upper) or upper <= 0:
        return 0.0, ""
    ends = [flutter_free_up_to(lattice, b.lines, b.family.maps, upper, comm=comm) for b in branches]
    lower = min(m for m, _ in ends)
    return lower, "; ".join(text for _, text in ends)


def _mode_text(mode, damped: bool) -> str:
    if damped:
        lam = complex(np.sqrt(complex(mode.sigma)))
        return f"damped flutter mode λ = {lam.real:.6g}{lam.imag:+.6g}i"
    return f"non-real σ = {mode.sigma.real:.6g}{mode.sigma.imag:+.6g}i (|Im σ| > radius {mode.radius:.1e})"


def _order_text(branches) -> str:
    order = max(b.family.order for b in branches)
    return f"{order:,} retained DOFs > FLUTTER_DENSE_MAX = {limits.FLUTTER_DENSE_MAX:,}"
