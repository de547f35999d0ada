"""Large sparse LCPs on PETSc: SNES VI (semismooth / reduced-space Newton) and TAO.

``newton``: F(x) = Mx + q with bounds 0 ≤ x ≤ ∞ solved by ``vinewtonrsls`` (default) or
``vinewtonssls``; the Jacobian is M, refilled at each callback because ``vinewtonssls``
modifies it in place (docs/design.md §11).  Linear solves by MUMPS LU (PETSc's own LU does not
pivot).  Any M; convergence is local, so the certificate decides.

``tao``: for symmetric M the LCP is the bound-constrained QP min ½xᵀMx + qᵀx, x ≥ 0, whose
KKT conditions are exactly the LCP; TAO's TRON/BLMVM/GPCG solve it.

Both are collective on the matrix's communicator: pass a PETSc Mat (distributed) or a
SciPy matrix (used on ``COMM_SELF``).  Options live under ``-meicp_lcp_`` (``snes_*``,
``ksp_*``, ``pc_*``, ``tao_*``) and can be overridden on the command line.  This module
registers them as the methods ``newton`` and ``tao`` of :func:`meicp.solve_lcp`.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..core.errors import PetscSolveError, ProblemError
from ..core.matrix import is_symmetric
from ..lcp.problem import DEFAULT_TOL, LCPProblem, LCPResult, best_of, certify, refine_on_support
from ..lcp.solve import register
from . import import_petsc
from .mat import mat_from_scipy, vec_to_numpy
from .options import LCP, LU, configure_and_solve, petsc_errors

PREFIX = LCP


def _petsc_operands(M, q, comm):
    """A PETSc Mat for M (distributed from SciPy when needed) and a Vec for q."""
    PETSc = import_petsc()
    owned = not isinstance(M, PETSc.Mat)
    A = mat_from_scipy(comm, M) if owned else M
    qv = A.createVecLeft()
    lo, hi = qv.getOwnershipRange()
    qv.setArray(np.asarray(q, dtype=PETSc.ScalarType)[lo:hi])
    return A, qv, owned


@petsc_errors("SNES VI of the LCP")
def snes_vi(M, q, *, comm=None, tol: float = 1e-12, max_iter: int = 200,
            snes_type: str = "vinewtonrsls", options: dict | None = None):
    """Solve LCP(q, M) (bounds 0 ≤ x ≤ ∞) with SNES VI through :func:`snes_vi_affine`.
    Returns ``(x, iterations, reason_str, seconds)`` with x gathered on every rank.  Collective."""
    n = len(q)
    defaults = {"snes_type": snes_type, "snes_max_it": max_iter, "snes_atol": 1e-30,
                "snes_rtol": tol, "snes_stol": 0.0}
    x, its, reason, seconds, _ = snes_vi_affine(M, q, np.zeros(n), np.full(n, np.inf), comm=comm,
                                                prefix=PREFIX, defaults=defaults, options=options)
    return x, its, reason, seconds


@petsc_errors("TAO of the LCP")
def tao_bqp(M, q, *, comm=None, tol: float = 1e-12, max_iter: int = 500,
            tao_type: str = "tron", options: dict | None = None):
    """Solve LCP(q, M), M symmetric, as min ½xᵀMx + qᵀx over x ≥ 0 with TAO.  Returns
    ``(x, iterations, reason_str, seconds)``, x gathered on every rank.  Collective."""
    PETSc = import_petsc()
    A, qv, owned = _petsc_operands(M, q, comm)
    x = A.createVecRight()
    x.set(0.0)
    lower, upper = x.duplicate(), x.duplicate()
    lower.set(0.0)
    upper.set(PETSc.INFINITY)
    Ax, grad = x.duplicate(), x.duplicate()

    def objective_gradient(tao, X, G):
        A.mult(X, Ax)
        f = 0.5 * X.dot(Ax) + qv.dot(X)
        Ax.copy(G)
        G.axpy(1.0, qv)
        return f

    def hessian(tao, X, H, P):
        pass  # constant Hessian M, set once below

    tao = PETSc.TAO().create(comm=A.getComm())
    try:
        tao.setObjectiveGradient(objective_gradient, grad)
        tao.setHessian(hessian, A)
        tao.setVariableBounds(lower, upper)
        defaults = {"tao_type": tao_type, "tao_max_it": max_iter, "tao_gatol": 0.0,
                    "tao_grtol": tol, "tao_gttol": 0.0}
        tao.setSolution(x)
        seconds, reason, its = configure_and_solve(tao, PREFIX, defaults, options, tao.solve)
        out = vec_to_numpy(x)
    finally:
        tao.destroy()
        for obj in (x, lower, upper, Ax, grad, qv):
            obj.destroy()
        if owned:
            A.destroy()
    return out, its, reason, seconds


def _method(kind: str):
    """The method ``kind`` (``newton``: :func:`snes_vi`; ``tao``: :func:`tao_bqp`) of
    :func:`meicp.solve_lcp`: PETSc's iterate polished on its support and certified; a PETSc
    error is a ``petsc_error`` status, not an exception."""
    def run(problem: LCPProblem, *, tol: float = DEFAULT_TOL, comm=None, options=None,
            max_iter: int | None = None, snes_type: str = "vinewtonrsls", tao_type: str = "tron",
            **_ignored) -> LCPResult:
        M = problem.M
        if kind == "tao" and not problem.distributed and not is_symmetric(M, 1e-12):
            raise ProblemError("tao solves the LCP as a QP and needs a symmetric M (use newton)")
        try:
            if kind == "tao":
                x, its, reason, seconds = tao_bqp(M, problem.q, comm=comm, tol=min(tol, 1e-12),
                                                  max_iter=max_iter or 500, tao_type=tao_type, options=options)
            else:
                x, its, reason, seconds = snes_vi(M, problem.q, comm=comm, tol=min(tol, 1e-12),
                                                  max_iter=max_iter or 200, snes_type=snes_type, options=options)
        except PetscSolveError as exc:  # e.g. TAO's line search on a QP that is unbounded below
            return LCPResult(method=kind, status="petsc_error", message=f"PETSc error {exc.ierr}: {exc.line}")
        result = LCPResult(method=kind, iterations=its, message=f"PETSc: {reason}")
        result.timings["solve"] = seconds
        converged = "CONVERGED" in reason
        x = best_of(problem, x, refine_on_support(problem, x)) if converged else x
        return certify(problem, result, x, tol=tol,
                       failure_status="certificate_failed" if converged else "not_converged")
    run.__name__ = kind
    return register(kind)(run)


newton = _method("newton")
tao = _method("tao")


def snes_vi_affine(J, q, lower, upper, *, comm=None, prefix: str = PREFIX, defaults: dict | None = None,
                   options: dict | None = None, x0=None):
    """Solve the affine VI ``lower ≤ z ≤ upper ⊥ F(z) = J z + q`` (a mixed complementarity
    problem: unbounded entries are equations) by SNES VI with a constant Jacobian J.

    J: a PETSc Mat or a SciPy matrix (every rank holds it; distributed with
    :func:`mat_from_scipy` over ``comm``); q, lower, upper, x0: full-length arrays on every rank
    (±inf for no bound).  The Jacobian is copied back from J in every callback
    (``vinewtonssls`` overwrites it, docs/design.md §11).  Options ``defaults`` < ``options`` < command
    line under ``prefix``.  Returns ``(z, iterations, reason_str, seconds, snes_type)`` with z
    gathered on every rank; a PETSc error inside the solve becomes ``reason_str = "PETSC_ERROR: ..."``.
    Collective.
    """
    PETSc = import_petsc()
    if not isinstance(J, PETSc.Mat):
        # vinewtonssls adds to the diagonal (MatDiagonalSet): store it, explicit zeros included
        c = sp.coo_matrix(J)
        n = c.shape[0]
        J = sp.csr_matrix((np.concatenate([c.data, np.zeros(n)]),
                           (np.concatenate([c.row, np.arange(n)]), np.concatenate([c.col, np.arange(n)]))),
                          shape=c.shape)
    A, qv, owned = _petsc_operands(J, q, comm)
    Jm = A.duplicate(copy=True)
    x = A.createVecRight()
    lo, hi = x.getOwnershipRange()

    def vec(values):
        v = x.duplicate()
        v.setArray(np.asarray(values, dtype=PETSc.ScalarType)[lo:hi])
        return v

    xl = vec(np.where(np.isfinite(lower), lower, PETSc.NINFINITY))
    xu = vec(np.where(np.isfinite(upper), upper, PETSc.INFINITY))
    x.setArray(np.zeros(hi - lo) if x0 is None else np.asarray(x0, dtype=PETSc.ScalarType)[lo:hi])
    r = x.duplicate()

    def residual(snes, X, F):
        A.mult(X, F)
        F.axpy(1.0, qv)

    def jacobian(snes, X, Jmat, P):
        A.copy(Jmat, structure=PETSc.Mat.Structure.SAME_NONZERO_PATTERN)

    snes = PETSc.SNES().create(comm=A.getComm())
    try:
        snes.setFunction(residual, r)
        snes.setJacobian(jacobian, Jm)
        snes.setVariableBounds(xl, xu)
        base = {"snes_type": "vinewtonrsls", "snes_max_it": 100, "snes_atol": 1e-30, "snes_rtol": 1e-12,
                "snes_stol": 0.0, "ksp_type": "preonly", "pc_type": "lu",
                "pc_factor_mat_solver_type": "mumps", "snes_linesearch_type": "basic"}
        base.update(defaults or {})
        try:
            seconds, reason, its = configure_and_solve(snes, prefix, base, options,
                                                       lambda: snes.solve(None, x))
        except PETSc.Error as exc:  # e.g. MUMPS on a singular reduced system
            seconds, reason, its = float("nan"), f"PETSC_ERROR: {exc}", snes.getIterationNumber()
        out = vec_to_numpy(x)
        used = snes.getType()
    finally:
        snes.destroy()
        for obj in (Jm, x, xl, xu, r, qv):
            obj.destroy()
        if owned:
            A.destroy()
    return out, its, reason, seconds, used


def lu_solve(A, b, *, comm=None, prefix: str = LU, options: dict | None = None):
    """``A⁻¹ b`` by MUMPS LU (KSP preonly) for a SciPy matrix every rank holds, distributed over
    ``comm``; the solution is gathered on every rank.  Returns ``(x, ok)``: ``ok`` is False
    when MUMPS failed (singular matrix).  Collective."""
    PETSc = import_petsc()
    M, bv, owned = _petsc_operands(A, b, comm)
    x = M.createVecRight()
    ksp = PETSc.KSP().create(comm=M.getComm())
    ok = True
    try:
        ksp.setOperators(M)
        defaults = {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"}
        try:
            configure_and_solve(ksp, prefix, defaults, options, lambda: ksp.solve(bv, x))
            ok = ksp.getConvergedReason() >= 0
        except PETSc.Error:
            ok = False
        out = vec_to_numpy(x)
    finally:
        ksp.destroy()
        for obj in (x, bv):
            obj.destroy()
        if owned:
            M.destroy()
    return out, ok and bool(np.all(np.isfinite(out)))
