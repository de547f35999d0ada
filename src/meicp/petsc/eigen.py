"""Generalized eigenpairs of a distributed pencil with SLEPc.

``A x = λ B x`` with shift-and-invert around a target (MUMPS factorisation), options
under a prefix so that everything is overridable from the command line.  Collective on
the matrices' communicator.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..core.comm import mpi_comm
from ..core.errors import ConvergenceError
from . import import_petsc, import_slepc
from .mat import ownership
from .options import GHEP, OptionsScope


@dataclass
class EigenPairs:
    """Converged eigenpairs, nearest the target first.

    values: real eigenvalues; vectors: PETSc Vecs (distributed like the matrices);
    residuals: SLEPc's relative residual ‖Ax − λBx‖ / ‖λx‖ of each pair (backward error
    relative to the matrix norms would be ``EPS.Errortype.BACKWARD``).
    """

    values: np.ndarray
    vectors: list
    residuals: np.ndarray
    iterations: int = 0
    unused_options: list = field(default_factory=list)


def ghep_defaults(nev: int, target: float) -> dict:
    """Code defaults for a symmetric-definite pencil solved by shift-and-invert + MUMPS."""
    return {
        "eps_gen_hermitian": True,
        "eps_nev": nev,
        "eps_target": target,
        "eps_target_magnitude": True,
        "eps_tol": 1e-10,
        "st_type": "sinvert",
        "st_ksp_type": "preonly",
        "st_pc_type": "cholesky",
        "st_pc_factor_mat_solver_type": "mumps",
        # AMF ordering: Debian's MUMPS has no METIS/SCOTCH and picks PORD, which was
        # 1.05-1.36x slower per eigen-solve from 3e5 to 1e6 DOFs (docs/benchmarks.md, scaling)
        "st_mat_mumps_icntl_7": 2,
    }


def solve_ghep(A, B, nev: int = 4, target: float = 0.0, *, prefix: str = GHEP,
               options: dict | None = None, ksp=None) -> EigenPairs:
    """The ``nev`` eigenpairs of the symmetric-definite pencil (A, B) nearest ``target``.

    ``options`` (e.g. a scene's ``[petsc]`` table, keys without the prefix) override the
    code defaults; command-line options override both.  ``ksp``: a KSP already set up with
    a MUMPS Cholesky factor of A itself (``target`` 0), which the spectral transformation
    then reuses instead of factoring A again (its operator is A unchanged, so PETSc keeps
    the factor).  Collective.  Raises :class:`ConvergenceError` if fewer than ``nev`` pairs
    converge.
    """
    if ksp is not None and target != 0.0:
        raise ValueError("a given KSP holds the factor of A: the target must be 0")
    PETSc = import_petsc()
    SLEPc = import_slepc()
    eps = SLEPc.EPS().create(comm=A.getComm())
    try:
        eps.setOperators(A, B)
        if ksp is not None:
            eps.getST().setKSP(ksp)
        with OptionsScope(prefix, ghep_defaults(nev, target), options) as scope:
            scope.configure(eps)
            eps.solve()
        nconv = eps.getConverged()
        values, vectors, residuals = [], [], []
        for i in range(min(nconv, eps.getDimensions()[0])):
            x = A.createVecRight()
            lam = eps.getEigenpair(i, x)
            values.append(lam.real)
            vectors.append(x)
            residuals.append(eps.computeError(i, SLEPc.EPS.ErrorType.RELATIVE))
        result = EigenPairs(np.array(values), vectors, np.array(residuals),
                            eps.getIterationNumber(), scope.unused)
        if nconv < eps.getDimensions()[0]:
            raise ConvergenceError(
                f"SLEPc converged {nconv} of {eps.getDimensions()[0]} eigenpairs "
                f"(reason {eps.getConvergedReason()})", result)
        return result
    finally:
        if ksp is not None:
            # destroying the EPS resets its ST's KSP, which would free the caller's factor
            detached = PETSc.KSP().create(comm=A.getComm())
            eps.getST().setKSP(detached)
            detached.destroy()
        eps.destroy()
        PETSc.garbage_cleanup() if hasattr(PETSc, "garbage_cleanup") else None


class _WeightedInverse:
    """The MATSHELL y ↦ W^½ K⁻¹ W^½ y (W a positive diagonal, its root ``root`` on this
    rank's rows) with K⁻¹ applied on rank 0 by ``solve_on_host`` (a whole vector in, the
    whole solution out on rank 0, None elsewhere; collective)."""

    def __init__(self, comm, solve_on_host, root: np.ndarray, counts: np.ndarray | None):
        self.comm, self.solve, self.root, self.counts = comm, solve_on_host, root, counts
        self.host = comm is None or comm.Get_rank() == 0
        self.whole = np.zeros(int(counts.sum()) if counts is not None else root.size) if self.host else None

    def mult(self, mat, x, y):
        local = x.getArray(readonly=True) * self.root
        if self.comm is None or self.comm.Get_size() == 1:
            self.whole[:] = local
        else:
            self.comm.Gatherv(local, [self.whole, self.counts] if self.host else None, root=0)
        solution = self.solve(self.whole if self.host else None)
        out = y.getArray()
        if self.comm is None or self.comm.Get_size() == 1:
            out[:] = solution
        else:
            self.comm.Scatterv([np.ascontiguousarray(solution), self.counts] if self.host else None, out, root=0)
        out *= self.root


def inverse_estimate(pcomm, solve_on_host, weights: np.ndarray, *, prefix: str, options: dict | None = None) -> float:
    """SLEPc's estimate of the smallest eigenvalue of (K, diag(weights)), K symmetric positive
    definite known only through ``solve_on_host`` (rank 0 holds the right-hand side and gets
    the solution, as with an interior solve of :class:`meicp.petsc.mumps_c.SchurSeries`):
    1/θ for the largest θ of the symmetric W^½K⁻¹W^½, Krylov–Schur (HEP) on a MATSHELL.
    ``weights``: every rank holds all of them (positive).  ``options`` (keys without the
    prefix) over the loose defaults of an estimate; 0.0 when SLEPc fails or does not converge —
    an estimate places things, it proves nothing.  Collective on the PETSc communicator."""
    PETSc = import_petsc()
    SLEPc = import_slepc()
    comm = mpi_comm(pcomm)
    n = int(weights.size)
    size, rank = pcomm.getSize(), pcomm.getRank()
    lo, hi = ownership(n, rank, size)
    counts = np.array([np.diff(ownership(n, r, size))[0] for r in range(size)]) if size > 1 else None
    shell = _WeightedInverse(comm if size > 1 else None, solve_on_host, np.sqrt(weights[lo:hi]), counts)
    op = PETSc.Mat().createPython(((hi - lo, n), (hi - lo, n)), shell, comm=pcomm)
    op.setUp()
    eps = SLEPc.EPS().create(comm=pcomm)
    try:
        eps.setOperators(op)
        defaults = {"eps_type": "krylovschur", "eps_hermitian": True, "eps_largest_magnitude": True,
                    "eps_nev": 1, "eps_ncv": 6, "eps_tol": 1e-3, "eps_max_it": 100}
        with OptionsScope(prefix, defaults, options) as scope:
            scope.configure(eps)
            try:
                eps.solve()
            except PETSc.Error:  # on every rank (the solves are collective): no estimate
                return 0.0
        if eps.getConverged() < 1:
            return 0.0
        theta = eps.getEigenvalue(0).real
        return float(1.0 / theta) if theta > 0 else 0.0
    finally:
        eps.destroy()
        op.destroy()
