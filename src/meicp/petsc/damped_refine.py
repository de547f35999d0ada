"""A real eigenpair of a distributed quadratic pencil on one support, near a given one
(docs/damping.md, "damped divergence modes at scale").

A damped divergence mode is a real λ ≥ 0 and x with ``x_O = 0`` on the complementarity rows O
outside its support and ``(λ²B + λD − A)_RR x_R = 0`` on the rest R.  From a nearby pair — the
undamped mode's ``(√σ, x)``, whose support it usually keeps when the damping is light —
:func:`refine_real_pair` converges to it by *residual inverse iteration* (Neumaier, SIAM J.
Numer. Anal. 22, 1985): with ``T(λ) = λ²B + λD − A`` restricted to R and one factor of
``T(λ₀)`` (block low rank: :data:`REFINE_LOW_RANK`),

    λ_{k+1}: the real root nearest λ_k of  wᵀT(λ₀)⁻¹T(λ)x_k = 0   (a quadratic in λ),
    x_{k+1} = x_k − T(λ₀)⁻¹T(λ_{k+1})x_k,   normalised by wᵀx = 1,

linearly convergent at a rate of order |λ − λ₀|, three solves per step (T(λ₀)⁻¹ applied to
Ax, Bx and Dx, so that the scalar equation is exact in λ).  The factor is DMUMPS' real LU
(:class:`~meicp.petsc.mumps_c.LUFactor`) of ``T(λ₀)`` with the rows and columns of O replaced
by the identity: about half the time and memory of the complex factor the flutter searches
need.  Nothing here is a
certificate: :func:`quadratic_certificate` checks the complementarity conditions on the
whole pencil, row by row, as :func:`meicp.eicp.quadratic.certify` does on dense data.

Collective on the matrices' communicator; the factor is destroyed before returning.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from ..core.comm import mpi_comm
from ..core.errors import ProblemError
from . import mumps_c
from .flutter import _allreduce
from .flutter_quadratic import QuadraticPencilOps
from .options import FLUTTER, mumps_controls

#: ξ_j > SUPPORT_TOL·‖ξ‖∞ counts as positive (as the dense quadratic MEiCP's)
SUPPORT_TOL = 1e-9
#: the factor of T(λ₀) is block-low-rank at this dropping tolerance (MUMPS ICNTL(35) = 2,
#: CNTL(7)): the iteration only needs an approximate inverse — its residuals are computed on
#: the pencil itself, so the factor's accuracy sets the rate, never the answer.  At 10⁶ DOFs
#: the refinement took 7.0 s against 13–15 s full rank, the same λ in the same single step
#: (docs/benchmarks-notes.md, "REFINE_LOW_RANK")
REFINE_LOW_RANK = 1e-8


def _allsum(comm, *values) -> np.ndarray:
    return _allreduce(comm, np.array(values, dtype=float))


def _real_roots(a: float, b: float, c: float) -> list[float]:
    """The real roots of ``a·λ² + b·λ + c``; a discriminant negative within rounding counts
    as 0 (a double root near λ = 0 under light damping would otherwise come out complex)."""
    if a == 0:
        return [-c / b] if b != 0 else []
    disc = b * b - 4 * a * c
    if disc < 0:
        if -disc > 1e-12 * (b * b + 4 * abs(a * c)):
            return []
        disc = 0.0
    root = np.sqrt(disc)
    q = -0.5 * (b + np.copysign(root, b))  # the stable pair: q/a and c/q
    return [q / a] + ([c / q] if q != 0 else [])


def _restricted(rows: sp.csr_matrix, lo: int, out: np.ndarray) -> sp.csr_matrix:
    """``rows`` (this rank's, global columns) with the rows and columns of ``out`` (global,
    sorted) replaced by those of the identity."""
    coo = rows.tocoo()
    keep = ~np.isin(coo.col, out) & ~np.isin(coo.row + lo, out)
    mine = out[(out >= lo) & (out < lo + rows.shape[0])]
    r = np.concatenate([coo.row[keep], mine - lo])
    c = np.concatenate([coo.col[keep], mine])
    v = np.concatenate([coo.data[keep], np.ones(mine.size)])
    return sp.csr_matrix((v, (r, c)), shape=rows.shape)


def refine_real_pair(ops: QuadraticPencilOps, lam0: float, x0: np.ndarray, out: np.ndarray, *,
                     tol: float = 1e-12, max_it: int = 40) -> tuple[float, np.ndarray, dict]:
    """The real eigenpair ``(λ, x)`` of ``λ²B + λD − A`` restricted to the complement of
    ``out`` (global reduced indices: x is 0 there) nearest ``(lam0, x0)`` (``x0`` the whole
    vector, on every rank), by residual inverse iteration (module docstring).  Returns
    ``(λ, x on every rank, info)``; info: ``iterations``, ``backward_error`` (on the
    restricted pencil), ``converged``, ``seconds``, ``why`` (when not converged).  Collective."""
    entry, why = mumps_c.load("d")
    if entry is None:
        raise ProblemError(f"damped divergence modes at scale need MUMPS: {why}")
    t0 = time.perf_counter()
    A = ops.A
    comm = mpi_comm(A.getComm())
    lo, hi = A.getOwnershipRange()
    n = A.getSize()[0]
    out = np.unique(np.asarray(out, dtype=np.int64))
    gone = out[(out >= lo) & (out < hi)] - lo

    def restrict(v):
        v = np.array(v.real, dtype=float)  # every vector here is real: the products' imaginary parts are 0
        v[gone] = 0.0
        return v

    T0 = (lam0 * lam0 * ops.B_local + lam0 * ops.D_local - ops.A_local).tocsr()
    icntl, cntl = mumps_controls(FLUTTER + "st_mat_mumps_")  # the flutter search's MUMPS options apply
    icntl, cntl = {35: 2, **icntl}, {7: REFINE_LOW_RANK, **cntl}
    x = restrict(x0[lo:hi])
    w = x.copy()
    x = x / _allsum(comm, np.dot(w, x))[0]
    lam, info = float(lam0), {"iterations": 0, "converged": False, "why": ""}
    with mumps_c.LUFactor(comm, _restricted(T0, lo, out), lo, n, arith="d", icntl=icntl, cntl=cntl,
                          what="MUMPS factor of the damped divergence refinement") as factor:
        for k in range(1, max_it + 1):
            Ax, Bx, Dx = (restrict(ops.times(M, x)) for M in (ops.A, ops.B, ops.D))
            a, b, d = (factor.solve(v) for v in (Ax, Bx, Dx))
            ca, cb, cd = _allsum(comm, np.dot(w, a), np.dot(w, b), np.dot(w, d))
            real = _real_roots(cb, cd, -ca)
            info["iterations"] = k
            if not real:
                info["why"] = f"the scalar equation has no real root at step {k}: the mode left the real axis"
                break
            lam = min(real, key=lambda r: abs(r - lam))
            x = x - (lam * lam * b + lam * d - a)
            x = x / _allsum(comm, np.dot(w, x))[0]
            r = restrict(lam * lam * ops.times(ops.B, x) + lam * ops.times(ops.D, x) - ops.times(ops.A, x))
            rr, xx = _allsum(comm, np.dot(r, r), np.dot(x, x))
            info["backward_error"] = float(np.sqrt(rr) / (ops.scale(lam) * np.sqrt(xx)))
            if info["backward_error"] <= tol:
                info["converged"] = True
                break
        else:
            info["why"] = f"backward error {info['backward_error']:.1e} after {max_it} steps"
    info["seconds"] = time.perf_counter() - t0
    return lam, ops.gather(x).real, info


def quadratic_certificate(ops: QuadraticPencilOps, lam: float, x: np.ndarray, J: np.ndarray) -> tuple[float, dict, np.ndarray]:
    """``(residual, parts, support)`` of a real candidate ``(λ, x)`` (x on every rank) of the
    quadratic MEiCP with complementarity rows ``J`` (global reduced indices), row by row on the
    pencil as :func:`meicp.eicp.quadratic.certify` measures it: row i against
    ``max|A_i·| + |λ| max|D_i·| + λ² max|B_i·|`` with ‖x‖₂ = 1; ``support`` the j ∈ J with
    ``x_j > SUPPORT_TOL·‖x‖∞``.  Collective."""
    A = ops.A
    comm = mpi_comm(A.getComm())
    lo, hi = A.getOwnershipRange()
    x = np.asarray(x, dtype=float) / np.linalg.norm(x)
    xl = x[lo:hi]
    y = (lam * lam * ops.times(ops.B, xl) + lam * ops.times(ops.D, xl) - ops.times(ops.A, xl)).real

    def row_max(M):
        M = abs(M).tocsr()
        return np.asarray(M.max(axis=1).todense()).ravel() if M.shape[0] else np.zeros(0)

    s = row_max(ops.A_local) + abs(lam) * row_max(ops.D_local) + lam * lam * row_max(ops.B_local)
    s = np.where(s > 0, s, 1.0)
    inJ = np.zeros(hi - lo, dtype=bool)
    mine = J[(J >= lo) & (J < hi)] - lo
    inJ[mine] = True
    on = ~inJ | (inJ & (xl > SUPPORT_TOL * np.abs(x).max()))
    local = np.array([np.max(np.abs(y[on]) / s[on], initial=0.0), max(0.0, -xl[inJ].min(initial=0.0)),
                      max(0.0, np.max(-y[inJ] / s[inJ], initial=0.0)),
                      np.max(np.abs(xl[inJ] * y[inJ]) / s[inJ], initial=0.0)])
    if comm is not None:  # an elementwise maximum over the ranks
        local = np.max(np.array(comm.allgather(local)), axis=0)
    parts = dict(zip(("eigen", "x_J", "y_J", "complementarity"), (float(v) for v in local)))
    support = J[x[J] > SUPPORT_TOL * np.abs(x).max()]
    return max(parts.values()), parts, support


__all__ = ["quadratic_certificate", "refine_real_pair"]
