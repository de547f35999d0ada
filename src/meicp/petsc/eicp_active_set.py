"""Active-set search for an MEiCP solution on large sparse or distributed pencils.

An outer loop over supports ``S ⊆ J``; each step is one SLEPc solve of the reduced pencil
on ``R = F ∪ S`` (:class:`~meicp.petsc.reduced_pencil.ReducedPencilSolver`: zeroed rows and
columns, fixed pattern, reused symbolic factorisation, warm start).  From the wanted
eigenpair (λ, ξ) — by default the largest real λ among the ``nev`` eigenvalues nearest
the target, i.e. the fastest-growing mode of the instability problem; after the first
solve that pair alone is followed (``follow``) — the support is updated:

- ``ξ`` is oriented so that ``eᵀξ_S > 0``; indices of S with ``ξ_j < 0`` leave S;
- indices of ``J∖S`` whose dual ``w_j = ((λB − A)ξ)_j`` is negative enter S.

Both at once by default; a support seen before switches to single moves (the most
violated index only), and when those revisit too the search stops with status
``cycling``.  A pair with no violation is certified (:func:`certify_pair`) and returned.

What the search proves: a returned solution is a certified solution; a failure proves
nothing about existence — ``coverage`` lists the supports visited, and the message says so.
Collective on the matrices' communicator; SciPy input runs on ``COMM_SELF``.  Registered
as the method ``active-set`` of :func:`meicp.solve_eicp`.
"""

from __future__ import annotations

import time

import numpy as np

from ..core.errors import PetscOptionError, PetscSolveError
from ..core.matrix import is_symmetric
from ..core.progress import Progress
from ..eicp.problem import DEFAULT_TOL, EiCPProblem, EiCPResult, certify_pair, lam_floor
from ..eicp.scaling import normalised, restore, scaled_value
from ..eicp.solve import register
from .mat import mat_from_scipy
from .options import ACTIVE_SET, ARGUMENT_ERRORS
from .reduced_pencil import ReducedPencilSolver


def _petsc_pair(problem: EiCPProblem, comm):
    if problem.distributed:
        return problem.A, problem.B, False
    return mat_from_scipy(comm, problem.A), mat_from_scipy(comm, problem.B), True


def _is_symmetric(problem: EiCPProblem) -> bool:
    return is_symmetric(problem.A, 1e-13) and is_symmetric(problem.B, 1e-13)


def _spurious_value(problem: EiCPProblem, target: float) -> float:
    """A value far below every eigenvalue of the pencil: removed DOFs get it, shift-and-invert
    around ``target`` never returns it.  Bound: |λ| ≤ max_i Σ_j|A_ij| / min_i B_ii for a
    diagonally dominant B; a generous multiple covers other B."""
    a, b = problem.scales()
    return target - 1e3 * (a / max(b, 1e-300)) * max(1.0, problem.n ** 0.5) - 1e3 * abs(target) - 1.0


@register("active-set")
def active_set(problem: EiCPProblem, *, tol: float = DEFAULT_TOL, target: float = 0.0, nev: int = 4,
               lam_min: float | None = None, support0=None, max_iter: int = 100, comm=None,
               options: dict | None = None, prefix: str = ACTIVE_SET, follow: bool = True,
               give_up_after: int | None = None, converging_after: int | None = None,
               **_ignored) -> EiCPResult:
    """One certified MEiCP solution by the active-set search (see the module docstring).

    target: shift of the eigen-solves; nev: eigenpairs per solve; lam_min: ignore eigenpairs
    below it (e.g. 0 for divergence modes); support0: the starting S (default all of J);
    options: PETSc options under ``prefix`` (a scene's ``[petsc]`` table); follow: after the
    first solve, follow the wanted eigenpair alone (nev = 1, shift just below its previous
    eigenvalue) — most of a solve's cost is shift-and-invert applications, and a shift next
    to the wanted eigenvalue needs a handful of them.  give_up_after: end an eigen-solve after
    that many Krylov–Schur restarts when no Ritz value estimates an eigenvalue ≥ lam_min
    (:class:`~meicp.petsc.reduced_pencil.ReducedPencilSolver`; a quick first look, not a proof);
    converging_after (with give_up_after): after that many restarts an eigen-solve goes on
    only while a Ritz value ≥ lam_min converges fast (``reduced_pencil.FAST_CONVERGENCE``)."""
    scaled, E = normalised(problem)
    if E is not None:  # shifts and the spurious value would overflow: solve scaled, map λ back
        result = active_set(scaled, tol=tol, target=scaled_value(target, E), nev=nev,
                            lam_min=scaled_value(lam_min, E), support0=support0, max_iter=max_iter, comm=comm,
                            options=options, prefix=prefix, follow=follow, give_up_after=give_up_after,
                            converging_after=converging_after)
        return restore(problem, scaled, result, E, tol)
    t0 = time.perf_counter()
    J = problem.J
    if support0 is None:
        S = J.copy()
    else:
        S = np.intersect1d(np.asarray(support0, dtype=np.int64), J)
    if problem.distributed:
        comm = problem.A.getComm()
    A, B, owned = _petsc_pair(problem, comm)
    symmetric = _is_symmetric(problem)
    solver = None
    option_error = False  # a value the user gave PETSc that it rejected (callers may call it bad input)
    result = EiCPResult(method="active-set")
    scales = problem.scales()
    visited: set = set()
    history = []
    status, message = "max_iterations", f"no certified solution within {max_iter} support updates"
    single_moves = False
    initial = None
    # the search ends at the first clean support, so max_iter is a bound, not a count
    progress = Progress(f"active-set search (at most {max_iter} support updates)", unit="eigen-solves")
    try:

        solver = ReducedPencilSolver(A, B, symmetric=symmetric, target=target,
                                     spurious=_spurious_value(problem, target), nev=nev,
                                     prefix=prefix, options=options,
                                     give_up=None if give_up_after is None else
                                     (give_up_after, 0.0 if lam_min is None else lam_floor(lam_min, scales),
                                      converging_after))
        result.timings["setup"] = time.perf_counter() - t0
        for it in range(1, max_iter + 1):
            key = S.tobytes()
            visited.add(key)
            if S.size == 0 and problem.F.size == 0:
                status, message = "empty_support", "every complementarity index left the support"
                break
            removed = np.setdiff1d(J, S)
            t_solve = time.perf_counter()
            try:
                if follow and history:
                    prev = history[-1]["lam"]
                    pairs = solver.solve(removed, initial, nev=1,
                                         target=prev - 1e-8 * max(abs(prev), scales[0] / max(scales[1], 1e-300)))
                else:
                    pairs = solver.solve(removed, initial)
            except (PetscSolveError, PetscOptionError) as exc:  # e.g. a singular shifted matrix at the target
                status, message = "petsc_error", _petsc_error_message(exc, it, S.size, prefix)
                option_error = isinstance(exc, PetscOptionError)
                break
            if lam_min is not None:
                floor = lam_floor(lam_min, scales)  # rounding only: tol is not a λ tolerance
                pairs = [p for p in pairs if p[0] >= floor]
            if not pairs:
                status = "not_converged"
                message = (f"no real eigenpair{'' if lam_min is None else f' with λ ≥ {lam_min}'} among "
                           f"the {nev} nearest the target {target} on support of size {S.size}")
                break
            # every returned pair is examined: a violation-free one (largest λ first) ends
            # the search; otherwise the largest λ drives the support update
            examined = sorted((_violations(problem, S, removed, lam, xi, scales, tol) + (err,)
                               for lam, xi, err in pairs), key=lambda v: -v[0])
            clean = [v for v in examined if v[3].size == 0 and v[4].size == 0]
            lam, xi, w, leave, enter, err = clean[0] if clean else examined[0]
            initial = xi
            xS, out = xi[S], removed
            history.append({"iteration": it, "lam": lam, "support": int(S.size), "leave": int(leave.size),
                            "enter": int(enter.size), "eps_residual": err,
                            "seconds": time.perf_counter() - t_solve})
            progress.update(it, detail=f"λ = {lam:.6g} on a support of {S.size}, {leave.size} leaving, "
                                       f"{enter.size} entering")
            if leave.size == 0 and enter.size == 0:
                sol = certify_pair(problem, lam, xi, scales)
                if sol.residual <= tol:
                    result.solutions = [sol]
                    status, message = "solved", f"certified after {it} eigen-solve(s)"
                else:
                    result.candidates = [sol]
                    status = "certificate_failed"
                    message = f"no sign or dual violation, but certificate residual {sol.residual:.2e} > {tol:.0e}"
                break
            S_next = np.union1d(np.setdiff1d(S, leave), enter)
            if single_moves or S_next.tobytes() in visited:
                single_moves = True
                S_next = _single_move(S, xS, w, out, leave, enter, visited)
                if S_next is None:
                    status, message = "cycling", f"every support update from iteration {it} revisits a support"
                    break
            S = S_next
        result.iterations = len(history)
    finally:
        if solver is not None:
            result.coverage = {"supports_visited": len(visited), "eigen_solves": solver.solves,
                               "eps_iterations": solver.eps_iterations, "gave_up": solver.gave_up,
                               "history": history,
                               "unused_options": solver.unused_options, "option_error": option_error}
            solver.destroy()
        if owned:
            A.destroy()
            B.destroy()
    result.status, result.message = status, message
    if status != "solved":
        result.message += (f"; {len(visited)} support(s) visited — this does not prove that no "
                           f"solution exists (use method='enumerate' for small |J|)")
    result.timings["solve"] = time.perf_counter() - t0
    return result


def _petsc_error_message(exc, it: int, support: int, prefix: str) -> str:
    """What went wrong, with PETSc's own last line, and the hint that fits the error: a bad
    option value (``-meicp_as_eps_tol abc``) is not cured by another target."""
    where = f"SLEPc/PETSc error {exc.ierr} in eigen-solve {it} (support of size {support})"
    if isinstance(exc, PetscOptionError):  # set_from_options named the prefix and the options given
        return f"{where}: {exc}"
    detail = f": {exc.line}" if exc.line else ""
    hint = (f"check the -{prefix}* options and the [petsc] table (a value PETSc cannot use)"
            if exc.ierr in ARGUMENT_ERRORS
            else f"a different target (-{prefix}eps_target) may avoid it")
    return f"{where}{detail}; {hint}"


def _violations(problem, S, removed, lam, xi, scales, tol=1e-10):
    """Orient ξ (eᵀξ_S > 0) and list the sign violations in S and dual violations off S.  An
    index leaves below −min(1e-9, tol/2)·max|ξ|: the certificate rejects x_j < −tol·‖x‖₂, so a
    looser test ended on a support it could not certify (an interface at μ = 20: x_j ≈ −3e-10)."""
    if (S.size and xi[S].sum() < 0) or (S.size == 0 and xi[np.argmax(np.abs(xi))] < 0):
        xi = -xi
    w = problem.residual_vector(lam, xi)
    scale_x = np.abs(xi).max()
    s = scales[0] + abs(lam) * scales[1]
    leave = S[xi[S] < -min(1e-9, 0.5 * tol) * scale_x] if S.size else S
    enter = removed[w[removed] < -1e-9 * s * scale_x] if removed.size else removed
    return lam, xi, w, leave, enter


def _single_move(S, xS, w, out, leave, enter, visited):
    """The most violated single index moves (leaving first), avoiding visited supports."""
    moves = []
    if leave.size:
        order = np.argsort(xS[np.isin(S, leave)])
        moves += [("leave", j) for j in leave[order]]
    if enter.size:
        order = np.argsort(w[enter])
        moves += [("enter", j) for j in enter[order]]
    for kind, j in moves:
        S_next = np.setdiff1d(S, [j]) if kind == "leave" else np.union1d(S, [j])
        if S_next.tobytes() not in visited:
            return S_next
    return None
