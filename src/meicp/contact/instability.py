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
The mass plays no role at σ = 0, and the rows E where w must vanish and B′ is zero (every
non-complementarity row: B′ has only slip rows, which are in J) do not involve μ, so x_E is
eliminated exactly, ``x_E = −A′_EE⁻¹ A′_EC x_C`` (C = the rest: J, plus any free row that
carries μ), by one sparse LU of the μ-independent block; the condensed EiCP of order |C|
(``Ac = A′_CC − A′_CE A′_EE⁻¹ A′_EC``, likewise ``Bc``) is enumerated in ν = 1/μ,
``(ν(−Ac) − (−Bc)) x_C = ν y_C``: the pencil's second matrix ``−Ac`` is the Schur
complement of ``−A′ = Q̃ᵀKQ̃``, positive definite unless a motion of zero stiffness exists
(see ``critical_friction`` for that case), so its principal blocks are well conditioned,
whereas ``Bc`` is typically nearly singular.  2^|J| solves of order ≤ |J| instead of
order r: 254× faster at |J| = 9, r = 135 (docs/benchmarks.md, resolution section).
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
#: critical_friction enumerates the 2^|J| supports of its EiCP condensed onto the |J|
#: complementarity DOFs (order ≤ |J|): 3.3 s at |J| = 17, 15 s at |J| = 19 (about ×2.2 per pair)
CRITICAL_J = 20
#: the μ-independent block −A′ (and its Schur complement) counts as singular beyond this
#: condition number: a motion of (near) zero stiffness, μ_c undefined
CRITICAL_COND = 1e12


def _enumeration_is_small(r: int, n_j: int) -> bool:
    """Whether 2^|J| dense eigen-solves of size r are within the enumeration budget
    (``analyze``'s ``auto`` choice, and ``critical_friction``'s bisection check)."""
    return r <= ENUMERATE_N and n_j <= ENUMERATE_J and 2.0 ** n_j * r ** 3 <= ENUMERATE_FLOPS


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
    from ..core.operators import max_abs_entry
    from ..eicp.problem import lam_floor
    from ..eicp.solve import solve_eicp

    solver = scene.solver
    lam_min = 0.0 if solver.lam_min is None else solver.lam_min
    tol = solver.tol or 1e-10
    r = A.getSize()[0] if hasattr(A, "getSize") else A.shape[0]
    small = _enumeration_is_small(r, red.J.size)
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
    # a σ below lam_min (even by 5e-11 just below μ_c) is not a divergence mode, but an exact
    # σ = lam_min computed a few ulps below it is (eicp.problem.lam_floor)
    floor = lam_floor(lam_min, (max_abs_entry(A), max_abs_entry(B)))
    modes = [_mode(sol, red, sets) for sol in eicp.solutions if sol.lam >= floor]
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


def critical_friction(scene, *, mu_max: float = 1e3, bisection: bool | None = None, tol: float = 1e-8,
                      condense: bool = True) -> float:
    """The smallest μ ≥ 0 at which a σ = 0 divergence mode exists for the scene's states
    (prescribed ones; with ``"solve"`` the states of the static equilibrium at the scene's μ),
    one μ for every frictional contact.  ``inf`` when there is none up to ``mu_max``.

    Solved as an EiCP in μ, condensed onto its complementarity DOFs (see the module
    docstring) and enumerated: all 2^|J| supports of order ≤ |J|, a proof of the smallest μ,
    for |J| ≤ ``CRITICAL_J`` (20) complementarity pairs per grazing case (ProblemError
    beyond); the μ_c found is lifted back to the whole reduced lattice and certified there.
    ``condense=False``: the former enumeration of the whole reduced pencil (order r per
    support, at most 16 pairs and 600 reduced DOFs; slow, kept for cross-checks).

    A motion of zero stiffness once the slip DOFs are eliminated — a floating body, or a
    block free to slide as a whole — makes the μ-independent block singular.  If such a
    motion is compatible with the slip directions (x_J ≥ 0) it is a σ = 0 motion at every μ
    and μ_c is undefined: ProblemError.  If it is not (e.g. a layer between two sliding
    contacts slipping in opposite directions), the enumeration meets singular pencils on
    some supports, so the bisection check is then required (ProblemError if it is too large
    for the default ``bisection=None``; a warning if ``bisection=False``).

    ``bisection``: cross-check on the σ-problem with the mass (a σ ≥ 0 mode must exist just
    above μ_c and none just below, each decided by enumerating the whole reduced pencil;
    ConvergenceError if they disagree).  ``None`` (default): run it when that enumeration is
    within ``analyze``'s budget for enumerating (2^|J|·r³ ≤ 2e9 flops, about ≤ 9 pairs on
    ~150 reduced DOFs), skip it beyond; ``True``: always; ``False``: never.  Serial.
    """
    scene, model, sets = _friction_states(scene)
    K, _ = assemble(model)
    best = np.inf
    small, singular = True, False
    for case in grazing_cases(sets):
        red = reduced_system(model, sets, case)
        # every case counts: the bisection check enumerates the σ-problem of each, with or without J
        small = small and _enumeration_is_small(red.retained.size, red.J.size)
        if red.J.size == 0:
            continue
        A1, B1 = _friction_pencil(K, red, sets)
        if condense:
            mu, sing = _smallest_mu_condensed(A1, B1, red.J, mu_max)
            singular = singular or sing
        else:
            mu = _smallest_mu_full(A1, B1, red.J, mu_max)
        best = min(best, mu)
    if singular and bisection is None and not small:
        raise ProblemError("critical_friction: a motion of zero stiffness is left once the slip DOFs are "
                           "eliminated (not compatible with the slip directions), so the enumeration meets "
                           "singular pencils and needs the bisection check, but the σ-problem is too large to "
                           "enumerate; pass bisection=True to run it anyway, or hold the body")
    if bisection or (bisection is None and small):
        _check_by_bisection(scene, sets, model, best, mu_max, tol)
    elif singular:
        log.warning("critical_friction: singular μ-independent block and bisection=False: μ_c = %.10g is "
                    "certified but its minimality is not cross-checked", best)
    elif bisection is None:
        log.info("critical_friction: bisection check skipped (the σ-problem is too large to enumerate)")
    return float(best)


def friction_pencils(scene):
    """The σ = 0 EiCPs in μ of :func:`critical_friction`, condensed onto the
    complementarity DOFs: one ``(Ac, Bc, J)`` per grazing case with a complementarity pair,
    for ``(μ Bc − Ac) x = y`` (dense, order |J|).  Raises ProblemError if the μ-independent
    block is singular.  Serial."""
    scene, model, sets = _friction_states(scene)
    K, _ = assemble(model)
    out = []
    for case in grazing_cases(sets):
        red = reduced_system(model, sets, case)
        if red.J.size == 0:
            continue
        Ac, Bc, Jc, _, null = _condense(*_friction_pencil(K, red, sets), red.J)
        if null.shape[1]:
            raise ProblemError(_singular_message(f"the condensed block −Ac (order {Ac.shape[0]}) is singular"))
        out.append((Ac, Bc, Jc))
    return out


def _friction_states(scene):
    """(scene, model, contact sets) with the states resolved (static equilibrium if asked)."""
    from ..core.errors import ConvergenceError
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
    return scene, model, contact_sets(scene, model, override)


def _friction_pencil(K, red, sets):
    """``A′ = −P̃₀ K Q̃``, ``B′ = P̃₁ K Q̃`` (sparse CSR) of the σ = 0 EiCP in μ."""
    P0 = (red.P - _friction_part(red, sets)).tocsr()
    return -(P0 @ K @ red.Q).tocsr(), (red.P_friction @ K @ red.Q).tocsr()


def _smallest_mu_full(A1, B1, J, mu_max):
    """The former path: enumerate the EiCP in μ on the whole reduced lattice."""
    from ..eicp.solve import solve_eicp

    if A1.shape[0] > ENUMERATE_N or J.size > ENUMERATE_J:
        raise ProblemError(f"critical_friction(condense=False) enumerates the whole reduced lattice: reduced size "
                           f"{A1.shape[0]} (limit {ENUMERATE_N}) / |J| = {J.size} (limit {ENUMERATE_J}) too large")
    r = solve_eicp(A1.toarray(), B1.toarray(), J=J, method="enumerate", lam_min=0.0, tol=1e-9)
    mus = [s.lam for s in r.solutions if 0.0 <= s.lam <= mu_max]
    return min(mus) if mus else np.inf


def _condense(A1, B1, J):
    """Eliminate the rows/columns E where w = 0 and B′ = 0 (no μ in the equation):
    ``x_E = −A′_EE⁻¹ A′_EC x_C``.  Returns ``(Ac, Bc, Jc, lift, null)``: Jc the positions of
    J in C, ``lift(x_C)`` the whole reduced x, ``null`` an orthonormal basis (columns) of the
    null space of −Ac (usually empty).  ProblemError if ``−A′_EE`` is singular: then a
    motion with x_C = 0 costs no energy, a σ = 0 motion at every μ."""
    import scipy.sparse.linalg as spl

    r = A1.shape[0]
    in_j = np.zeros(r, dtype=bool)
    in_j[J] = True
    with_mu = np.diff(B1.indptr) > 0           # rows of B′ with a stored entry
    keep = in_j | with_mu                       # C: J and any free row that carries μ
    C, E = np.flatnonzero(keep), np.flatnonzero(~keep)
    Jc = np.flatnonzero(in_j[C])
    A_CC, B_CC = A1[C][:, C].toarray(), B1[C][:, C].toarray()
    if E.size:
        A_EE = A1[E][:, E].tocsc()
        singular = f"the μ-independent block −A′_EE ({E.size} DOFs) is singular"
        try:
            lu = spl.splu(A_EE)
        except RuntimeError as exc:  # "Factor is exactly singular"
            raise ProblemError(_singular_message(singular)) from exc
        inv = spl.LinearOperator(A_EE.shape, matvec=lu.solve, rmatvec=lambda v: lu.solve(v, trans="T"),
                                 dtype=float)
        cond = spl.norm(A_EE, 1) * spl.onenormest(inv)
        if not np.isfinite(cond) or cond > CRITICAL_COND:
            raise ProblemError(_singular_message(f"{singular} (condition ≈ {cond:.1e})"))
        X_EC = lu.solve(A1[E][:, C].toarray())  # A′_EE⁻¹ A′_EC
        Ac = A_CC - A1[C][:, E] @ X_EC
        Bc = B_CC - B1[C][:, E] @ X_EC
    else:
        X_EC = np.zeros((0, C.size))
        Ac, Bc = A_CC, B_CC
    Ac, Bc = np.asarray(Ac), np.asarray(Bc)
    # −Ac is the Schur complement of −A′ = Q̃ᵀKQ̃: symmetric positive semidefinite, definite
    # unless a motion of zero stiffness is left (e.g. a layer sliding as a whole)
    ev, V = np.linalg.eigh(-0.5 * (Ac + Ac.T))
    null = V[:, ev <= max(ev[-1], 0.0) / CRITICAL_COND]

    def lift(xc):
        x = np.zeros(r)
        x[C] = xc
        x[E] = -X_EC @ xc
        return x

    return Ac, Bc, Jc, lift, null


def _singular_message(what: str) -> str:
    return (f"critical_friction: {what}: a motion of zero stiffness exists with the sliding contacts "
            "held (a floating body, or a block free to slide as a whole), a σ = 0 motion at every μ; "
            "μ_c is undefined — hold the body (boundary or sticking contacts)")


def _sign_feasible(N: np.ndarray) -> bool:
    """Whether some nonzero x = N c has x ≥ 0 (LP: N c ≥ 0, Σ(N c) = 1), or x = 0 on these
    rows for some c ≠ 0 (N rank deficient)."""
    from scipy.optimize import linprog

    if np.linalg.matrix_rank(N) < N.shape[1]:
        return True
    res = linprog(np.zeros(N.shape[1]), A_ub=-N, b_ub=np.zeros(N.shape[0]), A_eq=N.sum(axis=0)[None, :],
                  b_eq=[1.0], bounds=[(None, None)] * N.shape[1], method="highs")
    return res.status == 0


def _smallest_mu_condensed(A1, B1, J, mu_max):
    """Smallest μ in [0, mu_max] of ``(μB′ − A′)x = y`` by enumerating the condensed EiCP
    in ν = 1/μ, certified on the whole reduced pencil.  Returns (μ, singular): ``singular``
    when −Ac has a null space that is not sign-feasible (the enumeration met singular
    pencils; the caller must cross-check)."""
    from ..core.errors import ConvergenceError
    from ..eicp.problem import EiCPProblem, certify_pair
    from ..eicp.solve import solve_eicp

    if J.size > CRITICAL_J:
        raise ProblemError(f"critical_friction enumerates all 2^|J| supports of the EiCP condensed onto the "
                           f"contact DOFs: |J| = {J.size} complementarity pairs (slipping or grazing contacts) "
                           f"exceeds the limit CRITICAL_J = {CRITICAL_J}")
    Ac, Bc, Jc, lift, null = _condense(A1, B1, J)
    if null.shape[1] and _sign_feasible(null[Jc]):
        raise ProblemError(_singular_message(f"the condensed block −Ac (order {Ac.shape[0]}) is singular and its "
                                             "null space holds a motion with x_J ≥ 0"))
    if Ac.shape[0] > Jc.size:
        log.info("critical_friction: %d free rows carry μ and stay in the condensed EiCP", Ac.shape[0] - Jc.size)
    # μ > 0 ⇔ ν = 1/μ > 0.  μ = 0 is never a solution: −Ac is positive semidefinite and
    # x_J ≥ 0 with xᵀ(−Ac)x = xᵀy = 0 only for x in its null space, excluded just above
    r = solve_eicp(-Bc, -Ac, J=Jc, method="enumerate", lam_min=1.0 / mu_max if mu_max > 0 else np.inf,
                   tol=1e-9)
    nus = [s for s in r.solutions if s.lam > 0 and 1.0 / s.lam <= mu_max]
    if not nus:
        return np.inf, bool(null.shape[1])
    sol = max(nus, key=lambda s: s.lam)
    mu = 1.0 / sol.lam
    full = certify_pair(EiCPProblem.from_data(A1, B1, J), mu, lift(sol.x))
    if full.residual > 1e-9:
        raise ConvergenceError(f"critical_friction: μ_c = {mu:.10g} of the condensed EiCP fails the certificate on "
                               f"the whole reduced lattice (residual {full.residual:.1e})", r)
    return mu, bool(null.shape[1])


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
        if red.retained.size == 0:
            continue  # every DOF held: no mode (as in analyze)
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
