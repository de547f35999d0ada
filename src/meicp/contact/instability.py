"""The instability analysis end to end (seed 000 §III, DESIGN §4): ``meicp.analyze``.

1. Lattice: K and M (distributed when ``comm`` has several ranks).
2. Contact states: prescribed by the scene, or from the static frictional equilibrium
   (:func:`meicp.contact.static.static_equilibrium`) when a contact set says ``"solve"``.
3. For each assignment of the grazing contacts' tangential cases: the maps Q̃, P̃
   (:mod:`meicp.contact.maps`), the pencil ``A = −P̃ K Q̃``, ``B = P̃ M Q̃`` and the MEiCP
   ``(σB − A)x = w`` solved for σ ≥ 0: by support enumeration when the reduced problem is
   small (every divergence mode; an empty list proves stability), else by the SLEPc
   active-set search (one mode; no mode proves nothing unless the pencil is symmetric and
   its largest eigenvalue is negative: the Rayleigh-quotient bound).
4. Modes back in natural numbering: ``u = Q̃ x``.

``critical_friction``: the smallest μ ≥ 0 at which a σ = 0 mode exists, with μ as the
eigenvalue: at σ = 0, ``P̃(μ) K Q̃ x = y`` with ``P̃(μ) = P̃₀ + μ P̃₁`` is the EiCP
``(μ B′ − A′) x = y`` for ``A′ = −P̃₀ K Q̃``, ``B′ = P̃₁ K Q̃`` (B′ singular: only slip rows).
"""

from __future__ import annotations

import logging
import time

import numpy as np
import scipy.sparse as sp

from ..core.errors import ProblemError
from ..lattice.assembly import assemble
from ..lattice.model import LatticeModel
from .maps import contact_sets, grazing_cases, reduced_system
from .result import InstabilityResult, Mode

log = logging.getLogger("meicp")

#: reduced problems are enumerated when 2^|J| dense eigen-solves of size r cost at most
#: about this many flops (2^|J|·r³), with r ≤ ENUMERATE_N and |J| ≤ ENUMERATE_J
ENUMERATE_FLOPS = 2e9
ENUMERATE_N = 600
ENUMERATE_J = 16


def _needs_static(scene) -> bool:
    from ..io.scene import SOLVE

    if scene.contact is not None and scene.contact.states == SOLVE:
        return True
    return any(i.kind == "frictional" and i.states in (SOLVE, None) for i in scene.interfaces)


def _size(comm) -> int:
    return 1 if comm is None else comm.Get_size()


def analyze(scene, comm=None, *, method: str | None = None, scene_path=None, **solver_options) -> InstabilityResult:
    """Divergence modes of a scene's contact equilibrium (see the module docstring).

    scene: a :class:`~meicp.io.scene.Scene` or a path.  comm: an mpi4py communicator (None:
    serial SciPy/PETSc on one process).  method: ``enumerate`` | ``active-set`` | None
    (the scene's ``[solver] method``, ``auto`` = by size).  Collective on ``comm``.
    """
    from ..io.scene import Scene, load_scene

    t_start = time.perf_counter()
    timings = {}
    if not isinstance(scene, Scene):
        scene_path = scene_path or scene
        scene = load_scene(scene)
    model = LatticeModel(scene)
    if model.boundary.bottom != "contact" and not any(i.kind == "frictional" for i in scene.interfaces):
        raise ProblemError("the scene has no contact: set boundary.bottom = \"contact\" or a frictional interface")
    result = InstabilityResult()
    # -- states ---------------------------------------------------------------------------
    override = None
    if _needs_static(scene):
        from .static import static_equilibrium

        t0 = time.perf_counter()
        log.info("static equilibrium: frictional contact LCP")
        static = static_equilibrium(scene, model=model, comm=comm if _size(comm) > 1 else None)
        timings["static"] = time.perf_counter() - t0
        result.static = static
        if not static.success:
            result.status, result.message = static.status, f"static equilibrium failed: {static.message}"
            result.timings = timings
            return result
        override = {"base": static.states, **static.interface_states}
    sets = contact_sets(scene, model, override)
    result.states = list(next((cs.states for cs in sets if cs.name == "base"), ()))
    result.interface_states = {cs.name: list(cs.states) for cs in sets if cs.name != "base"}
    # -- lattice --------------------------------------------------------------------------
    t0 = time.perf_counter()
    distributed = _size(comm) > 1
    K, M = assemble(model, comm if distributed else None)  # PETSc (row bands) or SciPy
    timings["assemble"] = time.perf_counter() - t0
    log.info("assembled K, M: %d DOFs (%.2f s)", model.n_dofs, timings["assemble"])
    # -- one MEiCP per grazing case -------------------------------------------------------
    solver = scene.solver
    method = method or solver.method
    modes, evidences, stable_flags, eicps = [], [], [], []
    for case in grazing_cases(sets):
        t0 = time.perf_counter()
        red = reduced_system(model, sets, case)
        if red.retained.size and distributed:
            A, B = _distributed_pencil(K, M, red, comm)
        elif red.retained.size:
            A, B = -(red.P @ K @ red.Q).tocsr(), (red.P @ M @ red.Q).tocsr()
        timings["reduce"] = timings.get("reduce", 0.0) + time.perf_counter() - t0
        result.sizes = {"dofs": model.n_dofs, "retained": int(red.retained.size), "complementarity": int(red.J.size)}
        log.info("MEiCP: %d retained DOFs, %d complementarity pairs%s", red.retained.size, red.J.size,
                 f", grazing case {case}" if case else "")
        if red.retained.size == 0:
            evidences.append("every DOF is held (fixed or sticking): no mode can exist")
            stable_flags.append(True)
            eicps.append(None)
            continue
        t0 = time.perf_counter()
        try:
            modes_c, evidence, stable, eicp = _solve_meicp(A, B, red, model, sets, scene, comm, method,
                                                           solver_options)
        finally:
            if distributed:
                A.destroy()
                B.destroy()
        timings["eigen"] = timings.get("eigen", 0.0) + time.perf_counter() - t0
        modes += modes_c
        evidences.append(evidence)
        stable_flags.append(stable)
        eicps.append(eicp)
    if distributed:
        K.destroy()
        M.destroy()
    modes.sort(key=lambda m: -m.sigma)
    result.modes = modes
    result.eicp = eicps[0] if len(eicps) == 1 else eicps
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


def _solve_meicp(A, B, red, model, sets, scene, comm, method, options):
    from ..eicp.solve import solve_eicp

    solver = scene.solver
    lam_min = 0.0 if solver.lam_min is None else solver.lam_min
    tol = solver.tol or 1e-10
    r = A.getSize()[0] if hasattr(A, "getSize") else A.shape[0]
    small = r <= ENUMERATE_N and red.J.size <= ENUMERATE_J and 2.0 ** red.J.size * r ** 3 <= ENUMERATE_FLOPS
    chosen = method if method not in (None, "auto") else ("enumerate" if small else "active-set")
    kwargs = dict(options)
    if chosen == "active-set":
        kwargs.setdefault("nev", solver.nev or 4)
        kwargs.setdefault("target", 0.0)
        kwargs.setdefault("options", dict(scene.petsc))
        if solver.max_iterations:
            kwargs.setdefault("max_iter", solver.max_iterations)
    eicp = solve_eicp(A, B, J=red.J, method=chosen, lam_min=lam_min, tol=tol,
                      comm=comm if _size(comm) > 1 else None, **kwargs)
    # strict: a σ below lam_min (even by 5e-11 just below μ_c) is not a divergence mode
    modes = [_mode(sol, red, sets) for sol in eicp.solutions if sol.lam >= lam_min]
    if chosen == "enumerate":
        cover = eicp.coverage.get("supports", 0)
        if modes:
            return modes, f"enumeration of all {cover} supports: {len(modes)} divergence mode(s) with σ ≥ {lam_min}", False, eicp
        return [], f"enumeration of all {cover} supports: no solution with σ ≥ {lam_min} (a proof)", True, eicp
    if modes:
        return modes, f"active-set search: a certified divergence mode after {eicp.coverage.get('eigen_solves')} eigen-solves", False, eicp
    # no mode found: a proof only for a symmetric pencil, through the Rayleigh bound
    if _eigenvalues_at_or_above(A, B, lam_min) == 0:
        return [], (f"symmetric pencil with no eigenvalue ≥ {lam_min} (inertia of A − {lam_min}·B by an "
                    f"LDLᵀ factorisation): every MEiCP solution is a Rayleigh quotient of the pencil, so "
                    f"none has σ ≥ {lam_min} (a proof)"), True, eicp
    return [], (f"active-set search found no mode with σ ≥ {lam_min} ({eicp.status}); this is not a proof of "
                "stability"), None, eicp


def _eigenvalues_at_or_above(A, B, lam_min: float):
    """How many eigenvalues of the pencil are ≥ lam_min, when it is symmetric with B SPD
    (Sylvester's inertia of A − lam_min·B, MUMPS LDLᵀ); None for a nonsymmetric pencil."""
    from ..core.validation import is_symmetric
    from ..petsc.inertia import inertia
    from ..petsc.mat import mat_from_scipy

    if hasattr(A, "getSize"):
        a = max(abs(A.norm()), 1e-300)
        if not (A.isSymmetric(1e-12 * a) and B.isSymmetric(1e-12 * a)):
            return None
        C = A.duplicate(copy=True)
        C.axpy(-lam_min, B)
    else:
        if not (is_symmetric(A, 1e-12) and is_symmetric(B, 1e-12)):
            return None
        C = mat_from_scipy(None, (A - lam_min * B).tocsr())
    try:
        _, zero, positive = inertia(C)
    finally:
        C.destroy()
    return zero + positive


def _distributed_pencil(K, M, red, comm):
    """``A = −P̃KQ̃``, ``B = P̃MQ̃`` as PETSc matrices: Q̃ with K's row bands, the reduced
    DOFs owned by the rank of their node, two sparse products per matrix.  Collective."""
    from ..petsc.mat import mat_from_rows

    lo, hi = K.getOwnershipRange()
    r_lo, r_hi = np.searchsorted(red.retained, [lo, hi])
    n, r = K.getSize()[0], red.retained.size
    Q = mat_from_rows(comm, red.Q[lo:hi], (n, r), int(r_hi - r_lo))
    P = mat_from_rows(comm, red.P[r_lo:r_hi], (r, n), hi - lo)
    try:
        KQ, MQ = K.matMult(Q), M.matMult(Q)
        A, B = P.matMult(KQ), P.matMult(MQ)
        A.scale(-1.0)
        KQ.destroy()
        MQ.destroy()
    finally:
        Q.destroy()
        P.destroy()
    return A, B


def _mode(sol, red, sets) -> Mode:
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


def critical_friction(scene, *, mu_max: float = 1e3, bisection: bool = True, tol: float = 1e-8) -> float:
    """The smallest μ ≥ 0 at which a σ = 0 divergence mode exists for the scene's states
    (prescribed ones; with ``"solve"`` the states of the static equilibrium at the scene's μ),
    one μ for every frictional contact.  ``inf`` when there is none up to ``mu_max``.

    Solved as an EiCP in μ by enumeration (small problems), cross-checked by bisection on
    the existence of a σ ≥ 0 mode when ``bisection`` (raises ConvergenceError if the two
    disagree).  Serial.
    """
    from ..core.errors import ConvergenceError
    from ..eicp.solve import solve_eicp
    from ..io.scene import Scene, load_scene

    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    model = LatticeModel(scene)
    override = None
    if _needs_static(scene):
        from .static import static_equilibrium

        st = static_equilibrium(scene, model=model)
        if not st.success:
            raise ConvergenceError(f"static equilibrium failed: {st.message}", st)
        override = {"base": st.states, **st.interface_states}
    sets = contact_sets(scene, model, override)
    K, _ = assemble(model)
    best = np.inf
    for case in grazing_cases(sets):
        red = reduced_system(model, sets, case)
        if red.J.size == 0:
            continue
        P0 = (red.P - _friction_part(red, sets)).tocsr()
        A1 = -(P0 @ K @ red.Q).toarray()
        B1 = (red.P_friction @ K @ red.Q).toarray()
        if A1.shape[0] > ENUMERATE_N or red.J.size > ENUMERATE_J:
            raise ProblemError(f"critical_friction enumerates: reduced size {A1.shape[0]} / |J| = {red.J.size} too large")
        r = solve_eicp(A1, B1, J=red.J, method="enumerate", lam_min=0.0, tol=1e-9)
        mus = [s.lam for s in r.solutions if 0.0 <= s.lam <= mu_max]
        if mus:
            best = min(best, min(mus))
    if bisection:
        _check_by_bisection(scene, sets, model, best, mu_max, tol)
    return float(best)


def _friction_part(red, sets):
    """μ·P₁ with each contact's own μ (the part of P̃ proportional to friction)."""
    mus = np.zeros(red.P.shape[0])
    for k, (name, _, kind) in enumerate(red.pair_of):
        if kind == "t":
            mus[red.J[k]] = next(cs.friction for cs in sets if cs.name == name)
    return sp.diags(mus) @ red.P_friction


def _has_mode(scene, sets, model, mu) -> bool:
    """Whether a σ ≥ 0 mode exists with every contact's friction set to μ (enumeration)."""
    import dataclasses

    from ..eicp.solve import solve_eicp

    scaled = [dataclasses.replace(cs, friction=mu) for cs in sets]
    K, M = assemble(model)

    for case in grazing_cases(scaled):
        red = reduced_system(model, scaled, case)
        A = -(red.P @ K @ red.Q).toarray()
        B = (red.P @ M @ red.Q).toarray()
        r = solve_eicp(A, B, J=red.J, method="enumerate", lam_min=0.0)
        if r.solutions:
            return True
    return False


def _check_by_bisection(scene, sets, model, mu_c, mu_max, tol):
    """Existence of a σ ≥ 0 mode must switch on at μ_c: none just below, one at/above it."""
    from ..core.errors import ConvergenceError

    if np.isfinite(mu_c):
        below = mu_c * (1 - 1e-6) - 1e-12
        if below >= 0 and _has_mode(scene, sets, model, below):
            # bisect down to see where existence really starts
            lo, hi = 0.0, below
            if _has_mode(scene, sets, model, 0.0):
                raise ConvergenceError(f"a σ ≥ 0 mode exists at μ = 0 although μ as an eigenvalue gave {mu_c}")
            while hi - lo > tol * max(1.0, hi):
                mid = 0.5 * (lo + hi)
                lo, hi = (lo, mid) if _has_mode(scene, sets, model, mid) else (mid, hi)
            raise ConvergenceError(f"bisection finds modes from μ ≈ {hi:.8g}, below μ_c = {mu_c:.8g}")
        if not _has_mode(scene, sets, model, mu_c * (1 + 1e-6) + 1e-12):
            raise ConvergenceError(f"no σ ≥ 0 mode just above μ_c = {mu_c:.8g}: μ as an eigenvalue and "
                                   "existence disagree")
    elif _has_mode(scene, sets, model, mu_max):
        raise ConvergenceError(f"μ as an eigenvalue found no μ_c ≤ {mu_max}, but a mode exists at μ = {mu_max}")
