"""The (M)EiCP as a mixed complementarity problem in z = (x, λ), solved by PETSc SNES VI.

    F(z) = ( (λB − A)x , g(x) ),   bounds  x_J ∈ [0, ∞),  x_F and λ free,

so the MCP reads ``0 ≤ x_J ⊥ w_J ≥ 0``, ``w_F = 0``, ``g(x) = 0``.  The normalisation g keeps
x away from 0: ``g = eᵀx_J − 1`` when J ≠ ∅ (linear, the seed's choice, but it can only find
solutions with ``x_J ≠ 0``), and ``g = ½(xᵀBx − 1)`` when J = ∅ (a generalised eigenproblem).

Jacobian ``[[λB − A, Bx], [∇gᵀ, 0]]``: an AIJ matrix created once on the union pattern of
A, B, the diagonal and a dense last row and column, and *refilled completely* in every
Jacobian callback, because ``vinewtonssls`` overwrites it in place (docs/design.md §11).  The bordered
matrix is indefinite with a zero diagonal entry, so the linear solves are MUMPS LU (PETSc's
own LU does not pivot).  Options live under ``-meicp_eicp_vi_`` and the command line wins.

Line search ``basic`` (full Newton steps) by default: from the Niu set's x0 it solved 4 of 6
with ``vinewtonrsls`` where PETSc's default ``bt`` solved 1 (measured with PETSc 3.18);
override with ``-meicp_eicp_vi_snes_linesearch_type``.

Serial: the Mat lives on ``COMM_SELF`` (inputs are NumPy / SciPy).  This is a local Newton
method — converging or not depends on the start; callers must check the certificate, since
``vinewtonrsls`` can stop at a bad iterate at very tight ``snes_atol`` (docs/design.md §11).
"""

from __future__ import annotations


import numpy as np
import scipy.sparse as sp

from . import import_petsc
from .options import EICP_VI, configure_and_solve, petsc_errors

PREFIX = EICP_VI


class BorderedJacobian:
    """Fixed CSR pattern of ``[[λB − A, Bx], [∇gᵀ, 0]]`` and where A's and B's entries go in it.

    Positions are found once by sorting keys ``row·(n+1) + col`` (CSR with sorted column
    indices is sorted by that key), so a refill is a few vectorised NumPy assignments.
    """

    def __init__(self, A, B):
        A, B = sp.coo_matrix(A), sp.coo_matrix(B)
        A.sum_duplicates()
        B.sum_duplicates()
        n = A.shape[0]
        self.n = n
        N = n + 1
        rows = np.concatenate([A.row, B.row, np.arange(n), np.arange(n), np.full(N, n)])
        cols = np.concatenate([A.col, B.col, np.arange(n), np.full(n, n), np.arange(N)])
        pattern = sp.csr_matrix((np.ones(rows.size), (rows, cols)), shape=(N, N))
        pattern.sum_duplicates()
        pattern.sort_indices()
        self.indptr, self.indices = pattern.indptr, pattern.indices
        keys = np.repeat(np.arange(N), np.diff(self.indptr)) * N + self.indices

        def where(r, c):
            return np.searchsorted(keys, np.asarray(r) * N + np.asarray(c))

        self.A_pos, self.A_val = where(A.row, A.col), A.data.astype(float)
        self.B_pos, self.B_val = where(B.row, B.col), B.data.astype(float)
        self.col_pos = where(np.arange(n), n)
        self.row_pos = where(n, np.arange(n))
        self.nnz = keys.size

    def values(self, lam: float, Bx: np.ndarray, grad_g: np.ndarray) -> np.ndarray:
        vals = np.zeros(self.nnz)
        vals[self.B_pos] += lam * self.B_val
        vals[self.A_pos] -= self.A_val  # A_pos may coincide with B_pos: accumulate, never assign
        vals[self.col_pos] = Bx
        vals[self.row_pos] = grad_g
        return vals


@petsc_errors("SNES VI of the EiCP")
def snes_vi_eicp(A, B, J: np.ndarray, x0: np.ndarray, lam0: float, *, atol: float,
                 max_iter: int = 200, snes_type: str = "vinewtonrsls",
                 options: dict | None = None):
    """Solve the MCP above from ``(x0, lam0)``.  A, B: ndarray or SciPy sparse, serial.

    Returns ``(x, lam, iterations, reason_str, converged, seconds)``.  ``atol`` is the
    absolute SNES tolerance on ‖F‖ (the caller scales it by the matrix size).  A PETSc
    error is raised as :class:`~meicp.core.errors.PetscSolveError`.
    """
    PETSc = import_petsc()
    n = A.shape[0]
    N = n + 1
    J = np.asarray(J, dtype=np.int64)
    A_sp, B_sp = sp.csr_matrix(A), sp.csr_matrix(B)
    jac = BorderedJacobian(A_sp, B_sp)
    e_J = np.zeros(n)
    e_J[J] = 1.0

    if J.size:
        def g_and_grad(x, Bx):
            return float(x[J].sum()) - 1.0, e_J
    else:
        def g_and_grad(x, Bx):
            return 0.5 * (float(x @ Bx) - 1.0), Bx

    comm = PETSc.COMM_SELF
    Jmat = PETSc.Mat().createAIJ(size=(N, N), csr=(jac.indptr.astype(PETSc.IntType),
                                                    jac.indices.astype(PETSc.IntType),
                                                    np.zeros(jac.nnz)), comm=comm)
    Jmat.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, True)
    Jmat.assemble()
    z = PETSc.Vec().createSeq(N, comm=comm)
    r = z.duplicate()
    lower, upper = z.duplicate(), z.duplicate()
    lo = np.full(N, PETSc.NINFINITY)
    lo[J] = 0.0
    lower.setArray(lo)
    upper.set(PETSc.INFINITY)
    z.setArray(np.concatenate([x0, [lam0]]))

    def residual(snes, Z, Fv):
        zz = Z.getArray(readonly=True)
        x, lam = zz[:n], zz[n]
        Bx = B_sp @ x
        g, _ = g_and_grad(x, Bx)
        Fv.setArray(np.concatenate([lam * Bx - A_sp @ x, [g]]))

    def jacobian(snes, Z, Jm, P):
        zz = Z.getArray(readonly=True)
        x, lam = zz[:n], zz[n]
        Bx = B_sp @ x
        _, grad = g_and_grad(x, Bx)
        P.setValuesCSR(jac.indptr, jac.indices, jac.values(lam, Bx, grad),
                       addv=PETSc.InsertMode.INSERT_VALUES)
        P.assemble()
        if Jm.handle != P.handle:
            Jm.assemble()

    snes = PETSc.SNES().create(comm=comm)
    try:
        snes.setFunction(residual, r)
        snes.setJacobian(jacobian, Jmat)
        snes.setVariableBounds(lower, upper)
        defaults = {"snes_type": snes_type, "snes_max_it": max_iter, "snes_atol": atol,
                    "snes_rtol": 1e-30, "snes_stol": 0.0, "snes_max_funcs": 100 * max_iter,
                    "snes_linesearch_type": "basic", "ksp_type": "preonly", "pc_type": "lu",
                    "pc_factor_mat_solver_type": "mumps"}
        seconds, reason, its = configure_and_solve(snes, PREFIX, defaults, options, lambda: snes.solve(None, z))
        converged = snes.getConvergedReason() > 0
        out = z.getArray(readonly=True).copy()
    finally:
        snes.destroy()
        for obj in (Jmat, z, r, lower, upper):
            obj.destroy()
    return out[:n], float(out[n]), its, reason, converged, seconds
