"""Local Newton for the (M)EiCP: the complementarity system in z = (x, λ) by PETSc SNES VI.

Why a third method: enumeration and the active-set walk find solutions support by support;
this one needs neither symmetry nor a support guess, only a start near a solution — it is
the cross-check and the polisher from a good start (e.g. an interpolated solution of a
neighbouring problem).  It is *local*: from a poor start it can wander or stall (on the
Niu set a plain semismooth approach solves 2 of 6 from the given x0), so non-convergence
is reported as such, and a "converged" SNES whose iterate fails :func:`certify_pair`
is reported as ``certificate_failed`` — never as a solution.

The system, its normalisation and the PETSc details are in :mod:`meicp.petsc.eicp_vi`; this
module registers the method as ``semismooth`` of :func:`meicp.solve_eicp`.
With J ≠ ∅ the normalisation ``eᵀx_J = 1`` means only solutions with ``x_J ≠ 0`` are sought.
"""

from __future__ import annotations

import time

import numpy as np

from ..core.errors import PetscSolveError, ProblemError
from ..core.matrix import matrix_comm, to_scipy
from ..eicp.problem import DEFAULT_TOL, EiCPProblem, EiCPResult, certify_pair
from ..eicp.scaling import normalised, restore, scaled_value
from ..eicp.solve import register
from .eicp_vi import snes_vi_eicp

#: SNES stops when ‖F‖₂ ≤ ATOL_FACTOR · (matrix scale); the certificate then decides
ATOL_FACTOR = 1e-13


@register("semismooth")
def semismooth(problem: EiCPProblem, *, tol: float = DEFAULT_TOL, x0=None, lam0=None,
               max_iter: int = 200, snes_type: str = "vinewtonrsls", options: dict | None = None,
               lam_min: float | None = None, **_) -> EiCPResult:
    """One certified (M)EiCP solution by semismooth / reduced-space Newton from (x0, lam0).

    x0: start vector (default: uniform on J, zero on F; the normalised all-ones vector when
        J = ∅).  It is clipped to ``x_J ≥ 0`` and scaled onto the normalisation.
    lam0: start eigenvalue (default: the Rayleigh quotient ``x0ᵀAx0 / x0ᵀBx0``).
    snes_type: ``vinewtonrsls`` (reduced space, default) or ``vinewtonssls`` (semismooth,
        Fischer–Burmeister); ``options``: extra PETSc options under ``-meicp_eicp_vi_``.
        The reduced-space method reads the active set off ``x_j = 0``: give it a start with
        zeros where the solution has them (a small positive x_j there often sends it to
        another solution); ``vinewtonssls`` tolerates such starts.
    lam_min: a solution with λ < lam_min is not reported (status ``not_found``, the pair in
        ``candidates``): Newton cannot be steered by it, only filtered.
    """
    if snes_type not in ("vinewtonrsls", "vinewtonssls"):
        raise ProblemError(f"snes_type must be 'vinewtonrsls' or 'vinewtonssls', got {snes_type!r}")
    scaled, E = normalised(problem)
    if E is not None:  # λ0 and the Jacobian's λB − A would overflow: solve scaled, map λ back
        result = semismooth(scaled, tol=tol, x0=x0, lam0=scaled_value(lam0, E), max_iter=max_iter,
                            snes_type=snes_type, options=options, lam_min=scaled_value(lam_min, E))
        return restore(problem, scaled, result, E, tol)
    t0 = time.perf_counter()
    A, B = _serial_pencil(problem)
    x_start = _start_vector(problem, B, x0)
    if x_start is None:
        return _no_start(t0, snes_type, "the default start x0 (all ones) has x0ᵀBx0 ≤ 0, so it cannot be "
                         "normalised to xᵀBx = 1 (B singular or indefinite on it): give x0")
    if lam0 is not None and not np.isfinite(lam0):
        raise ProblemError(f"lam0 must be finite, got {lam0!r}")
    xBx = float(x_start @ (B @ x_start))
    rounding = 1e3 * np.finfo(float).eps * problem.scales()[1] * float(x_start @ x_start)
    if lam0 is None and not (np.isfinite(xBx) and abs(xBx) > rounding):
        return _no_start(t0, snes_type, f"x0ᵀBx0 = {xBx:g} (B singular on the start), so the Rayleigh "
                         "quotient gives no start eigenvalue: give lam0 or another x0")
    lam_start = float(x_start @ (A @ x_start)) / xBx if lam0 is None else float(lam0)
    if not np.isfinite(lam_start):
        return _no_start(t0, snes_type, f"the start eigenvalue x0ᵀAx0 / x0ᵀBx0 = {lam_start} is not finite: "
                         "give lam0")
    scales = problem.scales()
    try:
        x, lam, its, reason, converged, seconds = snes_vi_eicp(
            A, B, problem.J, x_start, lam_start, atol=ATOL_FACTOR * max(scales[0], scales[1], 1.0),
            max_iter=max_iter, snes_type=snes_type, options=options)
    except PetscSolveError as exc:  # e.g. MUMPS on an exactly singular bordered Jacobian
        result = _no_start(t0, snes_type, f"PETSc error {exc.ierr} in SNES {snes_type}: {exc.line}")
        result.status = "petsc_error"
        return result
    result = EiCPResult(method="semismooth", iterations=its,
                        coverage={"snes_type": snes_type, "snes_reason": reason,
                                  "lam0": lam_start},
                        timings={"snes": seconds, "total": 0.0})
    finite = bool(np.all(np.isfinite(x)) and np.isfinite(lam) and np.any(x != 0))
    if finite:
        sol = certify_pair(problem, lam, x, scales)
        result.residual = sol.residual
        if sol.residual <= tol:
            result.status = "solved"
            result.solutions = [sol]
            result.message = f"SNES {snes_type} reached a certified solution ({reason})"
        else:
            result.candidates = [sol]
    if result.solutions and lam_min is not None and result.lam < lam_min:
        result.candidates, result.solutions = result.solutions, []
        result.status = "not_found"
        result.message = (f"SNES {snes_type} reached a certified solution with λ = "
                          f"{result.candidates[0].lam:.10g} < lam_min = {lam_min:g} (in candidates)")
    elif not result.solutions:
        if converged and finite:
            result.status = "certificate_failed"
            result.message = (f"SNES {snes_type} reported convergence ({reason}) but the iterate "
                              f"fails the certificate: residual {result.residual:.2e} > tol {tol:g}")
        else:
            result.status = "not_converged"
            result.message = (f"SNES {snes_type} did not converge after {its} iteration(s): "
                              f"{reason}; last residual {result.residual:.2e} (local method: "
                              f"try a better x0/lam0 or another method)")
    result.timings["total"] = time.perf_counter() - t0
    return result


def _no_start(t0: float, snes_type: str, why: str) -> EiCPResult:
    """A failure before or instead of Newton's first step: a status, never a traceback."""
    return EiCPResult(method="semismooth", status="bad_start", message=why,
                      coverage={"snes_type": snes_type}, timings={"total": time.perf_counter() - t0})


def _serial_pencil(problem: EiCPProblem):
    """A, B as ndarray / CSR; a PETSc Mat is gathered only when it lives on one rank."""
    if not problem.distributed:
        return problem.A, problem.B
    if matrix_comm(problem.A) is not None:
        raise ProblemError("semismooth runs serially: pass NumPy/SciPy matrices or a Mat on "
                           "one rank")
    return to_scipy(problem.A), to_scipy(problem.B)


def _start_vector(problem: EiCPProblem, B, x0) -> np.ndarray | None:
    """A start that satisfies the normalisation g(x) = 0 and the bounds x_J ≥ 0 (None when
    the default start cannot be normalised)."""
    n, J = problem.n, problem.J
    if x0 is None:
        x = np.zeros(n)
        x[J] = 1.0
        if J.size == 0:
            x[:] = 1.0
    else:
        x = np.array(x0, dtype=np.float64).ravel()
        if x.shape != (n,) or not np.all(np.isfinite(x)):
            raise ProblemError(f"x0 must be a finite vector of length {n}")
        x[J] = np.maximum(x[J], 0.0)
    if J.size:
        total = x[J].sum()
        if total <= 0:
            raise ProblemError("x0 must have a positive entry in J: with J ≠ ∅ the "
                               "normalisation eᵀx_J = 1 only admits solutions with x_J ≠ 0")
        return x / total
    xBx = float(x @ (B @ x))
    if not xBx > 0:
        if x0 is None:
            return None  # the default start does not fit B: a failure status, not bad input
        raise ProblemError("x0 must have x0ᵀBx0 > 0 (normalisation xᵀBx = 1 with J = ∅)")
    return x / np.sqrt(xBx)
