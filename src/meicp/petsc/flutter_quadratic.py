"""Damped flutter eigenpairs of a distributed quadratic sliding pencil with SLEPc
(docs/damping.md, "damped flutter at scale").

The damped sliding pencil is ``Q(λ) = λ²B + λD − A`` (λ itself the growth rate and angular
frequency).  Its first companion linearisation ``L₀z = λL₁z``, ``z = [x; λx]``,

    L₀ = [[0, I], [A, −D]],   L₁ = diag(I, B),

is searched by complex shift-and-invert at a target λ₀: the operator ``T = (L₀ − λ₀L₁)⁻¹L₁``
(eigenvalues ``1/(λ − λ₀)``) costs one complex MUMPS solve with Q(λ₀) per application — for
``[f; g] = L₁z``, ``u = −Q(λ₀)⁻¹(g + (D + λ₀B)f)`` and ``v = f + λ₀u`` — which is what SLEPc's
TOAR does with shift-and-invert on MUMPS; SLEPc's PEP cannot take a complex target in this
real-scalar build, so, as for the undamped search (:mod:`meicp.petsc.flutter`), SLEPc's
Krylov–Schur runs on the real form of T (order 4n: every complex entry interleaved) and the
factor is ZMUMPS' (:class:`~meicp.petsc.mumps_c.ComplexFactor`).  Every pair is re-checked on
Q itself: backward error ‖Q(λ)x‖ / ((|λ|²‖B‖₁ + |λ|‖D‖₁ + ‖A‖₁)‖x‖).

Options: prefix :data:`~meicp.petsc.options.FLUTTER`, as for the undamped search.  Collective
on the matrices' communicator; the EPS and the factor are destroyed before the solve returns.
"""

from __future__ import annotations

import time

import numpy as np

from ..core.comm import mpi_comm
from ..core.errors import ProblemError
from . import import_petsc, import_slepc, mumps_c
from .flutter import PencilWork, StallWatch, complex_defaults, converged_pairs, local_csr, solve_tightened
from .options import FLUTTER, OptionsScope, mumps_controls


class QuadraticPencilOps(PencilWork):
    """The distributed quadratic pencil (A, B, D) with what every solve needs: the 1-norms,
    this rank's rows as SciPy CSR, complex products and backward errors.  Collective;
    ``destroy`` (or a ``with`` block) frees the work vectors, not the matrices."""

    def __init__(self, A, B, D):
        PETSc = import_petsc()
        self.A, self.B, self.D = A, B, D
        self.norms = tuple(M.norm(PETSc.NormType.NORM_1) for M in (A, B, D))
        self.A_local, self.B_local, self.D_local = local_csr(A), local_csr(B), local_csr(D)
        self.m = A.getLocalSize()[0]
        self._work = [A.createVecRight(), A.createVecLeft()]

    def times(self, M, x_local: np.ndarray) -> np.ndarray:
        """``M x`` (this rank's entries in, this rank's out): one product for a real x, two
        for a complex one.  Collective."""
        x, y = self._work
        x.setArray(np.ascontiguousarray(x_local.real))
        M.mult(x, y)
        real = y.getArray(readonly=True).copy()
        if not np.iscomplexobj(x_local):
            return real
        x.setArray(np.ascontiguousarray(x_local.imag))
        M.mult(x, y)
        return real + 1j * y.getArray(readonly=True)

    def scale(self, lam: complex) -> float:
        """|λ|²‖B‖₁ + |λ|‖D‖₁ + ‖A‖₁: the backward error's unit at λ."""
        norm_A, norm_B, norm_D = self.norms
        return abs(lam) ** 2 * norm_B + abs(lam) * norm_D + norm_A

    def residual(self, lam: complex, x_local: np.ndarray) -> float:
        """Backward error of (λ, x) on Q, x given by this rank's entries.  Collective."""
        r = lam * lam * self.times(self.B, x_local) + lam * self.times(self.D, x_local) - self.times(self.A, x_local)
        comm = mpi_comm(self.A.getComm())
        sums = np.array([np.vdot(r, r).real, np.vdot(x_local, x_local).real])
        if comm is not None:
            sums = comm.allreduce(sums)
        return float(np.sqrt(sums[0]) / (self.scale(lam) * np.sqrt(sums[1])))


class _CompanionInverse:
    """The MATSHELL of T = (L₀ − λ₀L₁)⁻¹L₁ on the real form of the companion vectors: each
    rank holds its rows of x and then of λx, every complex entry as (re, im)."""

    def __init__(self, ops: QuadraticPencilOps, factor, lam0: complex):
        self.ops, self.factor, self.lam0 = ops, factor, lam0

    def mult(self, mat, z, y):
        ops, m, lam0 = self.ops, self.ops.m, self.lam0
        a = z.getArray(readonly=True)
        c = a[0::2] + 1j * a[1::2]
        f = c[:m]
        # g + (D + λ₀B)f with g = B·z₂: B once, on z₂ + λ₀f
        u = -self.factor.solve(ops.times(ops.B, c[m:] + lam0 * f) + ops.times(ops.D, f))
        out = y.getArray()
        w = np.concatenate([u, f + lam0 * u])
        out[0::2], out[1::2] = w.real, w.imag


class GrowthWatch(StallWatch):
    """A stopping test for the damped search, a speed heuristic: the :class:`StallWatch`, and
    after ``restarts`` Krylov–Schur restarts the solve also ends when no Ritz value of the
    operator grows (θ, λ = λ₀ + 1/θ or λ̄₀ + 1/θ: the same real part; every Re λ < 0): the
    damping leaves nothing that grows near the target.

    Without it a target where nothing converges runs to the cap of 500 restarts (10⁶ DOFs,
    μ = 0.05: the error estimate 0.25 → 0.09 in 8 restarts, about 10 s each:
    docs/benchmarks.md, "Damping at scale")."""

    def __init__(self, lam0: complex, restarts: int, budget: int, tol: float):
        super().__init__(restarts, budget, tol)
        self.lam0, self.growing = complex(lam0), True

    def monitor(self, _eps, its, nconv, eig, err) -> None:
        super().monitor(_eps, its, nconv, eig, err)
        theta = np.asarray(eig, dtype=complex)
        theta = theta[theta != 0]
        self.growing = bool(theta.size == 0 or np.any(self.lam0.real + (1.0 / theta).real >= 0))

    def why_stop(self, its: int) -> str:
        return "no Ritz value with Re λ ≥ 0" if not self.growing else super().why_stop(its)


def quadratic_shift_solve(ops: QuadraticPencilOps, lam0: complex, *, nev: int = 2, ncv: int | None = 12,
                          tol: float = 1e-12, low_rank: float | None = None, max_it: int = 500,
                          options: dict | None = None, gate: float | None = None,
                          strict_tol: float | None = None, give_up: tuple | None = None) -> tuple[list, dict]:
    """The ~nev eigenvalues λ of Q(λ) = λ²B + λD − A nearest the complex target λ₀ (module
    docstring).  Returns ``(pairs, info)`` as :func:`meicp.petsc.flutter.complex_shift_solve`
    does, with λ in place of σ: pairs = [(λ with Im λ ≥ 0, x gathered on every rank, backward
    error on Q)], info = {``radius`` (the largest |λ − λ₀| converged), ``nconv``,
    ``iterations``, ``seconds``, ``solves``}.  ``gate``, ``strict_tol``, ``low_rank``,
    ``max_it``, ``options``: as there; ``give_up``: ``(restarts, budget)`` of a
    :class:`GrowthWatch` on the solve (info ``gave_up``: why it stopped it, or "").
    ProblemError when no ZMUMPS of a known version loads (this search has no real-form
    fallback).  Collective."""
    PETSc = import_petsc()
    SLEPc = import_slepc()
    entry, why = mumps_c.load("z")
    if entry is None:
        raise ProblemError(f"the damped flutter search needs a complex MUMPS: {why}")
    t0 = time.perf_counter()
    lam0 = complex(lam0)
    A = ops.A
    n = A.getSize()[0]
    pcomm = A.getComm()
    size = ((4 * ops.m, 4 * n), (4 * ops.m, 4 * n))
    eps = SLEPc.EPS().create(comm=pcomm)
    T = factor = None
    vectors = []
    try:
        defaults = complex_defaults(2 * nev, ncv and 2 * ncv, tol, n=n, low_rank=low_rank, max_it=max_it)
        with OptionsScope(FLUTTER, defaults, options) as scope:
            icntl, cntl = mumps_controls(FLUTTER + "st_mat_mumps_")
            lo = A.getOwnershipRange()[0]
            Q0 = (lam0 * lam0 * ops.B_local + lam0 * ops.D_local - ops.A_local).tocsr()
            factor = mumps_c.ComplexFactor(mpi_comm(pcomm), Q0, lo, n, icntl=icntl, cntl=cntl)
            T = PETSc.Mat().createPython(size, _CompanionInverse(ops, factor, lam0), comm=pcomm)
            T.setUp()
            eps.setOperators(T)
            scope.configure(eps)  # setFromOptions, last
            watch = None if give_up is None else GrowthWatch(lam0, *give_up, tol=eps.getTolerances()[0]).attach(eps)

            def collect():
                return converged_pairs(eps, T, lam0, inverted=True, residual=ops.residual, gather=ops.gather,
                                       comm=mpi_comm(pcomm), head=ops.m, info={"factor": "complex"})

            pairs, info = solve_tightened(eps, collect, T, gate, strict_tol, vectors)
        info["seconds"] = time.perf_counter() - t0
        info["gave_up"] = "" if watch is None else watch.gave_up
        return pairs, info
    finally:
        for obj in (eps, T, factor, *vectors):
            if obj is not None:
                obj.destroy()
