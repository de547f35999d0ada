"""``critical_friction``: the friction at which the first instability starts, as a certified
bracket — the driver.  Divergence (the smallest μ with a σ = 0 mode): the enumerated path
(:mod:`.enumerated`), the bracket (:mod:`.bracket`) and the cross-check (:mod:`.bisection`)
per grazing case; flutter (the smallest μ with a non-real σ of the sliding pencil):
:mod:`.flutter_onset`; both on one assembly of the lattice."""

from __future__ import annotations

import dataclasses
import logging

import numpy as np

from ...core import limits
from ...core.comm import mpi_comm
from ...core.errors import ConvergenceError, ProblemError
from ...core.machine import available_memory
from ...core.validation import as_flag, as_positive
from ...lattice.model import LatticeModel
from ...lattice.size import check_size
from ...petsc.assembly import LatticeMatrices
from ...scene import Scene
from ..damped import DampingUsed
from ..damped_proportional import proportional_damping
from ..damped_mu_windows import prove_up_to
from ..damped_rayleigh import divergence_free_up_to
from ..divergence import enumeration_is_small
from ..maps import grazing_cases, reduced_system
from ..problem import contact_states, pencil_of
from .bisection import check_by_bisection
from .bracket import bracket
from .enumerated import condense_in_mu, friction_pencil, singular_message, smallest_mu
from ..flutter import flutter_asked
from .flutter_onset import flutter_onset
from .result import EXACT_WIDTH, CriticalFriction, Onset

log = logging.getLogger("meicp")

#: why the divergence onset of a damped lattice is computed as the undamped one's
DAMPED_DIVERGENCE = ("at λ = 0 the damping drops out of y = (λ²B + λD − A)x, so the smallest μ with a λ = 0 "
                     "mode is the undamped μ_c, computed here; damped modes born at λ > 0 below it are the "
                     "cross-check's (the quadratic MEiCP enumerated)")
#: the same with damping proportional to stiffness and mass (:mod:`..damped_proportional`)
PROPORTIONAL_DIVERGENCE = ("damping proportional to stiffness and mass makes the damped MEiCP at every μ the undamped "
                           "one (σ = (λ² + αλ)/(1 + cλ), λ ≥ 0 ⟺ σ ≥ 0), so its onset is the undamped μ_c, computed here")


def critical_friction(scene, *, mu_max: float = 1e3, bisection: bool | None = None, tol: float = 1e-8,
                      comm=None, flutter: bool | None = None) -> CriticalFriction:
    """The friction at which the first instability starts for the scene's states (prescribed
    ones; with ``"solve"`` the states of the static equilibrium at the scene's μ), one μ for
    every frictional contact, as a :class:`CriticalFriction`: a float (the upper end of the
    overall bracket, a μ with a certified mode; ``inf`` when none was found up to ``mu_max``)
    carrying ``lower``, ``upper``, ``exact``, ``evidence``, the two onsets ``divergence`` and
    ``flutter`` (each an :class:`~.result.Onset`) and ``first`` (which starts first, when the
    brackets prove it).  ``scene``: a :class:`~meicp.scene.Scene` (:func:`meicp.critical_friction`
    also reads a file).  The lattice is assembled once, in SciPy on every rank.

    The flutter onset μ_f (``flutter``: default the scene's ``[solver] flutter``, true; False
    skips it, ``result.flutter`` is then None and the value the divergence onset): the
    smallest μ with a non-real σ of the sliding pencil, bracketed by an interval cover proved
    flutter-free from μ = 0 and a certified flutter mode (:mod:`.flutter_onset`;
    docs/critical-friction.md, "The flutter onset").

    The divergence onset μ_c, the smallest μ with a σ = 0 mode, is solved as an EiCP in μ,
    condensed onto its complementarity DOFs
    (docs/critical-friction.md).  Up to ``limits.CRITICAL_J`` (20) complementarity pairs per grazing
    case it is enumerated — all 2^|J| supports, exact — and the μ_c found is lifted back to
    the whole reduced lattice and certified there.  Beyond, a bracket: the lower end is a
    proof (diagonally scaled positive definiteness of the condensed S + μR on [0, lower]),
    the upper end a σ = 0 mode found by a search on the condensed problem, lifted and
    certified on the whole reduced lattice; condensations by MUMPS (collective on ``comm``;
    None: this process alone).

    A motion of zero stiffness once the slip DOFs are eliminated — a floating body, or a
    block free to slide as a whole — makes the μ-independent block singular.  If such a
    motion is compatible with the slip directions (x_J ≥ 0) it is a σ = 0 motion at every μ
    and μ_c is undefined: ProblemError.  If it is not (e.g. a layer between two sliding
    contacts slipping in opposite directions), the enumeration meets singular pencils on
    some supports, so the bisection check is then required (ProblemError if it is too large
    for the default ``bisection=None``; a warning if ``bisection=False``); beyond limits.CRITICAL_J
    such a lattice is refused (the bracket needs the lattice held once the contacts are).

    With damping (docs/critical-friction.md, "With damping") μ_c is the smallest μ with a
    λ = 0 mode — where the damping drops out, the undamped μ_c — cross-checked on the
    quadratic MEiCP, and μ_f the smallest μ with a non-real λ, Re λ > 0, its lower end an
    interval cover of the companion form (:mod:`meicp.contact.damped_cover`).

    ``bisection``: cross-check of an enumerated μ_c on the σ-problem with the mass (a σ ≥ 0
    mode must exist just above μ_c and none just below, each decided by enumerating the
    whole reduced pencil; ConvergenceError if they disagree).  ``None`` (default): run it
    when that enumeration is within ``analyze``'s budget for enumerating (2^|J|·r³ ≤ 2e9
    flops, about ≤ 9 pairs on ~150 reduced DOFs), skip it beyond; ``True``: always;
    ``False``: never.  Never run for a bracket.  ``tol``: the bisection's relative width in μ
    (in (0, 0.01]).  ``mu_max``: finite, > 0.
    """
    mu_max, tol, bisection = check_arguments(mu_max, tol, bisection)
    comm = mpi_comm(comm)
    flutter = flutter_asked(scene, flutter)
    lattice, lines = _friction_states(scene)
    proportional = proportional_damping(lattice.model) if scene.damped else None
    divergence = _divergence_onset(lattice, lines, mu_max, bisection, tol, comm,
                                   damped=scene.damped and proportional is None)
    if scene.damped:
        why = DAMPED_DIVERGENCE if proportional is None else PROPORTIONAL_DIVERGENCE
        divergence = dataclasses.replace(divergence, evidence=f"{why} "
                                         f"({DampingUsed.of(scene).describe()}); {divergence.evidence}")
    if not flutter:
        return CriticalFriction.of(divergence, None)
    onset_f = flutter_onset(lattice, lines, scene, mu_max=mu_max, comm=comm, options=dict(scene.petsc))
    return CriticalFriction.of(_floor_for(lattice, lines, divergence, onset_f, comm), onset_f)


def _divergence_onset(lattice, lines, mu_max, bisection, tol, comm, *, damped: bool = False) -> Onset:
    """The divergence onset μ_c (:func:`critical_friction`'s docstring).  ``damped``: damping
    that is not proportional, so damped modes born at λ > 0 may start below μ_c: where the
    quadratic cross-check did not look for them, the lower end is only what is proved free of
    them (:func:`_damped_floor`)."""
    K, M = lattice.K, lattice.M
    ends, evidence = [], []
    small, singular, enumerated = True, False, True
    for case in grazing_cases(lines):
        red = reduced_system(lattice.model, lines, case)
        # every case counts: the bisection check enumerates the σ-problem of each, with or without J
        small = small and enumeration_is_small(red.retained.size, red.J.size)
        if red.J.size == 0:
            continue
        A1, B1 = friction_pencil(K, red)
        if red.J.size <= limits.CRITICAL_J:
            mu, sing = smallest_mu(A1, B1, red.J, mu_max)
            singular = singular or sing
            ends.append((mu, mu))
        else:
            enumerated = False
            lo, up, text = bracket(comm, red, K, M, A1, B1, mu_max)
            ends.append((lo, up))
            evidence.append(text)
    lower = min((lo for lo, _ in ends), default=np.inf)
    upper = min((up for _, up in ends), default=np.inf)
    if enumerated:
        if singular and bisection is None and not small:
            raise ProblemError("critical_friction: a motion of zero stiffness is left once the slip DOFs are "
                               "eliminated (not compatible with the slip directions), so the enumeration meets "
                               "singular pencils and needs the bisection check, but the σ-problem is too large to "
                               "enumerate; pass bisection=True to run it anyway, or hold the body")
        note, born = "", None
        if bisection or (bisection is None and small):
            note, born = check_by_bisection(lattice, lines, upper, mu_max, tol)
        elif singular:
            log.warning("critical_friction: singular μ-independent block and bisection=False: μ_c = %.10g is "
                        "certified but its minimality is not cross-checked", upper)
        elif bisection is None:
            log.info("critical_friction: bisection check skipped (the σ-problem is too large to enumerate)")
        lower = mu_max if not np.isfinite(upper) else upper
        text = ("every support of the condensed EiCP in μ enumerated" +
                (f": no σ = 0 mode up to μ = {mu_max:g}" if not np.isfinite(upper) else
                 ", the smallest μ certified on the whole reduced lattice") + note)
        if born is not None and lattice.model.damped:
            # damped modes below the λ = 0 onset (ξᵀDx < 0 moves the λ = 0 mode below μ_c): the
            # divergence starts where they do, found by sampling μ; below, the damped Rayleigh
            # bound and the λ-windows over μ prove what they can
            top = min(upper, born)
            return _damped_floor(lattice, lines, Onset(top, top, True, text + "; with damping these modes are "
                                                       f"divergence too: it starts at μ ≤ {top:.8g}"), comm=comm)
        if born is not None or bisection or (bisection is None and small):  # cross-checked
            return Onset(lower, upper, True, text)
        return _unchecked(lattice, lines, Onset(lower, upper, True, text), damped, comm)
    exact = (upper - lower <= EXACT_WIDTH * upper) if np.isfinite(upper) else lower >= mu_max
    return _unchecked(lattice, lines, Onset(min(lower, upper), upper, exact, "; ".join(evidence)), damped, comm)


def _unchecked(lattice, lines, onset: Onset, damped: bool, comm) -> Onset:
    """The onset where the cross-check did not run: with damping that is not proportional its
    lower end cut to what is proved (:func:`_damped_floor`), else said to be that of σ = 0 modes,
    with nothing yet proved of modes born at σ > 0 (``floor`` 0: :func:`_floor_for`)."""
    if damped:
        return _damped_floor(lattice, lines, onset, UNCHECKED, comm)
    return dataclasses.replace(onset, evidence=onset.evidence + SIGMA_ZERO, floor=0.0)


def _floor_for(lattice, lines, divergence: Onset, flutter: Onset, comm) -> Onset:
    """``divergence`` with its ``floor`` raised as far as the overall answer needs it: above
    the flutter mode's μ when flutter is certified below the σ = 0 onset (else "flutter starts
    first" is not proved), else up to the flutter onset's lower end (the overall lower end) —
    by the Rayleigh bound along μ and the condensed windows carried over μ, which exclude
    divergence modes of any σ ≥ 0 (:func:`_case_floor`, damping 0).  Collective on ``comm``."""
    if divergence.floor is None:
        return divergence
    need = flutter.upper if flutter.upper < divergence.lower else min(flutter.lower, divergence.lower)
    if not 0 < need < np.inf:
        return divergence
    floor, how = _proved_floor(lattice, lines, min(need * (1 + 1e-9), divergence.lower), comm)
    text = (f"{divergence.evidence}; no divergence mode of any σ ≥ 0 for μ in [0, {floor:.8g}] (what the answer "
            f"needs proved: {how})")
    return dataclasses.replace(divergence, floor=floor, evidence=text)


#: what an undamped onset means when the cross-check did not run (docs/critical-friction.md,
#: "The bisection check")
SIGMA_ZERO = ("; the onset of σ = 0 modes: modes born at σ > 0 below it are not looked for (the cross-check did not "
              "run: too large)")


#: why a damped lattice's λ = 0 onset is not its divergence onset when the cross-check did not run
UNCHECKED = ("with damping, modes born at λ > 0 below the λ = 0 onset are divergence too, and the quadratic "
             "cross-check did not run (too large)")


def _damped_floor(lattice, lines, onset: Onset, why: str = "", comm=None) -> Onset:
    """``onset`` with its lower end cut to what is proved free of damped divergence modes of any
    λ ≥ 0: the damped Rayleigh bound (convex in μ: the bound at 0 and at m proves [0, m];
    :func:`~..damped_rayleigh.divergence_free_up_to`), then condensed λ-windows carried over μ
    from there (:mod:`..damped_mu_windows`), per grazing case.  Collective on ``comm``."""
    floor, how = _proved_floor(lattice, lines, min(onset.lower, onset.upper), comm)
    lower = min(onset.lower, floor)
    text = (f"{onset.evidence}; {why + '; ' if why else ''}no damped divergence mode of any λ ≥ 0 for μ in "
            f"[0, {floor:.8g}]: {how}")
    exact = onset.exact if lower == onset.lower else bool(np.isfinite(onset.upper)
                                                          and onset.upper - lower <= EXACT_WIDTH * onset.upper)
    return Onset(lower, onset.upper, exact, text)


def _proved_floor(lattice, lines, top: float, comm) -> tuple[float, str]:
    """``(m, how)``: no divergence mode of any λ ≥ 0 (σ ≥ 0 without damping) at any μ in [0, m],
    m ≤ top, the smallest over the grazing cases (:func:`_case_floor`), each case's how joined;
    ``(0, "")`` for an infinite ``top``.  Collective on ``comm``."""
    floors = [_case_floor(lattice, lines, case, top, comm) if np.isfinite(top) else (0.0, "")
              for case in grazing_cases(lines)]
    return min(f for f, _ in floors), "; ".join(t for _, t in floors)


def _case_floor(lattice, lines, case, top: float, comm) -> tuple[float, str]:
    """``(m, how)``: no divergence mode (any λ ≥ 0, so any σ = λ² ≥ 0 without damping) of one
    grazing case at any μ in [0, m], m ≤ top; with damping 0 the bound and the windows are the
    undamped ones."""
    # to 1 %: the λ-windows over μ carry it on from there
    floor = divergence_free_up_to(lattice, lines, case, top, rel=1e-2, comm=comm)
    log.info("critical_friction: no divergence mode of any λ ≥ 0 for μ in [0, %.6g] (Rayleigh bound along μ)",
             floor)
    bound = "damped Rayleigh bound" if lattice.model.damped else "Rayleigh bound (sym A(μ) ≺ 0)"
    text = f"[0, {floor:.8g}] by the {bound} at both ends (convex in μ: a proof)"
    if floor >= top:
        return floor, text
    with pencil_of(lattice, lines, case, maps=reduced_system(lattice.model, lines, case).with_friction(1.0)) as unit:
        cover = prove_up_to(unit, floor, top, comm)
    return (cover.reach, f"{text}; {cover.statement}") if cover.reach > floor else (floor, text)


#: the loosest bisection tolerance: a relative width in μ
MAX_BISECTION_TOL = 1e-2


def check_arguments(mu_max, tol, bisection) -> tuple[float, float, bool | None]:
    """``(mu_max, tol, bisection)`` checked: ProblemError naming the one that is wrong (a
    ``mu_max`` of −1 used to fail inside as ``lam_min``, ``tol = 0`` to bisect forever)."""
    return (as_positive(mu_max, "mu_max"), as_positive(tol, "tol", maximum=MAX_BISECTION_TOL),
            as_flag(bisection, "bisection", allow_none=True))


def friction_pencils(scene):
    """The σ = 0 EiCPs in μ of :func:`critical_friction`, condensed onto the
    complementarity DOFs: one ``(Ac, Bc, J)`` per grazing case with a complementarity pair,
    for ``(μ Bc − Ac) x = y`` (dense, order |J|).  Raises ProblemError if the μ-independent
    block is singular.  Serial."""
    lattice, lines = _friction_states(scene)
    out = []
    for case in grazing_cases(lines):
        red = reduced_system(lattice.model, lines, case)
        if red.J.size == 0:
            continue
        Ac, Bc, Jc, _, null = condense_in_mu(*friction_pencil(lattice.K, red), red.J)
        if null.shape[1]:
            raise ProblemError(singular_message(f"the condensed block −Ac (order {Ac.shape[0]}) is singular"))
        out.append((Ac, Bc, Jc))
    return out




def _friction_states(scene) -> tuple[LatticeMatrices, tuple]:
    """The lattice assembled once (SciPy, this process) and the contact lines with their
    states resolved (static equilibrium if asked, on the same K)."""
    if not isinstance(scene, Scene):
        raise ProblemError(f"scene must be a Scene, got {type(scene).__name__} "
                           "(meicp.critical_friction also reads a scene file)")
    check_size(scene, memory=available_memory())  # serial SciPy: this process, no PETSc indices
    model = LatticeModel(scene)
    if model.boundary.bottom != "contact" and not any(i.kind == "frictional" for i in scene.interfaces):
        # without friction there is no friction to be critical (the free 4-node cell's rigid
        # motions once surfaced as a ConvergenceError of the bisection check)
        raise ProblemError("critical_friction needs a frictional contact: boundary.bottom = \"contact\" or an "
                           "[[interfaces]] entry with kind = \"frictional\"; this scene has neither "
                           "(meicp.analyze gives it a modal analysis)")
    lattice = LatticeMatrices(model)
    lines, static = contact_states(scene, lattice)
    if lines is None:
        raise ConvergenceError(f"static equilibrium failed: {static.message}", static)
    return lattice, lines
