"""All solutions of a small (M)EiCP by support enumeration (DESIGN §3).

λ is a solution iff for some support ``S ⊆ J`` the reduced pencil on ``R = F ∪ S`` has
``A_RR ξ = λ B_RR ξ`` with ``ξ_S > 0`` and dual feasibility ``(λB − A)_{J∖S, R} ξ ≥ 0``.
Every ``S`` is visited (``2^|J|`` of them), so the list is complete — and an empty list in a
λ window proves that the window holds no solution.

Speed: supports of one size are solved together as a stack (NumPy's batched LAPACK): for
symmetric A with SPD B by a batched Cholesky transform and ``eigh``, otherwise by the
batched standard problem ``B_RR⁻¹A_RR`` (``eig``).  Only sign-feasible eigenvectors reach
the dual test.  Supports whose reduced pencil has a repeated eigenvalue or a singular or
ill-conditioned ``B_RR`` (condition estimate above ``COND_LIMIT``) are redone one by one:
the eigenspace is searched for a feasible vector by a linear program (a repeated
eigenvalue's arbitrary eigenvector basis must not hide a solution), and the pencil is
solved by QZ (``scipy.linalg.eig``), not through ``B_RR⁻¹``.

Under MPI (``comm`` with several ranks) the supports are dealt round-robin to the ranks and
the solutions gathered on every rank.
"""

from __future__ import annotations

import itertools
import time

import numpy as np
import scipy.linalg
from scipy.optimize import linprog

from ..core.errors import ProblemError
from ..core.validation import is_symmetric
from .problem import DEFAULT_TOL, EiCPProblem, EiCPResult, EiCPSolution, certify_batch, lam_floor

MAX_J = 24
#: supports solved per stack (bounds memory: BATCH · |R|² doubles several times)
BATCH = 20000


#: supports whose B_RR has a larger condition estimate are solved by QZ (scipy.linalg.eig
#: on the pencil), not through B_RR⁻¹: a 1e-13 singular value lost solutions in 34 of 200
#: random 5 × 5 problems that way
COND_LIMIT = 1e8


def _norm_inf(X: np.ndarray) -> np.ndarray:
    """‖X_b‖∞ of each matrix of a stack."""
    return np.abs(X).sum(axis=2).max(axis=1)


def _distinct(values: np.ndarray) -> np.ndarray:
    """Sorted values with near-duplicates (relative 1e-10) merged into their mean."""
    if values.size == 0:
        return values
    groups = np.split(values, np.flatnonzero(np.diff(values) > 1e-10 * np.maximum(1.0, np.abs(values[1:]))) + 1)
    return np.array([g.mean() for g in groups])


def _combinations(J, k, rank, size):
    for idx, S in enumerate(itertools.combinations(J, k)):
        if idx % size == rank:
            yield S


def _batches(iterable, n):
    it = iter(iterable)
    while True:
        chunk = list(itertools.islice(it, n))
        if not chunk:
            return
        yield chunk


class _Enumerator:
    def __init__(self, problem: EiCPProblem, tol: float, lam_min, lam_max):
        self.problem = problem
        self.A, self.B = problem.dense()
        self.J, self.F = problem.J, problem.F
        self.symmetric = is_symmetric(self.A, 1e-13) and is_symmetric(self.B, 1e-13)
        self.diagonal_B = not np.any(self.B - np.diag(np.diagonal(self.B)))
        self.tol = tol
        self.lam_min = -np.inf if lam_min is None else lam_min
        self.lam_max = np.inf if lam_max is None else lam_max
        self.scales = problem.scales()
        self.rows: list = []
        self.seen: set = set()
        self.eigen_solves = 0
        self.slow_path = 0

    # -- one stack of supports of equal size ------------------------------------------
    def run_stack(self, supports: list[tuple]) -> None:
        F = self.F
        R = np.array([np.concatenate([F, np.array(S, dtype=np.int64)]) for S in supports])
        if R.shape[1] == 0:
            return
        k = R.shape[1]
        AR = self.A[R[:, :, None], R[:, None, :]]
        BR = self.B[R[:, :, None], R[:, None, :]]
        self.eigen_solves += len(supports)
        slow = np.zeros(len(supports), dtype=bool)
        if self.symmetric:
            try:
                L = np.linalg.cholesky(BR)
                Linv = np.linalg.inv(L)
                slow |= (_norm_inf(L) * _norm_inf(Linv)) ** 2 > COND_LIMIT  # ≈ cond(B_RR)
                C = Linv @ AR @ np.swapaxes(Linv, 1, 2)
                lam, Y = np.linalg.eigh(0.5 * (C + np.swapaxes(C, 1, 2)))
                V = np.swapaxes(Linv, 1, 2) @ Y
            except np.linalg.LinAlgError:
                return self._one_by_one(supports)
        else:
            try:
                if self.diagonal_B:  # B_RR⁻¹A_RR by row scaling (batched solves are slow
                    #                   under a threaded BLAS)
                    Bd = np.diagonal(BR, axis1=1, axis2=2)
                    if np.any(Bd == 0):
                        raise np.linalg.LinAlgError("singular diagonal B_RR")
                    slow |= np.abs(Bd).max(axis=1) > COND_LIMIT * np.abs(Bd).min(axis=1)
                    lam, V = np.linalg.eig(AR / Bd[:, :, None])
                else:
                    # B_RR⁻¹A_RR loses the finite eigenvalues when B_RR is nearly singular
                    # (no error is raised: the "proof" would miss solutions); those supports
                    # go to the QZ path of _one_support
                    Binv = np.linalg.inv(BR)
                    slow |= _norm_inf(BR) * _norm_inf(Binv) > COND_LIMIT
                    lam, V = np.linalg.eig(Binv @ AR)
            except np.linalg.LinAlgError:
                return self._one_by_one(supports)
            real = np.abs(lam.imag) <= 1e-10 * np.maximum(1.0, np.abs(lam.real))
            lam = np.where(real, lam.real, np.nan)
            V = V.real
        # repeated eigenvalues: redo those supports with the LP over the eigenspace
        srt = np.sort(np.where(np.isnan(lam), np.inf, lam), axis=1)
        if k > 1:
            with np.errstate(invalid="ignore"):  # inf − inf where complex pairs were masked
                gaps = np.diff(srt, axis=1)
            scale = np.maximum(1.0, np.abs(srt[:, 1:]))
            slow |= np.any(np.isfinite(gaps) & (gaps <= 1e-8 * scale), axis=1)
        nF = F.size
        # sign test on the S part: all > 0 or all < 0 (S empty: any sign)
        if k > nF:
            VS = V[:, nF:, :]
            mn, mx = VS.min(axis=1), VS.max(axis=1)
            vmax = np.abs(V).max(axis=1)
            sign_ok = (mn > 1e-12 * vmax) | (mx < -1e-12 * vmax)
        else:
            sign_ok = np.ones(lam.shape, dtype=bool)
        window = (lam >= self.lam_min - self.tol) & (lam <= self.lam_max + self.tol)
        cand = sign_ok & window & np.isfinite(lam) & ~slow[:, None]
        cs, ii = np.nonzero(cand)
        if cs.size:
            X = np.zeros((cs.size, self.problem.n))
            np.put_along_axis(X, R[cs], V[cs, :, ii], axis=1)
            self._accept(lam[cs, ii], X)
        for c in np.flatnonzero(slow):
            self._one_support(R[c], k - nF)

    def _one_by_one(self, supports):
        for S in supports:
            R = np.concatenate([self.F, np.array(S, dtype=np.int64)])
            self._one_support(R, len(S))

    # -- slow path: one support, exact handling of repeated eigenvalues -------------------
    def _one_support(self, R: np.ndarray, nS: int) -> None:
        self.slow_path += 1
        AR, BR = self.A[np.ix_(R, R)], self.B[np.ix_(R, R)]
        lam, V = scipy.linalg.eig(AR, BR)
        finite = np.isfinite(lam) & (np.abs(lam.imag) <= 1e-10 * np.maximum(1.0, np.abs(lam.real)))
        values = _distinct(np.sort(lam.real[finite]))
        nF = self.F.size
        out = np.setdiff1d(self.J, R[nF:])
        scale_A, scale_B = self.scales
        for value in values:
            if not (self.lam_min - self.tol <= value <= self.lam_max + self.tol):
                continue
            # eigenspace basis: null space of (A_RR − λB_RR), to the pencil's scale (an
            # absolute threshold: a relative one is meaningless for a 1 × 1 block)
            Mv = AR - value * BR
            _, sv, Vh = np.linalg.svd(Mv)
            basis = Vh[sv <= 1e-9 * (scale_A + abs(value) * scale_B)].T
            if basis.shape[1] == 0:
                continue
            if basis.shape[1] == 1:
                vecs = [basis[:, 0], -basis[:, 0]]
            else:  # LP: ξ = Bc, ξ_S ≥ 1, (λB − A)_{out,R} ξ ≥ 0
                rows = (value * self.B - self.A)[np.ix_(out, R)] @ basis
                A_ub = [-basis[nF:]] if nS else []
                b_ub = [-np.ones(nS)] if nS else []
                if out.size:
                    A_ub.append(-rows)
                    b_ub.append(np.zeros(out.size))
                if not A_ub:
                    vecs = [basis[:, 0]]
                else:
                    res = linprog(np.zeros(basis.shape[1]), A_ub=np.vstack(A_ub), b_ub=np.concatenate(b_ub),
                                  bounds=[(None, None)] * basis.shape[1], method="highs")
                    vecs = [basis @ res.x] if res.status == 0 else []
            for xi in vecs:
                if nS and xi[nF:].min() <= 0:
                    continue
                x = np.zeros(self.problem.n)
                x[R] = xi
                self._accept(np.array([value]), x[None, :])

    def _accept(self, lams: np.ndarray, X: np.ndarray) -> None:
        """Certify a stack of candidates; keep the passing ones not seen before (a support
        gives one solution per eigenvalue; ±ξ on an empty support are one solution)."""
        X, W, in_support, res = certify_batch(self.problem, lams, X, self.scales)
        # the windows above keep a slack so that no candidate is lost to rounding, but a
        # reported solution must lie in [lam_min, lam_max] up to rounding: e.g. σ = −5e-11
        # just below μ_c is not a divergence mode (failure-map finding, issue 7), while an
        # exact σ = 0 computed as −2e-15 is one
        inside = (lams >= lam_floor(self.lam_min, self.scales)) & (lams <= self.lam_max)
        for r in np.flatnonzero((res <= self.tol) & inside):
            key = (in_support[r].tobytes(), float(f"{lams[r]:.9g}"))
            if key in self.seen:
                continue
            self.seen.add(key)
            self.rows.append((lams[r], X[r], W[r], in_support[r], res[r]))

    def arrays(self):
        """The accepted solutions as stacked arrays (cheap to gather across ranks)."""
        n, nJ = self.problem.n, self.J.size
        if not self.rows:
            return np.zeros(0), np.zeros((0, n)), np.zeros((0, n)), np.zeros((0, nJ), bool), np.zeros(0)
        lams, X, W, masks, res = zip(*self.rows)
        return np.array(lams), np.array(X), np.array(W), np.array(masks), np.array(res)


def enumerate_eicp(problem: EiCPProblem, *, tol: float = DEFAULT_TOL, lam_min=None, lam_max=None,
                   max_j: int = MAX_J, comm=None, **_ignored) -> EiCPResult:
    """Every solution with ``lam_min ≤ λ ≤ lam_max``; collective on ``comm`` if given."""
    J = problem.J
    if J.size > max_j:
        raise ProblemError(f"enumerate visits 2^|J| supports: |J| = {J.size} > max_j = {max_j}")
    if problem.n - J.size > 2000:
        raise ProblemError(f"enumerate solves dense pencils of size |F| + |S|: |F| = {problem.n - J.size} is too large")
    if problem.distributed:
        # gathered once (collective); from here on every rank works on its own supports
        problem = EiCPProblem.from_data(*problem.dense(), J=problem.J)
    rank, size = (0, 1) if comm is None else (comm.Get_rank(), comm.Get_size())
    t0 = time.perf_counter()
    e = _Enumerator(problem, tol, lam_min, lam_max)
    for k in range(J.size + 1):
        for chunk in _batches(_combinations(J, k, rank, size), BATCH):
            e.run_stack(chunk)
    lams, X, W, masks, res = e.arrays()
    solves, slow = e.eigen_solves, e.slow_path
    if size > 1:
        parts = comm.allgather((lams, X, W, masks, res))
        lams, X, W, masks, res = (np.concatenate([p[k] for p in parts]) for k in range(5))
        solves = comm.allreduce(solves)
        slow = comm.allreduce(slow)
    order = np.lexsort((np.arange(lams.size), -lams))
    found = [EiCPSolution(float(lams[r]), X[r], W[r], J[masks[r]], float(res[r])) for r in order]
    result = EiCPResult(method="enumerate", solutions=found, iterations=solves)
    result.coverage = {"supports": 2 ** J.size, "eigen_solves": solves, "one_by_one": slow, "ranks": size,
                       "window": (lam_min, lam_max)}
    result.timings["solve"] = time.perf_counter() - t0
    window = "" if lam_min is None and lam_max is None else f" in [{lam_min}, {lam_max}]"
    if found:
        result.status = "solved"
        result.message = f"{len(found)} solution(s){window}; all {2 ** J.size} supports visited"
    else:
        result.status = "no_solution"
        result.message = (f"no solution{window}: all {2 ** J.size} supports visited, none gives a "
                          f"real eigenpair with x_S > 0 and w_J∖S ≥ 0 (tolerance {tol:.0e})")
    return result
