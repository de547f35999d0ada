"""The largest Ritz value of a symmetric-definite pencil ``(sym A, sym B)`` by SLEPc's
Krylov–Schur (Lanczos) — the adapter only; what it tells about the divergence σ-window is
:mod:`meicp.contact.divergence.sigma_window`.

No factorisation: B through its Jacobi "solve" (exact for a lumped mass), a MUMPS Cholesky
otherwise.  The restarts are capped and the largest Ritz value seen is returned when the run
does not converge.  Options under ``meicp_window_``.  Collective on the matrices'
communicator.
"""

from __future__ import annotations

import math

from ..core.matrix import is_petsc_mat
from . import import_petsc, import_slepc
from .inertia import diagonal_minimum
from .mat import mat_from_scipy, symmetric_part
from .options import WINDOW, OptionsScope


def largest_ritz_value(A, B, *, max_it: int, tol: float, options: dict | None = None) -> tuple[float, bool, int]:
    """``(θ, converged, restarts)``: θ the largest Ritz value of ``(sym A, sym B)`` seen in at
    most ``max_it`` restarts (its residual below ``tol`` when ``converged``; nan when SLEPc
    fails, e.g. a breakdown of the B-inner product).  A, B: SciPy (solved on this process) or
    PETSc Mats."""
    PETSc, SLEPc = import_petsc(), import_slepc()
    SA, SB = symmetric_part(A), symmetric_part(B)
    if not is_petsc_mat(SA):
        SA, SB = mat_from_scipy(None, SA), mat_from_scipy(None, SB)
    seen = [-math.inf]

    def monitor(eps_, its, nconv, eig, err):
        if len(eig):
            seen[0] = max(seen[0], max(e.real for e in eig))

    eps = SLEPc.EPS().create(comm=SA.getComm())
    try:
        eps.setOperators(SA, SB)
        defaults = {"eps_gen_hermitian": True, "eps_largest_real": True, "eps_nev": 1, "eps_tol": tol,
                    "eps_max_it": max_it, "st_type": "shift", "st_ksp_type": "preonly", "st_pc_type": "jacobi"}
        if not diagonal_minimum(SB)[0]:
            defaults.update({"st_pc_type": "cholesky", "st_pc_factor_mat_solver_type": "mumps"})
        eps.setMonitor(monitor)
        try:
            with OptionsScope(WINDOW, defaults, options) as scope:
                scope.configure(eps)
                eps.solve()
        except PETSc.Error:  # e.g. a breakdown of the B-inner product: no estimate, no window
            return math.nan, False, 0
        converged = eps.getConverged() >= 1
        theta = eps.getEigenvalue(0).real if converged else seen[0]
        return float(theta), converged, int(eps.getIterationNumber())
    finally:
        try:
            eps.destroy()
        except PETSc.Error:  # SLEPc 3.18 cannot destroy a DS left mid-factorisation by a failed solve
            pass
        SA.destroy()
        SB.destroy()

