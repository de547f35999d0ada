"""A scene without contact: its lowest vibration modes (``meicp.analyze``'s modal analysis).

With no rigid base and no frictional interface there is no friction, hence no frictional
instability to decide; what such a lattice has is its vibration modes.  On the free DOFs
(every DOF not held by a Dirichlet boundary) ``K v = ω² M v``; with the pencil of
docs/design.md §7.2 without contact, ``A = −K_FF``, ``B = M_FF`` (:func:`pencil_of`), each
mode is an eigenpair ``A v = σ B v`` with ``σ = −ω²`` and is reported and written like any
mode: σ ≤ 0, frequency ω = √−σ, growth rate 0, empty support.

The verdict rests on the inertia of ``−K_FF`` (a MUMPS LDLᵀ, Sylvester's law): no
eigenvalue σ ≥ 0 proves K_FF positive definite, every motion oscillates (``stable =
True``); otherwise the lattice has motions of zero stiffness — rigid-body motions the
boundary does not hold, σ = 0, neither growing nor oscillating — and ``stable`` is None
with their count in the evidence.  The pairs come from SLEPc
(:func:`~meicp.petsc.eigen.solve_ghep`: shift-and-invert with a MUMPS Cholesky, options
under ``-meicp_ghep_``) with the shift at σ = 0 when K_FF is definite, else just above it
(every σ ≤ 0 lies below the shift, so the eigenvalues nearest it are the lowest
frequencies); every pair is certified on the pencil (:func:`~meicp.eicp.problem.certify_pair`,
J empty) and one that fails is not a mode.
"""

from __future__ import annotations

import logging
import time

import numpy as np

from ..core.errors import ConvergenceError
from ..core.matrix import is_petsc_mat, max_abs_entry
from ..eicp.problem import EiCPProblem, certify_pair
from ..lattice.model import LatticeModel
from ..petsc.assembly import LatticeMatrices
from ..petsc.eigen import solve_ghep
from ..petsc.inertia import nonnegative_count, rounding_margin
from ..petsc.mat import destroying, mat_from_scipy, vec_to_numpy
from ..petsc.stages import stage
from ..scene import Scene
from .problem import pencil_of
from .rayleigh import pencil_is_negative
from .result import InstabilityResult, Mode

log = logging.getLogger("meicp")

#: vibration modes computed when neither the caller nor the scene's ``[solver] nev`` says
MODAL_NEV = 6
#: with a singular K_FF (σ = 0 exactly) the shift sits this far above σ = 0, relative to
#: max|A| / max|B| (about the highest σ's size): closer, the zero modes' huge shift-inverted
#: eigenvalues (1/shift) drown the others in rounding — at 1e-10 the elastic modes of the
#: free 4-node cell failed their certificate by 1e-6
SHIFT = 1e-3


def has_contact(scene: Scene) -> bool:
    """Whether the scene has a rigid base or a frictional interface (else: modal analysis)."""
    return scene.boundary.bottom == "contact" or any(i.kind == "frictional" for i in scene.interfaces)


def modal_analysis(scene: Scene, model: LatticeModel, comm=None, *, nev: int | None = None,
                   tol: float | None = None, options: dict | None = None) -> InstabilityResult:
    """The ``nev`` lowest vibration modes of a scene without contact (module docstring).

    comm: None or an mpi4py communicator (collective).  nev: modes wanted (default the
    scene's ``[solver] nev``, else ``MODAL_NEV``; at most the free DOFs).  tol: certificate
    tolerance (default the scene's, else 1e-10).  options: PETSc options under
    ``-meicp_ghep_`` (default the scene's ``[petsc]`` table)."""
    t_start = time.perf_counter()
    timings: dict = {}
    result = InstabilityResult(analysis="modal")
    tol = tol or scene.solver.tol or 1e-10
    t0 = time.perf_counter()
    with stage("assemble"):
        lattice = LatticeMatrices(model, comm).assemble()
    timings["assemble"] = time.perf_counter() - t0
    with lattice:
        t0 = time.perf_counter()
        with stage("reduce"):
            pen = pencil_of(lattice, [])
        timings["reduce"] = time.perf_counter() - t0
    with pen:
        r = int(pen.maps.retained.size)
        result.sizes = {"dofs": model.n_dofs, "retained": r}
        if r == 0:
            result.stable, result.status = True, "solved"
            result.evidence = "no friction, hence no frictional instability; every DOF is held: nothing can move"
            result.timings = {**timings, "total": time.perf_counter() - t_start}
            return result
        want = min(nev or scene.solver.nev or MODAL_NEV, r)
        log.info("modal analysis: no contact; the %d lowest vibration modes of %d free DOFs (SLEPc)", want, r)
        t0 = time.perf_counter()
        with stage("eigen"):
            proof = pencil_is_negative(pen.A, pen.B)   # A = −K_FF, B = M_FF: symmetric
            # σ ≥ 0 within rounding: motions of zero stiffness (rigid-body motions)
            proved = proof is not None and proof.proved is True
            held_back = 0 if proved else nonnegative_count(pen.A, rounding_margin(r))
            modes, dropped = _modes(pen, want, tol, dict(scene.petsc) if options is None else options,
                                    singular=held_back > 0)
        timings["eigen"] = time.perf_counter() - t0
    result.modes = modes
    result.stable = True if proved else None
    computed = (f"the {len(modes)} lowest vibration modes by SLEPc (σ = −ω², certified)"
                + (f"; {dropped} eigenpair(s) failed the certificate and are left out" if dropped else ""))
    if proved:
        result.evidence = (f"no friction, hence no frictional instability; K is positive definite on the {r} free "
                           f"DOFs (LDLᵀ inertia of −K: no σ ≥ 0), so every motion oscillates; {computed}")
    else:
        result.evidence = (f"no friction, hence no frictional instability; but K has {held_back} eigenvalue(s) "
                           f"σ ≥ 0 on the {r} free DOFs (LDLᵀ inertia of −K): motions of zero stiffness "
                           f"(rigid-body motions the boundary does not hold), σ = 0, neither growing nor "
                           f"oscillating; {computed}")
    result.status = "solved" if modes else "certificate_failed"
    if not modes:
        result.message = f"none of the {dropped} eigenpairs SLEPc returned passed its certificate (tolerance {tol:.0e})"
    result.timings = {**timings, "total": time.perf_counter() - t_start}
    return result


def _modes(pen, nev: int, tol: float, options: dict, *, singular: bool) -> tuple[list, int]:
    """The certified vibration modes of the pencil (A = −K_FF, B = M_FF), lowest frequency
    first, in natural numbering; and how many pairs failed their certificate.  ``singular``:
    K_FF has zero-stiffness motions (the shift must then avoid σ = 0)."""
    A, B = pen.A, pen.B
    owned = not is_petsc_mat(A)
    Ap, Bp = (mat_from_scipy(None, A), mat_from_scipy(None, B)) if owned else (A, B)
    target = SHIFT * max_abs_entry(A) / max(max_abs_entry(B), 1e-300) if singular else 0.0
    problem = EiCPProblem.from_data(A, B, J=np.zeros(0, dtype=np.int64))
    scales = problem.scales()
    modes, dropped = [], 0
    try:
        try:
            pairs = solve_ghep(Ap, Bp, nev=nev, target=target, options=options)
        except ConvergenceError as exc:
            pairs = exc.result
            log.warning("modal analysis: %s", exc)
        with destroying(*pairs.vectors):
            for sigma, vec in zip(pairs.values, pairs.vectors):
                sol = certify_pair(problem, float(sigma), vec_to_numpy(vec), scales)
                if sol.residual > tol:
                    dropped += 1
                    continue
                u = pen.maps.Q @ sol.x
                u /= np.linalg.norm(u)
                modes.append(Mode(float(sigma), u, np.zeros(0, dtype=np.int64), float(sol.residual)))
    finally:
        if owned:
            Ap.destroy()
            Bp.destroy()
    modes.sort(key=lambda m: -m.sigma)
    return modes, dropped
