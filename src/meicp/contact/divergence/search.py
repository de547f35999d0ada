"""The SLEPc active-set search for a divergence mode from the top of the σ-window
(:mod:`meicp.petsc.eicp_active_set`).

Its shift sits at an estimate of λ_max(sym A, sym B), which bounds the real part of every
eigenvalue of every support's pencil, so the first pair it takes is the rightmost real
eigenvalue of the full support S = J — never the slow vibrations clustered just below 0 that a
shift at 0 returns; each support update follows that pair.  A returned mode is certified on the whole
reduced problem.  The first search starts lower where the scene's contact-strip proxy has a
real σ_p > 0 below the top (at ``PROXY_SHIFT``·σ_p: a contact mode's σ hardly depends on the
lattice's size, and the top, a Ritz value of the symmetric part, can lie far above every
eigenvalue, so that the rightmost converged slowly or not first).  The first search is short (``FIRST_SEARCH`` support updates,
``FIRST_EPS_MAX_IT`` restarts each, given up after ``FIRST_GIVE_UP`` restarts when every Ritz
value estimates an eigenvalue below 0); the whole search, with the caller's budget, comes
only after the condensed proof stopped.

Both follow one eigenpair per solve.  A caller's or scene's ``nev`` > 1 only widens a last
search, made when the whole one found nothing: each of the ``nev`` eigenpairs must converge,
and beyond the rightmost they sit in the cluster of slow vibrations, where Krylov–Schur needs
tens of restarts (docs/benchmarks-notes.md, "nev widens the last search": 87 restarts instead
of 9 for the same mode of the shipped 10⁶-DOF scene coarsened to 4·10⁴ DOFs).
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, replace

from ...core.errors import PetscOptionError
from ...eicp.solve import solve_eicp
from ..on_root import on_root
from ..proxy import rightmost_real
from .modes import FoundModes, certified_modes

#: support updates of the first, short search (before the proof), and
#: the Krylov–Schur restarts each of its eigen-solves may take: a rightmost eigenvalue that is
#: a mode stands apart and converges in a few, while one inside the cluster of slow vibrations
#: is no mode and costs the most (docs/benchmarks-notes.md, "first search")
FIRST_SEARCH = 3
FIRST_EPS_MAX_IT = 6
#: ... and it gives up after this many restarts when every Ritz value estimates an eigenvalue
#: below 0: on a stable lattice all sit in the cluster of slow vibrations from the first
#: restart on, while a mode shows above 0 at once (docs/benchmarks-notes.md, "first search");
#: the proof, or the whole search after it, decides
FIRST_GIVE_UP = 1
#: ... and past FIRST_EPS_MAX_IT restarts, up to this many, it goes on while a Ritz value
#: above 0 converges fast (its error estimate falling ≥ 10× a restart): a mode of the shipped
#: 10⁶-DOF scene coarsened to 4·10⁴ DOFs was at 8e-10 after six restarts and converged in
#: nine, where stopping at six cost a condensed proof and a σ-window before the whole search
#: found it (docs/benchmarks-notes.md, "first search")
FIRST_EPS_MAX_IT_CONVERGING = 12
#: the first search starts at PROXY_SHIFT times the contact-strip proxy's rightmost real
#: eigenvalue σ_p when that lies below the window's top: a contact mode's σ hardly depends on
#: the lattice's size, so from there the lattice's mode converges in a restart or two where
#: from the top (a Ritz value of the symmetric part, often 10–20× above it) it took nine, or
#: never came first.  On the 37 scenes of the first-search benchmark whose top is positive
#: (two-layer 400 and 1000 columns, frictional interfaces): every mode found from the top
#: found again, the same σ, and 6 more (docs/benchmarks-notes.md, "first search from the proxy")
PROXY_SHIFT = 1.25
#: where the search from the top ends with no real eigenpair nearest its shift (a nonsymmetric
#: pencil at large μ: complex eigenvalues crowd the top of the window), short searches from
#: these fractions of the top follow (a frictional interface at μ = 20, 10⁴ DOFs: the top at
#: σ = 86, the mode at σ = 0.82, found from the shift 0.86)
LOWER_SHIFTS = (1e-1, 1e-2, 1e-3)

log = logging.getLogger("meicp")


@dataclass(frozen=True)
class Tally:
    """Supports visited and eigen-solves made by the searches so far."""

    supports_visited: int = 0
    eigen_solves: int = 0

    def after(self, eicp) -> Tally:
        return Tally(self.supports_visited + int(eicp.coverage.get("supports_visited", 0)),
                     self.eigen_solves + int(eicp.coverage.get("eigen_solves", 0)))


@dataclass(frozen=True)
class SearchSettings:
    """One pencil's search: its keywords for :func:`~meicp.eicp.solve.solve_eicp` (``target``,
    ``nev`` = 1, ``options``, the caller's own), the whole search's budget of support updates
    (None: the solver's default), the ``nev`` > 1 of the last, widened search (None: no such
    search), and the clock of the verdict (for the log)."""

    pen: object
    comm: object
    lam_min: float
    tol: float
    keywords: dict
    full_budget: int | None
    widened_nev: int | None
    started: float
    #: the caller gave the shift (``target``): the first search keeps it
    target_given: bool = False

    @property
    def target(self) -> float:
        return self.keywords["target"]

    @property
    def first_budget(self) -> int:
        """Support updates of the first search: FIRST_SEARCH, or fewer when the whole budget is."""
        return FIRST_SEARCH if self.full_budget is None else min(FIRST_SEARCH, self.full_budget)

    @property
    def whole_search_left(self) -> bool:
        """Whether the whole budget exceeds the first search's."""
        return self.full_budget is None or self.full_budget > self.first_budget

    def from_shift(self, shift: float) -> SearchSettings:
        """The same search from another shift (a certified σ_max, the proxy's estimate)."""
        return replace(self, keywords={**self.keywords, "target": shift})

    def widened(self) -> SearchSettings:
        """The same search with the caller's ``nev`` eigenpairs per solve."""
        return replace(self, keywords={**self.keywords, "nev": self.widened_nev})


def search_settings(pen, scene, comm, lam_min: float, tol: float, options, shift: float,
                    started: float) -> SearchSettings:
    """The caller's keywords, completed: the shift at the estimated top of the window (the
    top is the short run's Ritz value: placing the shift needs no certificate), one
    eigenpair per solve, the scene's ``[petsc]`` options; ``max_iter`` (else the scene's) is
    the whole budget; ``nev`` (else the scene's) > 1 is the widened last search's."""
    keywords = dict(options)
    given = "target" in keywords
    keywords.setdefault("target", shift)
    nev = keywords.pop("nev", None) or scene.solver.nev or 1
    keywords["nev"] = 1
    keywords.setdefault("options", dict(scene.petsc))
    full_budget = keywords.pop("max_iter", scene.solver.max_iterations or None)
    return SearchSettings(pen, comm, lam_min, tol, keywords, full_budget, int(nev) if nev > 1 else None, started,
                          given)


@dataclass(frozen=True)
class SearchOutcome:
    """One search: the EiCP result, the tally of every search so far, its certified modes,
    and the shift it started from."""

    eicp: object
    tally: Tally
    modes: FoundModes
    target: float

    @property
    def found(self) -> bool:
        return bool(self.modes.found)


def search(settings: SearchSettings, before: Tally, max_iter: int | None, *, first: bool = False) -> SearchOutcome:
    """One active-set search with at most ``max_iter`` support updates (None: the solver's
    default); ``first``: the short search's restarts and its giving up.  A ``[petsc]`` or
    command-line value PETSc rejects is bad input: PetscOptionError."""
    pen = settings.pen
    budget = {} if max_iter is None else {"max_iter": max_iter}
    if first:
        budget["options"] = {"eps_max_it": FIRST_EPS_MAX_IT_CONVERGING, **settings.keywords["options"]}
        budget["give_up_after"] = FIRST_GIVE_UP
        budget["converging_after"] = FIRST_EPS_MAX_IT
    eicp = solve_eicp(pen.A, pen.B, J=pen.maps.J, method="active-set", lam_min=0.0, tol=settings.tol,
                      comm=settings.comm, **{**settings.keywords, **budget})
    if eicp.coverage.get("option_error"):
        raise PetscOptionError(eicp.message)
    got = certified_modes(eicp, pen, settings.lam_min)
    log.info("divergence: search from σ = %.6g%s, %d mode(s), %s Krylov–Schur restart(s)%s (%.2f s)",
             settings.target, "" if settings.keywords["nev"] == 1 else f" with nev = {settings.keywords['nev']}",
             len(got.found), eicp.coverage.get("eps_iterations", "?"),
             ", given up: no Ritz value above 0" if eicp.coverage.get("gave_up") else "",
             time.perf_counter() - settings.started)
    return SearchOutcome(eicp, before.after(eicp), got, settings.target)


def first_shift(settings: SearchSettings, scene) -> tuple[float | None, str]:
    """``(shift, why)``: where the first search starts — PROXY_SHIFT times the rightmost real
    eigenvalue of the scene's contact-strip proxy (:func:`~meicp.contact.proxy.rightmost_real`,
    computed on rank 0: the shift is collective) when that is below the window's top
    ``settings.target``, else the top; the caller's own ``target`` when it gave one; None
    (no first search) when the proxy has no real σ above 0: from the top the short search
    then found nothing on every scene measured (docs/benchmarks-notes.md,
    "no first search without a proxy mode").  Collective."""
    if settings.target_given:
        return settings.target, "the caller's target"
    estimate = on_root(settings.comm, lambda: rightmost_real(scene, settings.pen.lines))
    if estimate == 0.0:
        return None, "the contact-strip proxy has no real σ above 0"
    if estimate is None or not PROXY_SHIFT * estimate < settings.target:
        return settings.target, "the window's top"
    return PROXY_SHIFT * estimate, f"{PROXY_SHIFT:g}× the contact-strip proxy's rightmost real σ = {estimate:.6g}"


def first_search(settings: SearchSettings, scene=None, *, skip: bool = True) -> SearchOutcome | None:
    """The short search: a mode on the full support, or one support update away, is found at
    once.  From the shift :func:`first_shift` places (given the scene; where it places none,
    None — no search — or, with ``skip`` False, from the top), else from ``settings.target``;
    the outcome's ``target`` says where it started."""
    if scene is not None:
        shift, why = first_shift(settings, scene)
        if shift is None and not skip:
            shift, why = settings.target, f"the window's top: {why}, searched all the same"
        if shift is None:
            log.info("divergence: no first search (%s)", why)
            return None
        log.info("divergence: first search from σ = %.6g (%s)", shift, why)
        settings = settings.from_shift(shift)
    return search(settings, Tally(), settings.first_budget, first=True)


def whole_search(settings: SearchSettings, before: Tally) -> SearchOutcome:
    """The search with its whole budget, after the proofs stopped."""
    return search(settings, before, settings.full_budget)


def widened_search(settings: SearchSettings, before: Tally) -> SearchOutcome:
    """The last search, with the caller's ``nev`` eigenpairs per solve and the whole budget:
    only when the searches that follow one eigenpair found nothing."""
    return search(settings.widened(), before, settings.full_budget)


def searches_below(settings: SearchSettings, last: SearchOutcome) -> tuple[SearchOutcome, list[float]]:
    """Short searches from shifts ``LOWER_SHIFTS`` times the window's top, lowest last, until
    one certifies a mode: where the search from the top ends without a real eigenpair nearest
    its shift.  Returns the last outcome and the shifts tried."""
    tried = []
    for factor in LOWER_SHIFTS:
        if not settings.target > 0:
            break
        tried.append(settings.target * factor)
        last = search(settings.from_shift(tried[-1]), last.tally, settings.full_budget, first=True)
        if last.found:
            break
    return last, tried
