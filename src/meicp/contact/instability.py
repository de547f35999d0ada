"""The instability analysis end to end (seed 000 §III, docs/design.md §7–§8): ``meicp.analyze``.

1. Lattice: K and M (distributed when ``comm`` has several ranks), assembled once
   (:class:`~meicp.petsc.assembly.LatticeMatrices`): every later step reads them.
2. Contact states: prescribed by the scene, or from the static frictional equilibrium
   (:func:`meicp.contact.static.static_equilibrium`) when a contact set says ``"solve"``.
3. For each assignment of the grazing contacts' tangential cases: the pencil
   ``A = −P̃ K Q̃``, ``B = P̃ M Q̃`` (:mod:`meicp.contact.problem`) and the MEiCP
   ``(σB − A)x = w`` solved for σ ≥ 0: by support enumeration when the reduced problem is
   small (every divergence mode; a complete enumeration that finds none, status
   ``no_solution``, proves stability — ``undecided`` or ``out_of_range`` does not), else
   decided by :mod:`meicp.contact.divergence` (its driver gives the order: the Rayleigh
   bound at 0, a first short search, the condensed proof on [0, ∞), the σ-window only where
   that proof stops, the whole search); undecided says what was established.
4. Modes back in natural numbering: ``u = Q̃ x``.
5. Flutter of steady sliding: the non-real σ of each sliding pencil (:mod:`meicp.contact.flutter`).

The verdict is about σ ≥ 0 whatever ``lam_min``: a negative σ is an oscillation, never a
divergence mode, so ``lam_min`` must be ≥ 0, and a ``lam_min > 0`` only filters the modes
listed (the search still covers every σ ≥ 0, so a mode with 0 ≤ σ < lam_min still makes the
scene unstable, and the evidence says how many were left out).

A scene without contact has no frictional instability to decide: it gets a modal analysis
instead, its lowest vibration modes (:mod:`meicp.contact.modal`).  Each phase runs in its
PETSc log stage (``-log_view``: static, assemble, reduce, eigen, flutter).

The verdict of each pencil is :mod:`meicp.contact.divergence`; the PETSc side (distributed pencil, inertia) in
:mod:`meicp.petsc`.  The critical friction is :mod:`meicp.contact.critical_friction`.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Mapping

import numpy as np

from ..core.comm import available_memory_on, comm_size, mpi_comm
from ..core.errors import ProblemError
from ..core.progress import Progress
from ..core import limits
from ..core.validation import as_int, as_real, check_keywords, check_tol
from ..eicp.solve import available_methods
from ..lattice.model import LatticeModel
from ..lattice.size import check_size
from ..petsc.assembly import LatticeMatrices
from ..petsc.comm import index_max
from ..petsc.stages import stage
from ..scene import Scene
from .damped import DampingUsed, damped_divergence, refuse
from .divergence import all_held, divergence_of
from .flutter import analyze_flutter, flutter_asked, not_analysed
from .lines import BASE, ContactState, state_names
from .maps import grazing_cases
from .modal import has_contact, modal_analysis
from .problem import contact_states, pencil_of
from .result import InstabilityResult, Mode

log = logging.getLogger("meicp")

#: keywords ``analyze`` sets itself, or that would turn the verdict into a statement about a
#: window of σ only (``lam_max``), each with the reason it is refused
REFUSED_OPTIONS = {"J": "analyze sets it itself", "comm": "analyze sets it itself",
                   "all_solutions": "analyze sets it itself",
                   "lam_max": "the verdict covers every σ ≥ 0; use lam_min to filter the modes listed"}
#: the eigen-solver keywords ``analyze`` hands on (any other name is a TypeError): shift,
#: eigenpairs per solve, the active-set search's budget, the enumeration's limit of pairs,
#: PETSc options for the eigen-solves (default: the scene's ``[petsc]``)
SOLVER_OPTIONS = ("target", "nev", "max_iter", "max_j", "options")


def analyze(scene: Scene, comm=None, *, method: str | None = None, lam_min=None, tol=None,
            scene_path=None, flutter: bool | None = None, flutter_dense_max: int | None = None,
            **solver_options) -> InstabilityResult:
    """Divergence modes of a scene's contact equilibrium (see the module docstring).

    scene: a :class:`~meicp.scene.Scene` (:func:`meicp.analyze` also reads a scene file).
    comm: an mpi4py communicator (None: serial SciPy/PETSc on one process).  method:
    ``enumerate`` | ``active-set`` | None (the scene's ``[solver] method``, ``auto`` = by
    size).  lam_min: list only the modes with σ ≥ lam_min (finite, ≥ 0; default the scene's
    ``[solver] lam_min``, else 0); the verdict is about every σ ≥ 0 regardless.  tol: the
    certificate tolerance (default the scene's, else 1e-10).  Other keywords go to the
    eigen-solver (``target``, ``nev``, ...).  scene_path: the file the scene was read from,
    when the caller read it (the scene's ``source`` says the same; not used here).
    flutter: also decide flutter of steady sliding (:mod:`meicp.contact.flutter`; default the
    scene's ``[solver] flutter``, true); False leaves ``result.flutter`` None, so ``stable``
    cannot be True.  flutter_dense_max: retained DOFs up to which flutter takes the dense path
    (None: ``limits.FLUTTER_DENSE_MAX``).  Collective on ``comm``.
    """
    t_start = time.perf_counter()
    timings = {}
    if not isinstance(scene, Scene):
        raise ProblemError(f"scene must be a Scene, got {type(scene).__name__} "
                           "(meicp.analyze also reads a scene file)")
    lam_min, tol = _check_options(scene, method or scene.solver.method, method is not None, lam_min, tol,
                                  solver_options)
    flutter = flutter_asked(scene, flutter)
    dense = {} if flutter_dense_max is None else {"dense_max": _check_dense_max(flutter_dense_max)}
    comm = mpi_comm(comm)
    memory, where = available_memory_on(comm)
    check_size(scene, memory=memory, index_max=index_max(), ranks=comm_size(comm), where=where)
    model = LatticeModel(scene)
    if not has_contact(scene):  # no friction: no instability to decide, its vibration modes instead
        refuse(scene, "the modal analysis of a scene without contact")
        return modal_analysis(scene, model, comm, nev=solver_options.get("nev"),
                              options=solver_options.get("options"))
    result = InstabilityResult(damping=DampingUsed.of(scene))
    # the lattice, assembled once and read by every step below; PETSc (row bands) when
    # distributed, else SciPy (serial: the static equilibrium assembles it, reading it first)
    with LatticeMatrices(model, comm) as lattice:
        # -- states -----------------------------------------------------------------------
        t0 = time.perf_counter()
        with stage("static"):
            lines, static = contact_states(scene, lattice)
        if static is not None:
            timings["static"] = time.perf_counter() - t0
            result.static = static
            if lines is None:
                result.status, result.message = static.status, f"static equilibrium failed: {static.message}"
                result.timings = timings
                return result
        # -- lattice: after the static equilibrium, which on several ranks reads its own
        # serial copy (the distributed K, M would only add to its peak) ---------------------
        t0 = time.perf_counter()
        with stage("assemble"):
            lattice.assemble()
        timings["assemble"] = time.perf_counter() - t0
        log.info("assembled K, M: %d DOFs (%.2f s)", model.n_dofs, timings["assemble"])
        result.states = state_names(next((line.states for line in lines if line.name == BASE), ()))
        result.interface_states = {line.name: state_names(line.states) for line in lines if line.name != BASE}
        # -- one MEiCP per grazing case ---------------------------------------------------
        method = method or scene.solver.method
        verdicts, sliding = [], None
        n_grazing = sum(s is ContactState.GRAZING for line in lines for s in line.states)
        progress = Progress("grazing cases", total=3 ** n_grazing, unit="MEiCPs")
        for k, case in enumerate(grazing_cases(lines)):
            progress.update(k, detail=f"{sum(len(v.modes) for v in verdicts)} mode(s) so far")
            t0 = time.perf_counter()
            with stage("reduce"):
                pen = pencil_of(lattice, lines, case, static)
            with pen:
                red = pen.maps
                timings["reduce"] = timings.get("reduce", 0.0) + time.perf_counter() - t0
                result.sizes = {"dofs": model.n_dofs, "retained": int(red.retained.size),
                                "complementarity": int(red.J.size)}
                log.info("MEiCP: %d retained DOFs, %d complementarity pairs%s", red.retained.size, red.J.size,
                         f", grazing case {tuple((s, i, c.value) for s, i, c in case)}" if case else "")
                if red.retained.size == 0:
                    verdicts.append(all_held())
                    continue
                t0 = time.perf_counter()
                with stage("eigen"):
                    verdict = (damped_divergence(pen, scene, comm, method, lam_min, tol, solver_options) if pen.damped
                               else divergence_of(pen, scene, comm, method, lam_min, tol, solver_options))
                timings["eigen"] = timings.get("eigen", 0.0) + time.perf_counter() - t0
                if flutter and not n_grazing:  # steady sliding of this very pencil (docs/flutter.md)
                    with stage("flutter"):
                        sliding = analyze_flutter(lattice, lines, scene, pencil=pen, static=static, **dense,
                                                  options=dict(scene.petsc), real_bound=verdict.real_part_bound())
            verdicts.append(verdict)
        if flutter and sliding is None:  # grazing branches (or nothing retained): their own pencils
            with stage("flutter"):
                sliding = analyze_flutter(lattice, lines, scene, static=static, options=dict(scene.petsc), **dense)
    result.modes = sorted((m for v in verdicts for m in v.modes), key=lambda m: -m.sigma)
    result.eicp = [v.eicp for v in verdicts]
    result.proofs = [v.proof for v in verdicts]
    stable_flags = [v.stable for v in verdicts]
    if any(s is False for s in stable_flags):  # a mode with σ ≥ 0, listed or not (lam_min)
        result.divergence = True
    elif all(s is True for s in stable_flags):
        result.divergence = False
    else:
        result.divergence = None
    result.evidence = " | ".join(v.evidence for v in verdicts)
    sliding = sliding or not_analysed("flutter = false")
    result.flutter, result.flutter_modes, result.flutter_evidence = sliding.flutter, sliding.modes, sliding.evidence
    result.flutter_growth = sliding.growth
    result.compose_verdict()
    # the question is answered once `stable` is decided: a certified flutter mode proves
    # instability even when the divergence search failed, so that failure leaves divergence
    # undecided (its evidence and `divergence_failure` say why) but is no failure of the run
    why = result.divergence_failure
    result.status = "inconclusive" if result.stable is None and why is not None else "solved"
    result.message = why or ""
    timings["flutter"] = sliding.seconds
    timings["total"] = time.perf_counter() - t_start
    result.timings = timings
    return result


def _check_options(scene: Scene, method, from_call: bool, lam_min, tol, options: dict) -> tuple[float, float]:
    """``(lam_min, tol)`` from the arguments or the scene, checked: ProblemError naming the
    one that is wrong (also for a keyword ``analyze`` sets itself)."""
    if method is not None and method not in available_methods():
        raise ProblemError(f"{'method' if from_call else '[solver] method'} must be one of "
                           f"{', '.join(available_methods())}, got {method!r}")
    check_keywords("analyze", sorted(options, key=lambda k: k not in REFUSED_OPTIONS), SOLVER_OPTIONS,
                   REFUSED_OPTIONS)
    _check_solver_options(options)
    name = "lam_min" if lam_min is not None else "[solver] lam_min"
    lam_min = scene.solver.lam_min if lam_min is None else lam_min
    lam_min = 0.0 if lam_min is None else as_real(lam_min, name)
    if lam_min < 0:
        raise ProblemError(f"{name} must be ≥ 0, got {lam_min!r}: a mode with σ < 0 is an oscillation, "
                           "never a divergence mode")
    name = "tol" if tol is not None else "[solver] tol"
    tol = scene.solver.tol if tol is None else tol
    return lam_min, (1e-10 if tol is None else check_tol(tol, name))


def _check_solver_options(options: dict) -> None:
    """The values of the eigen-solver keywords, before any work: ProblemError naming the one
    that is wrong (None: the default)."""
    checks = {"nev": lambda v: as_int(v, "nev", minimum=1), "target": lambda v: as_real(v, "target"),
              "max_iter": lambda v: as_int(v, "max_iter", minimum=1),
              "max_j": lambda v: as_int(v, "max_j", minimum=0, maximum=limits.MAX_ENUMERATED)}
    for name, check in checks.items():
        if options.get(name) is not None:
            check(options[name])
    petsc = options.get("options")
    if petsc is not None and not (isinstance(petsc, Mapping) and all(isinstance(k, str) for k in petsc)):
        raise ProblemError(f"options must be a dict of PETSc options (name → value), got {petsc!r}"[:300])


def _check_dense_max(value) -> int:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or value < 0:
        raise ProblemError(f"flutter_dense_max must be a whole number ≥ 0 of retained DOFs, got {value!r}")
    return int(value)

