"""All solutions of a small (M)EiCP by support enumeration (docs/design.md §4.2).

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

Scale and conditioning (:mod:`meicp.eicp.scaling`): the supports are solved on the pencil
equilibrated by powers of two (Ruiz on |B|, then max|Ã| = max|B̃| = 1), λ mapped back
exactly, and every candidate certified row-wise on the original (A, B).  Eigenvalues are
only resolved beyond the rounding of the matrix they come from: where the window reaches
the zone ``|λ̃| ≤ ZONE·‖C‖`` and a support has an eigenvalue in it, the support is redone
by QZ on the pencil equilibrated on |A| instead (a second pass: with one layer's density
1e-16 the first pass resolves the light layer's modes and the second the heavy one's).
A candidate that is sign-feasible but whose eigen-residual fails is polished by Newton's
method; if it still fails and its violations are no larger than its own inaccuracy, it may
hide a solution: it is *unverified*.  ``no_solution`` is claimed only with no unverified
candidate and no λ beyond double precision in the window; otherwise the status is
``undecided`` with the reason.  An eigenvalue whose β (QZ) is at rounding level,
``|β| ≤ INFINITE_FACTOR·k·eps·‖B_RR‖``, is an infinite eigenvalue of a singular B_RR, not a
solution; ``coverage["infinite"]`` counts them.  Limit: a pencil with three or more widely
separated scales can have eigenvalues that neither pass resolves and that are not
sign-feasible in either; they are not detected.

Under MPI (``comm`` with several ranks) the supports are dealt round-robin to the ranks and
the solutions gathered on every rank.

Memory: the supports of one size are solved in stacks of :func:`stack_size` supports, so
that a stack's arrays stay within :data:`STACK_BYTES` (256 MiB) whatever the order of the
pencils; beyond it the enumeration holds the dense pencil and the certified solutions.
"""

from __future__ import annotations

import itertools
import math
import time

import numpy as np
import scipy.linalg
from scipy.optimize import linprog

from ..core import limits
from ..core.errors import ProblemError
from ..core.progress import Progress
from ..core.threads import dense_phase
from ..core.validation import is_symmetric
from .problem import DEFAULT_TOL, EiCPProblem, EiCPResult, EiCPSolution, certificate_parts, lam_floor
from .scaling import PencilScaling, refine_pair

#: supports solved per stack at most (small pencils: the batched LAPACK calls' overhead)
BATCH = 20000
#: bytes the arrays of one stack may take (:func:`stack_size`): the enumeration's working
#: memory, whatever the order of its pencils.  With BATCH supports per stack whatever their
#: order, 17 pairs on 85 retained DOFs (stacks of order 76) held 5.8 GB; a stack's time is
#: per support (one LAPACK call each), so smaller stacks cost no time
STACK_BYTES = 256 * 2 ** 20
#: |R| × |R| double arrays a stack holds per support at its peak (A_RR, B_RR, the Cholesky
#: factor, its inverse, the transformed matrix, its symmetric part, the eigenvectors before
#: and after the back-transform): 8.1 measured with tracemalloc at order 73, 6.1 for the
#: nonsymmetric path; 10 leaves room for the candidates' certificates
STACK_ARRAYS = 10


#: supports whose B_RR has a larger condition estimate are solved by QZ (scipy.linalg.eig
#: on the pencil), not through B_RR⁻¹: a 1e-13 singular value lost solutions in 34 of 200
#: random 5 × 5 problems that way
COND_LIMIT = 1e8
#: a candidate failing its eigen-residual is unverified (it may hide a solution) when its
#: sign and dual violations are at most this many times that residual
UNVERIFIED_FACTOR = 1e3
#: candidates polished by Newton per enumeration at most (each a dense solve of order |R|)
REFINE_BUDGET = 1000
#: an eigenvalue of the scaled pencil whose β is within INFINITE_FACTOR·k·eps·‖B_RR‖ is infinite
INFINITE_FACTOR = 100.0
#: eigenvalues within ZONE·‖C‖ of 0 (C the matrix they are computed from) are rounding
#: noise or too inaccurate to certify (their error is about k·eps·‖C‖): where the window
#: reaches them, a second pass with A balanced redoes the support
ZONE = 1e-6


def _norm_inf(X: np.ndarray) -> np.ndarray:
    """‖X_b‖∞ of each matrix of a stack."""
    return np.abs(X).sum(axis=2).max(axis=1)


def _distinct(values: np.ndarray) -> np.ndarray:
    """Sorted values with near-duplicates (relative 1e-10) merged into their mean."""
    if values.size == 0:
        return values
    groups = np.split(values, np.flatnonzero(np.diff(values) > 1e-10 * np.maximum(1.0, np.abs(values[1:]))) + 1)
    return np.array([g.mean() for g in groups])


def stack_size(order: int) -> int:
    """Supports per stack for reduced pencils of ``order`` |R|: as many as fit in
    :data:`STACK_BYTES` (:data:`STACK_ARRAYS` arrays of order² doubles each), at least one,
    at most :data:`BATCH`."""
    per_support = STACK_ARRAYS * 8 * max(int(order), 1) ** 2
    return int(max(1, min(BATCH, STACK_BYTES // per_support)))


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


class _View:
    """The pencil under one scaling (:class:`PencilScaling`): the matrices the eigenvalues are
    computed from, and the λ window in its units (with a slack that loses nothing to
    rounding; a certified λ is then held to [lam_floor, lam_max] in the original units)."""

    def __init__(self, A, B, balance: str, lam_min: float, lam_max: float):
        self.scaling = PencilScaling(A, B, balance=balance)
        self.A, self.B = self.scaling.A, self.scaling.B
        self.symmetric = is_symmetric(self.A, 1e-13) and is_symmetric(self.B, 1e-13)
        self.diagonal_B = not np.any(self.B - np.diag(np.diagonal(self.B)))
        lo, hi = self.scaling.lam_scaled(lam_min), self.scaling.lam_scaled(lam_max)
        self.window = (lo - 1e-8 * (1.0 + abs(lo)), hi + 1e-8 * (1.0 + abs(hi)))

    def in_window(self, lam):
        return (lam >= self.window[0]) & (lam <= self.window[1])

    def zone_hits_window(self, zone):
        """Whether [−zone, zone] (the λ̃ not resolved) meets the window."""
        return (self.window[0] <= zone) & (self.window[1] >= -zone)


class _Enumerator:
    def __init__(self, problem: EiCPProblem, tol: float, lam_min, lam_max):
        self.problem = problem
        self.A0, self.B0 = problem.dense()
        self.J, self.F = problem.J, problem.F
        self.tol = tol
        self.lam_min = -np.inf if lam_min is None else lam_min
        self.lam_max = np.inf if lam_max is None else lam_max
        # B balanced: λ of every size resolved relative to ‖B̃‖ (the light layer's modes);
        # A balanced, built only for supports that need it: the λ near 0 that the first
        # one cannot resolve (the heavy layer's modes when another is very light)
        self.view = _View(self.A0, self.B0, "B", self.lam_min, self.lam_max)
        self._view_a = None
        self.scales = problem.scales()
        self.floor = lam_floor(self.lam_min, self.scales)
        self.rows: list = []
        self.seen: dict = {}  # support mask → indices into rows
        a, b = self.scales
        self.same_lam = 1e-12 * (a / b if b > 0 else 1.0)  # absolute part of "the same λ"
        self.eigen_solves = 0
        self.slow_path = 0
        self.second_pass = 0
        self.unverified = 0
        self.worst_unverified = 0.0
        self.out_of_range = 0
        self.unsolved = 0  # supports whose QZ did not converge (extreme scaling)
        self.infinite = 0
        self.refined = 0

    @property
    def view_a(self) -> _View:
        if self._view_a is None:
            self._view_a = _View(self.A0, self.B0, "A", self.lam_min, self.lam_max)
        return self._view_a

    # -- one stack of supports of equal size ------------------------------------------
    def run_stack(self, supports: list[tuple]) -> None:
        F, view = self.F, self.view
        R = np.array([np.concatenate([F, np.array(S, dtype=np.int64)]) for S in supports])
        if R.shape[1] == 0:
            return
        k = R.shape[1]
        AR = view.A[R[:, :, None], R[:, None, :]]
        BR = view.B[R[:, :, None], R[:, None, :]]
        self.eigen_solves += len(supports)
        slow = np.zeros(len(supports), dtype=bool)
        if view.symmetric:
            try:
                L = np.linalg.cholesky(BR)
                Linv = np.linalg.inv(L)
                slow |= (_norm_inf(L) * _norm_inf(Linv)) ** 2 > COND_LIMIT  # ≈ cond(B_RR)
                C = Linv @ AR @ np.swapaxes(Linv, 1, 2)
                lam, Y = np.linalg.eigh(0.5 * (C + np.swapaxes(C, 1, 2)))
                V = np.swapaxes(Linv, 1, 2) @ Y
                size = np.abs(lam)
            except np.linalg.LinAlgError:
                return self._one_by_one(supports)
        else:
            try:
                if view.diagonal_B:  # B_RR⁻¹A_RR by row scaling (batched solves are slow
                    #                   under a threaded BLAS)
                    Bd = np.diagonal(BR, axis1=1, axis2=2)
                    if np.any(Bd == 0):
                        raise np.linalg.LinAlgError("singular diagonal B_RR")
                    slow |= np.abs(Bd).max(axis=1) > COND_LIMIT * np.abs(Bd).min(axis=1)
                    C = AR / Bd[:, :, None]
                else:
                    # B_RR⁻¹A_RR loses the finite eigenvalues when B_RR is nearly singular
                    # (no error is raised: the "proof" would miss solutions); those supports
                    # go to the QZ path of _one_support
                    Binv = np.linalg.inv(BR)
                    slow |= _norm_inf(BR) * _norm_inf(Binv) > COND_LIMIT
                    C = Binv @ AR
                lam, V = np.linalg.eig(C)
            except np.linalg.LinAlgError:
                return self._one_by_one(supports)
            size = np.abs(lam)
            real = np.abs(lam.imag) <= 1e-10 * np.maximum(1.0, np.abs(lam.real))
            lam = np.where(real, lam.real, np.nan)
            V = V.real
        # eigenvalues are resolved only beyond the rounding of the matrix they come from:
        # supports with one inside that zone, where the window is, get a second pass
        zone = ZONE * np.abs(C).max(axis=(1, 2))
        unresolved = size <= zone[:, None]
        second = np.any(unresolved, axis=1) & view.zone_hits_window(zone) & ~slow
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
        cand = sign_ok & view.in_window(lam) & np.isfinite(lam) & ~slow[:, None]
        cs, ii = np.nonzero(cand)
        if cs.size:
            X = np.zeros((cs.size, self.problem.n))
            np.put_along_axis(X, R[cs], V[cs, :, ii], axis=1)
            # a candidate the second pass redoes is not counted as unverified here
            self._accept(view.scaling.lam(lam[cs, ii]), view.scaling.x(X), R[cs],
                         countable=~(second[cs] & unresolved[cs, ii]))
        for c in np.flatnonzero(slow):
            self._one_support(view, R[c], k - nF)
        for c in np.flatnonzero(second & ~slow):
            self._one_support(self.view_a, R[c], k - nF)

    def _one_by_one(self, supports):
        for S in supports:
            R = np.concatenate([self.F, np.array(S, dtype=np.int64)])
            self._one_support(self.view, R, len(S))

    # -- slow path: one support, exact handling of repeated eigenvalues -------------------
    def _one_support(self, view: _View, R: np.ndarray, nS: int) -> None:
        first = view is self.view
        self.slow_path += first
        self.second_pass += not first
        AR, BR = view.A[np.ix_(R, R)], view.B[np.ix_(R, R)]
        try:
            (alpha, beta), V = scipy.linalg.eig(AR, BR, homogeneous_eigvals=True)
        except (np.linalg.LinAlgError, ValueError):  # LAPACK's QZ did not converge: this
            self.unsolved += 1                       # support may hide a solution
            return
        eps = np.finfo(float).eps
        # B_RR numerically singular: QZ returns its infinite eigenvalues with β at rounding
        infinite = np.abs(beta) <= INFINITE_FACTOR * R.size * eps * max(np.abs(BR).max(), 1e-300)
        with np.errstate(divide="ignore", invalid="ignore"):
            lam = np.where(infinite, np.inf, alpha / np.where(infinite, 1.0, beta))
        real = np.abs(lam.imag) <= 1e-10 * np.maximum(1.0, np.abs(lam.real))
        self.infinite += int(np.count_nonzero(real & infinite)) if first else 0
        values = _distinct(np.sort(lam.real[real & ~infinite]))
        # λ near 0 are resolved to the rounding of A_RR relative to B_RR; on the first
        # pass they are left to the second (A balanced) when the window reaches them
        zone = ZONE * np.abs(AR).max() / max(np.abs(BR).max(), 1e-300)
        second = first and bool(np.any(np.abs(lam[~infinite]) <= zone)) and bool(view.zone_hits_window(zone))
        if second:
            self._one_support(self.view_a, R, nS)
        nF = self.F.size
        out = np.setdiff1d(self.J, R[nF:])
        scale_A, scale_B = np.abs(view.A).max(), np.abs(view.B).max()
        for value in values:
            if not view.in_window(value):
                continue
            countable = not (second and abs(value) <= zone)  # the second pass redoes these
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
                rows = (value * view.B - view.A)[np.ix_(out, R)] @ basis
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
                self._accept(view.scaling.lam(np.array([value])), view.scaling.x(x), R[None, :],
                             countable=np.array([countable]))

    def _accept(self, lams: np.ndarray, X: np.ndarray, R: np.ndarray, countable: np.ndarray) -> None:
        """Certify a stack of candidates (λ, x of the original problem, found on the reduced
        sets R) on the original (A, B), polish the ones whose eigen-residual fails, and keep
        the passing ones not seen before (a support gives one solution per eigenvalue; ±ξ on
        an empty support are one solution).  What still fails but cannot be excluded is
        counted as unverified (where ``countable``: not when a second pass redoes it)."""
        lams = np.array(lams, dtype=np.float64)
        X, W, in_support, parts = certificate_parts(self.problem, lams, X)
        res = np.maximum.reduce(list(parts.values()))
        # the windows above keep a slack so that no candidate is lost to rounding, but a
        # reported solution must lie in [lam_min, lam_max] up to rounding: e.g. σ = −5e-11
        # just below μ_c is not a divergence mode (failure-map finding, issue 7), while an
        # exact σ = 0 computed as −2e-15 is one
        inside = (lams >= self.floor) & (lams <= self.lam_max)
        # a failing candidate may hide a solution when it is no more violated than it is
        # inaccurate: Newton-polish those, then judge again
        for r in np.flatnonzero(self._doubtful(res, parts) & np.isfinite(lams)):
            if self.refined >= REFINE_BUDGET:
                break
            self.refined += 1
            polished = refine_pair(self.A0, self.B0, R[r], lams[r], X[r])
            if polished is None:
                continue
            x1, w1, s1, p1 = certificate_parts(self.problem, np.array([polished[0]]), polished[1][None, :])
            r1 = max(v[0] for v in p1.values())
            if r1 < res[r]:
                lams[r], X[r], W[r], in_support[r], res[r] = polished[0], x1[0], w1[0], s1[0], r1
                inside[r] = self.floor <= polished[0] <= self.lam_max
                for key in parts:
                    parts[key][r] = p1[key][0]
        for r in np.flatnonzero((res <= self.tol) & inside):
            self._keep((lams[r], X[r], W[r], in_support[r], res[r]))
        doubtful = self._doubtful(res, parts) & inside & countable & np.isfinite(lams)
        self.unverified += int(np.count_nonzero(doubtful))
        if doubtful.any():
            self.worst_unverified = max(self.worst_unverified, float(parts["eigen"][doubtful].max()))
        # λ beyond double precision in the window: overflow (±inf), or underflow (NaN, ≈ 0)
        beyond = (np.isinf(lams) & inside) | (np.isnan(lams) & (self.floor <= 0.0 <= self.lam_max))
        self.out_of_range += int(np.count_nonzero(beyond & countable))

    def _keep(self, row) -> None:
        """One solution per (support, λ): a support gives one solution per eigenvalue, ±ξ on
        an empty support are one solution, and the two passes may both find it (λ equal to
        1e-8 relative: then the better certified one stays)."""
        lam, res = row[0], row[4]
        mates = self.seen.setdefault(row[3].tobytes(), [])
        for k in mates:
            other = self.rows[k]
            if abs(other[0] - lam) <= 1e-8 * max(abs(other[0]), abs(lam)) + self.same_lam:
                if res < other[4]:
                    self.rows[k] = row
                return
        mates.append(len(self.rows))
        self.rows.append(row)

    def _doubtful(self, res, parts):
        """Failing candidates whose eigenpair is not resolved and whose sign and dual
        violations are within what that inaccuracy could cause."""
        with np.errstate(invalid="ignore"):
            return (res > self.tol) & (parts["eigen"] > self.tol) & \
                (np.maximum(parts["sign"], parts["dual"]) <= UNVERIFIED_FACTOR * parts["eigen"])

    def arrays(self):
        """The accepted solutions as stacked arrays (cheap to gather across ranks)."""
        n, nJ = self.problem.n, self.J.size
        if not self.rows:
            return np.zeros(0), np.zeros((0, n)), np.zeros((0, n)), np.zeros((0, nJ), bool), np.zeros(0)
        lams, X, W, masks, res = zip(*self.rows)
        return np.array(lams), np.array(X), np.array(W), np.array(masks), np.array(res)


def enumerate_eicp(problem: EiCPProblem, *, tol: float = DEFAULT_TOL, lam_min=None, lam_max=None,
                   max_j: int | None = None, comm=None, **_ignored) -> EiCPResult:
    """Every solution with ``lam_min ≤ λ ≤ lam_max``; collective on ``comm`` if given."""
    J = problem.J
    max_j = limits.EICP_MAX_J if max_j is None else max_j
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
    # this rank's share of the supports, and their cost for the estimate of the time left: a
    # support of size k is a dense eigen-solve of order |F| + k, batched, whose time grows
    # about linearly with the order (the batches' overhead), not as its cube
    # (docs/benchmarks-notes.md, eicp)
    share = [len(range(rank, math.comb(J.size, k), size)) for k in range(J.size + 1)]
    cost = [float(share[k]) * (problem.F.size + k) for k in range(J.size + 1)]
    progress = Progress("enumeration" + (f" (rank 0's share on {size} ranks)" if size > 1 else ""),
                        total=sum(share), unit="supports", work=sum(cost))
    done, work = 0, 0.0
    with dense_phase():
        for k in range(J.size + 1):
            for chunk in _batches(_combinations(J, k, rank, size), stack_size(problem.F.size + k)):
                e.run_stack(chunk)
                done += len(chunk)
                work += len(chunk) * float(problem.F.size + k)
                progress.update(done, work, f"support size {k} of {J.size}, {len(e.rows)} solution(s) so far")
    lams, X, W, masks, res = e.arrays()
    counts = np.array([e.eigen_solves, e.slow_path, e.unverified, e.out_of_range, e.infinite, e.refined,
                       e.second_pass, e.unsolved])
    worst = e.worst_unverified
    if size > 1:
        parts = comm.allgather((lams, X, W, masks, res))
        lams, X, W, masks, res = (np.concatenate([p[k] for p in parts]) for k in range(5))
        counts = comm.allreduce(counts)
        worst = comm.allreduce(worst, op=_max_op())
    solves, slow, unverified, out_of_range, infinite, refined, second, unsolved = (int(c) for c in counts)
    order = np.lexsort((np.arange(lams.size), -lams))
    found = [EiCPSolution(float(lams[r]), X[r], W[r], J[masks[r]], float(res[r])) for r in order]
    result = EiCPResult(method="enumerate", solutions=found, iterations=solves)
    result.coverage = {"supports": 2 ** J.size, "eigen_solves": solves, "one_by_one": slow, "ranks": size,
                       "window": (lam_min, lam_max), "unverified": unverified, "out_of_range": out_of_range,
                       "infinite": infinite, "refined": refined, "second_pass": second, "unsolved": unsolved,
                       "lam_exponent": e.view.scaling.lam_exponent}
    result.timings["solve"] = time.perf_counter() - t0
    window = "" if lam_min is None and lam_max is None else f" in [{lam_min}, {lam_max}]"
    doubts = []
    if unverified:
        doubts.append(f"{unverified} sign-feasible candidate(s) whose eigenpair could not be resolved "
                      f"(row-wise residual up to {worst:.1e} after Newton polishing: the pencil is too badly "
                      f"conditioned on their supports) may hide solutions")
    if unsolved:
        doubts.append(f"the QZ eigen-solve (LAPACK) did not converge on {unsolved} support(s)")
    if out_of_range:
        doubts.append(f"{out_of_range} candidate(s) have λ beyond double precision (λ = 2^{e.view.scaling.lam_exponent}"
                      f"·λ̃ of the scaled pencil overflows or underflows)")
    if found:
        result.status = "solved"
        result.message = f"{len(found)} solution(s){window}; all {2 ** J.size} supports visited"
        if doubts:
            result.message += "; the list may be incomplete: " + "; ".join(doubts)
    elif doubts:
        result.status = "undecided"
        result.message = (f"no certified solution{window}, but this is not a proof that there is none: "
                          + "; ".join(doubts))
    else:
        result.status = "no_solution"
        result.message = (f"no solution{window}: all {2 ** J.size} supports visited, none gives a "
                          f"real eigenpair with x_S > 0 and w_J∖S ≥ 0 (tolerance {tol:.0e})")
    return result


def _max_op():
    from mpi4py import MPI

    return MPI.MAX
