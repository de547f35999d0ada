"""The instability analysis end to end (seed 000 §III, docs/design.md §7–§8): ``meicp.analyze``.

1. Lattice: K and M (distributed when ``comm`` has several ranks).
2. Contact states: prescribed by the scene, or from the static frictional equilibrium
   (:func:`meicp.contact.static.static_equilibrium`) when a contact set says ``"solve"``.
3. For each assignment of the grazing contacts' tangential cases: the pencil
   ``A = −P̃ K Q̃``, ``B = P̃ M Q̃`` (:mod:`meicp.contact.problem`) and the MEiCP
   ``(σB − A)x = w`` solved for σ ≥ 0: by support enumeration when the reduced problem is
   small (every divergence mode; an empty list proves stability), else by the SLEPc
   active-set search (one mode; no mode proves nothing unless the pencil is symmetric and
   its largest eigenvalue is negative: the Rayleigh-quotient bound, by LDLᵀ inertia).
4. Modes back in natural numbering: ``u = Q̃ x``.

A scene without contact has no frictional instability to decide: it gets a modal analysis
instead, its lowest vibration modes (:mod:`meicp.contact.modal`).  Each phase runs in its
PETSc log stage (``-log_view``: static, assemble, reduce, eigen).

The verdict logic lives here; the PETSc side (distributed pencil, inertia) in
:mod:`meicp.petsc`.  The critical friction is :mod:`meicp.contact.critical_friction`.
"""

from __future__ import annotations

import logging
import time

import numpy as np

from ..core.errors import ProblemError
from ..core.progress import Progress
from ..eicp.problem import lam_floor
from ..eicp.solve import solve_eicp
from ..lattice.model import LatticeModel
from ..petsc.assembly import assemble
from ..petsc.comm import mpi_comm
from ..petsc.inertia import eigenvalues_at_or_above
from ..petsc.mat import destroying, max_abs_entry
from ..petsc.stages import stage
from ..scene import Scene
from .maps import grazing_cases
from .modal import has_contact, modal_analysis
from .problem import Pencil, contact_states, pencil_of
from .result import InstabilityResult, Mode

log = logging.getLogger("meicp")

#: reduced problems are enumerated when 2^|J| dense eigen-solves of size r cost at most
#: about this many flops (2^|J|·r³), with r ≤ ENUMERATE_N and |J| ≤ ENUMERATE_J
ENUMERATE_FLOPS = 2e9
ENUMERATE_N = 600
ENUMERATE_J = 16


def enumeration_is_small(r: int, n_j: int) -> bool:
    """Whether 2^|J| dense eigen-solves of size r are within the enumeration budget
    (``analyze``'s ``auto`` choice, and ``critical_friction``'s bisection check)."""
    return r <= ENUMERATE_N and n_j <= ENUMERATE_J and 2.0 ** n_j * r ** 3 <= ENUMERATE_FLOPS


def analyze(scene: Scene, comm=None, *, method: str | None = None, scene_path=None,
            **solver_options) -> InstabilityResult:
    """Divergence modes of a scene's contact equilibrium (see the module docstring).

    scene: a :class:`~meicp.scene.Scene` (:func:`meicp.analyze` also reads a scene file).
    comm: an mpi4py communicator (None: serial SciPy/PETSc on one process).  method:
    ``enumerate`` | ``active-set`` | None (the scene's ``[solver] method``, ``auto`` = by
    size).  scene_path: the file the scene was read from, when the caller read it (the
    scene's ``source`` says the same; not used here).  Collective on ``comm``.
    """
    t_start = time.perf_counter()
    timings = {}
    if not isinstance(scene, Scene):
        raise ProblemError(f"scene must be a Scene, got {type(scene).__name__} "
                           "(meicp.analyze also reads a scene file)")
    comm = mpi_comm(comm)
    model = LatticeModel(scene)
    if not has_contact(scene):  # no friction: no instability to decide, its vibration modes instead
        return modal_analysis(scene, model, comm, nev=solver_options.get("nev"),
                              options=solver_options.get("options"))
    result = InstabilityResult()
    # -- states ---------------------------------------------------------------------------
    t0 = time.perf_counter()
    with stage("static"):
        sets, static = contact_states(scene, model, comm)
    if static is not None:
        timings["static"] = time.perf_counter() - t0
        result.static = static
        if sets is None:
            result.status, result.message = static.status, f"static equilibrium failed: {static.message}"
            result.timings = timings
            return result
    result.states = list(next((cs.states for cs in sets if cs.name == "base"), ()))
    result.interface_states = {cs.name: list(cs.states) for cs in sets if cs.name != "base"}
    # -- lattice --------------------------------------------------------------------------
    t0 = time.perf_counter()
    with stage("assemble"):
        K, M = assemble(model, comm)  # PETSc (row bands) when distributed, else SciPy
    timings["assemble"] = time.perf_counter() - t0
    log.info("assembled K, M: %d DOFs (%.2f s)", model.n_dofs, timings["assemble"])
    # -- one MEiCP per grazing case -------------------------------------------------------
    method = method or scene.solver.method
    modes, evidences, stable_flags, eicps = [], [], [], []
    n_grazing = sum(s == "grazing" for cs in sets for s in cs.states)
    progress = Progress("grazing cases", total=3 ** n_grazing, unit="MEiCPs")
    with destroying(K, M):
        for k, case in enumerate(grazing_cases(sets)):
            progress.update(k, detail=f"{len(modes)} mode(s) so far")
            t0 = time.perf_counter()
            with stage("reduce"):
                pen = pencil_of(K, M, model, sets, case, static)
            with pen:
                red = pen.maps
                timings["reduce"] = timings.get("reduce", 0.0) + time.perf_counter() - t0
                result.sizes = {"dofs": model.n_dofs, "retained": int(red.retained.size),
                                "complementarity": int(red.J.size)}
                log.info("MEiCP: %d retained DOFs, %d complementarity pairs%s", red.retained.size, red.J.size,
                         f", grazing case {case}" if case else "")
                if red.retained.size == 0:
                    evidences.append("every DOF is held (fixed or sticking): no mode can exist")
                    stable_flags.append(True)
                    eicps.append(None)
                    continue
                t0 = time.perf_counter()
                with stage("eigen"):
                    modes_c, evidence, stable, eicp = _solve_meicp(pen, scene, comm, method, solver_options)
                timings["eigen"] = timings.get("eigen", 0.0) + time.perf_counter() - t0
            modes += modes_c
            evidences.append(evidence)
            stable_flags.append(stable)
            eicps.append(eicp)
    modes.sort(key=lambda m: -m.sigma)
    result.modes = modes
    result.eicp = eicps
    if modes:
        result.stable = False
    elif all(s is True for s in stable_flags):
        result.stable = True
    else:
        result.stable = None
    result.evidence = " | ".join(evidences)
    failed = [e for e in eicps if e is not None and not e.success and e.status not in ("no_solution",)]
    if result.stable is None and failed:
        result.status = "inconclusive"
        result.message = failed[0].message
    else:
        result.status = "solved"
    timings["total"] = time.perf_counter() - t_start
    result.timings = timings
    return result


def _solve_meicp(pen: Pencil, scene: Scene, comm, method, options):
    """The MEiCP of one pencil: its certified modes, the evidence sentence, the verdict
    (True proved stable, False a mode, None undecided) and the raw EiCP result."""
    A, B, red = pen.A, pen.B, pen.maps
    solver = scene.solver
    lam_min = 0.0 if solver.lam_min is None else solver.lam_min
    tol = solver.tol or 1e-10
    small = enumeration_is_small(red.retained.size, red.J.size)
    chosen = method if method not in (None, "auto") else ("enumerate" if small else "active-set")
    kwargs = dict(options)
    if chosen == "active-set":
        kwargs.setdefault("nev", solver.nev or 4)
        kwargs.setdefault("target", 0.0)
        kwargs.setdefault("options", dict(scene.petsc))
        if solver.max_iterations:
            kwargs.setdefault("max_iter", solver.max_iterations)
    eicp = solve_eicp(A, B, J=red.J, method=chosen, lam_min=lam_min, tol=tol, comm=comm, **kwargs)
    # a σ below lam_min (even by 5e-11 just below μ_c) is not a divergence mode, but an exact
    # σ = lam_min computed a few ulps below it is (eicp.problem.lam_floor)
    floor = lam_floor(lam_min, (max_abs_entry(A), max_abs_entry(B)))
    modes = [_mode(sol, red) for sol in eicp.solutions if sol.lam >= floor]
    if chosen == "enumerate":
        cover = eicp.coverage.get("supports", 0)
        if modes:
            return modes, f"enumeration of all {cover} supports: {len(modes)} divergence mode(s) with σ ≥ {lam_min}", False, eicp
        return [], f"enumeration of all {cover} supports: no solution with σ ≥ {lam_min} (a proof)", True, eicp
    if modes:
        return modes, f"active-set search: a certified divergence mode after {eicp.coverage.get('eigen_solves')} eigen-solves", False, eicp
    # no mode found: a proof only for a symmetric pencil, through the Rayleigh bound
    if eigenvalues_at_or_above(A, B, lam_min) == 0:
        return [], (f"symmetric pencil with no eigenvalue ≥ {lam_min} (inertia of A − {lam_min}·B by an "
                    f"LDLᵀ factorisation): every MEiCP solution is a Rayleigh quotient of the pencil, so "
                    f"none has σ ≥ {lam_min} (a proof)"), True, eicp
    return [], (f"active-set search found no mode with σ ≥ {lam_min} ({eicp.status}); this is not a proof of "
                "stability"), None, eicp


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
