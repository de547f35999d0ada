"""Symmetric (M)EiCP as the stationary points of the Rayleigh quotient (seed 000; Júdice et al.).

Why this works.  For symmetric A, B with B SPD let ``r(x) = xᵀAx / xᵀBx``; its gradient
``∇r(x) = 2 (A − r(x) B) x / xᵀBx`` is orthogonal to x (r is homogeneous of degree 0).

* EiCP (J = all), feasible set the simplex Δ = {x ≥ 0, eᵀx = 1}.  The KKT conditions of
  max r (of min r) on Δ read ``∇r(x) = μe − ν`` (``μe + ν``) with ``ν ≥ 0, νᵀx = 0``;
  multiplying by xᵀ gives μ = 0, hence ``w = (r B − A) x = (xᵀBx / 2) ν`` (``−(xᵀBx / 2) ν``)
  — for max r, ``w ≥ 0, xᵀw = 0``:
  (λ, x) = (r(x), x) solves the EiCP, and conversely every EiCP solution is a KKT point of
  *max* r.  The sign matters: KKT points of *min* r have ``w ≤ 0`` off the support, so
  they solve this EiCP only where w vanishes there — generically when the support is full
  (x_J > 0), e.g. the full-support λ_min(B⁻¹A) of a Z-matrix A.  ``sense="min"`` is kept
  for those; measured on 300 random problems (n ≤ 6) it found nothing in 188 of them.
* MEiCP (free set F ≠ ∅), feasible set the cone K = {x_J ≥ 0} without 0.  The same
  argument with the multiplier ν supported on J gives ``w_F = 0``, ``w_J ≥ 0 ⊥ x_J``:
  KKT points of max r on K (any scaling) are exactly the MEiCP solutions, including
  those with x_J = 0.  We run the projected method on the (convex) cone and, because r does
  not see the scale, rescale each iterate to ``‖x‖₂ = 1`` so it can neither vanish nor blow up.

Method: spectral projected gradient (Birgin–Martínez–Raydan, nonmonotone line search;
projection onto Δ by the sort-based algorithm, onto K by clipping x_J) ascending r
(``sense="max"``; ``"min"`` descends, ``"both"`` does both) from several starts.  SPG only
has to find the right support S: each limit is *polished* by solving the reduced
symmetric-definite pencil ``A_RR ξ = λ B_RR ξ`` on ``R = F ∪ S`` and keeping eigenpairs
with ``ξ_S > 0`` — exact up to rounding, so the certificates come out near 1e-14.  Only
pairs that pass :func:`certify_pair` are returned.

Matrix-vector products only during SPG, so SciPy sparse A, B scale; polishing is dense for
``|R| ≤ 2000`` and uses ``eigsh`` (shift-invert at r(x)) above that.
"""

from __future__ import annotations

import time
from collections import deque

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
from scipy.sparse.linalg import eigsh

from ..core import limits
from ..core.errors import ProblemError
from ..core.matrix import to_dense, to_scipy
from ..core.validation import check_spd, check_symmetric
from .problem import DEFAULT_TOL, EiCPProblem, EiCPResult, EiCPSolution, certify_pair
from .scaling import normalised, restore, scaled_value

#: how many aligned eigenpairs of the reduced pencil one polish certifies at most
POLISH_CANDIDATES = 3
#: SPG iterations with an unchanged support before a polish is tried mid-run
SUPPORT_PATIENCE = 10


# ------------------------------------------------------------------------------------------
# public entry point
# ------------------------------------------------------------------------------------------


def rayleigh(problem: EiCPProblem, *, tol: float = DEFAULT_TOL, max_iter: int = 5000,
             starts=None, n_starts: int = 8, seed: int = 0, lam_min: float | None = None,
             sense: str = "max", spg_tol: float = 1e-9, memory: int = 10, **_) -> EiCPResult:
    """Certified (M)EiCP solutions of a symmetric problem (B SPD) by SPG on the Rayleigh quotient.

    starts: optional list of start vectors (projected onto the feasible set); otherwise
        ``n_starts`` starts: the uniform vector, vertices e_i with the largest (``sense="min"``:
        smallest) ``A_ii / B_ii``, and random points (``seed``).
    sense: ``"max"`` ascends r: its limits are KKT points of max r, which are exactly the
        solutions (local maxima of r on the feasible set; saddles only by luck, through the
        polish of supports met on the way).  ``"min"`` descends: its limits are solutions
        only when they have full support (see the module docstring).  ``"both"``: both.
    max_iter: SPG iterations per start; ``spg_tol``: relative stationarity at which SPG stops
        and hands its support to the polisher.  ``lam_min`` drops solutions with λ < lam_min.

    Returns an :class:`EiCPResult` whose ``solutions`` are distinct, certified to ``tol``, and
    sorted largest λ first; uncertified end points go to ``candidates``.
    """
    t0 = time.perf_counter()
    if sense not in ("max", "min", "both"):
        raise ProblemError(f"sense must be 'max', 'min' or 'both', got {sense!r}")
    scaled, E = normalised(problem)
    if E is not None:  # A·1e300, B·1e-300: quotients would overflow; solve scaled, map λ back
        result = rayleigh(scaled, tol=tol, max_iter=max_iter, starts=starts, n_starts=n_starts, seed=seed,
                          lam_min=scaled_value(lam_min, E), sense=sense, spg_tol=spg_tol, memory=memory)
        return restore(problem, scaled, result, E, tol)
    A, B = _serial_symmetric_pencil(problem)
    scales = problem.scales()
    quotient = _Quotient(A, B)
    feasible = _Simplex() if problem.J.size == problem.n else _Cone(problem.J)
    senses = (1.0, -1.0) if sense == "both" else ((1.0,) if sense == "max" else (-1.0,))

    found: list[EiCPSolution] = []
    candidates: list[EiCPSolution] = []
    total_iterations, polishes, runs = 0, 0, 0
    rng = np.random.default_rng(seed)
    for direction in senses:
        start_list = (list(starts) if starts is not None
                      else _default_starts(problem, A, B, n_starts, direction, rng))
        for x0 in start_list:
            x0 = feasible.start(np.asarray(x0, dtype=np.float64).ravel(), problem.n)
            if x0 is None:
                continue
            runs += 1
            polisher = _Polisher(problem, A, B, scales, tol)
            x, its = _spg(quotient, feasible, x0, direction, problem, scales,
                          max_iter=max_iter, spg_tol=spg_tol, memory=memory, polisher=polisher)
            total_iterations += its
            polisher.try_support(x, final=True)
            polishes += polisher.calls
            _add_distinct(found, polisher.certified, scales)
            if not polisher.certified:
                candidates.append(certify_pair(problem, quotient.value(x), x, scales))

    found.sort(key=lambda s: -s.lam)
    below = [s for s in found if lam_min is not None and s.lam < lam_min]
    solutions = [s for s in found if lam_min is None or s.lam >= lam_min]
    coverage = {"starts": runs, "senses": sense, "polishes": polishes,
                "certified_before_filter": len(found), "feasible_set": feasible.name}
    result = EiCPResult(method="rayleigh", solutions=solutions, candidates=candidates + below,
                        iterations=total_iterations, coverage=coverage,
                        timings={"total": time.perf_counter() - t0})
    if solutions:
        result.status = "solved"
        result.residual = max(s.residual for s in solutions)
        result.message = (f"{len(solutions)} distinct certified stationary point(s) of the "
                          f"Rayleigh quotient from {runs} start(s)")
    elif below:
        result.status = "not_found"
        result.message = (f"{len(below)} certified solution(s) found, none with λ ≥ {lam_min:g} "
                          f"(they are in candidates); rayleigh does not prove there is none")
    else:
        best = min((c.residual for c in candidates), default=float("nan"))
        result.status = "not_converged"
        result.message = (f"no start reached a certifiable stationary point within {max_iter} "
                          f"SPG iterations (best residual {best:.2e} > tol {tol:g})")
    return result


# ------------------------------------------------------------------------------------------
# input
# ------------------------------------------------------------------------------------------


def _serial_symmetric_pencil(problem: EiCPProblem):
    """(A, B) as ndarray / CSR after the symmetric-definite checks this method relies on."""
    A, B = problem.A, problem.B
    if problem.distributed:
        A, B = to_scipy(A), to_scipy(B)
    try:
        check_symmetric(A, "A")
    except ProblemError as exc:
        raise ProblemError(f"rayleigh needs a symmetric problem: {exc}") from None
    try:
        check_spd(B, "B")
    except ProblemError as exc:
        raise ProblemError(f"rayleigh needs B symmetric positive definite: {exc}") from None
    return A, B


# ------------------------------------------------------------------------------------------
# the quotient and the two feasible sets
# ------------------------------------------------------------------------------------------


class _Quotient:
    """r(x) = xᵀAx / xᵀBx with its gradient, by two matrix-vector products."""

    def __init__(self, A, B):
        self.A, self.B = A, B

    def evaluate(self, x):
        Ax, Bx = self.A @ x, self.B @ x
        xBx = float(x @ Bx)
        r = float(x @ Ax) / xBx
        return r, 2.0 * (Ax - r * Bx) / xBx, Ax, Bx

    def value(self, x) -> float:
        return float(x @ (self.A @ x)) / float(x @ (self.B @ x))


def project_simplex(v: np.ndarray) -> np.ndarray:
    """Euclidean projection onto {x ≥ 0, eᵀx = 1} by sorting (Held et al.; Duchi et al.)."""
    v = v - v.max()  # P(v + ce) = P(v); the shift keeps huge |v| from cancelling θ
    u = np.sort(v)[::-1]
    cumulative = np.cumsum(u) - 1.0
    k = np.arange(1, v.size + 1)
    positive = np.flatnonzero(u - cumulative / k > 0)
    rho = positive[-1] if positive.size else 0  # empty only by rounding at huge |v|
    return np.maximum(v - cumulative[rho] / (rho + 1), 0.0)


class _Simplex:
    """EiCP: the simplex, which excludes 0 and needs no rescaling."""

    name = "simplex"

    def project(self, x):
        return project_simplex(x)

    def rescale(self, x) -> float:
        return 1.0

    def start(self, x0, n):
        """r is scale-free, so a nonnegative start is scaled onto Δ rather than projected."""
        if x0.shape != (n,) or not np.all(np.isfinite(x0)):
            raise ProblemError(f"a start vector must be finite with length {n}")
        clipped = np.maximum(x0, 0.0)
        total = clipped.sum()
        return clipped / total if total > 0 else self.project(x0)


class _Cone:
    """MEiCP: the cone {x_J ≥ 0}; iterates are rescaled to ‖x‖₂ = 1 (r is scale-free)."""

    name = "cone"

    def __init__(self, J):
        self.J = J

    def project(self, x):
        y = x.copy()
        y[self.J] = np.maximum(y[self.J], 0.0)
        return y

    def rescale(self, x) -> float:
        return 1.0 / np.linalg.norm(x)

    def start(self, x0, n):
        if x0.shape != (n,) or not np.all(np.isfinite(x0)):
            raise ProblemError(f"a start vector must be finite with length {n}")
        x = self.project(x0)
        nrm = np.linalg.norm(x)
        return x / nrm if nrm > 0 else None


def _default_starts(problem, A, B, n_starts, direction, rng):
    """Uniform, the most promising vertices (by A_ii / B_ii), then random points."""
    n, J = problem.n, problem.J
    ratio = np.asarray(A.diagonal(), dtype=float) / np.asarray(B.diagonal(), dtype=float)
    uniform = np.zeros(n)
    uniform[J] = 1.0
    if J.size == 0:
        uniform[:] = 1.0
    starts = [uniform]
    n_vertices = min(n, n_starts // 2)
    for i in np.argsort(-direction * ratio, kind="stable")[:n_vertices]:
        e = np.zeros(n)
        e[i] = 1.0
        starts.append(e)
    while len(starts) < n_starts:
        x = rng.standard_normal(n)
        x[J] = np.abs(x[J])
        starts.append(x)
    return starts[:max(n_starts, 1)]


# ------------------------------------------------------------------------------------------
# spectral projected gradient
# ------------------------------------------------------------------------------------------


def _stationarity(problem, scales, x, r, Ax, Bx) -> float:
    """The certificate's residual of (r(x), x) without recomputing products: how far x is
    from being a solution, relative to the matrix scale."""
    nrm = np.abs(x).max()
    w = (r * Bx - Ax) / nrm
    s = max(scales[0] + abs(r) * scales[1], np.finfo(float).tiny)
    J = problem.J
    vanish = np.ones(problem.n, dtype=bool)  # w must vanish on the free set and on supp x_J
    vanish[J] = x[J] > 0.0
    parts = [np.abs(w[vanish]).max() / s if vanish.any() else 0.0]
    if J.size:
        parts.append(max(0.0, -float(w[J].min())) / s)
    return max(parts)


def _spg(quotient, feasible, x, direction, problem, scales, *, max_iter, spg_tol, memory,
         polisher, gamma=1e-4, sigma1=0.1, sigma2=0.9, alpha_min=1e-30, max_reach=1e3):
    """Minimise f = −direction·r on the feasible set (BMR's SPG2).  Returns (x, iterations).

    The spectral step is capped so that ``α‖g‖∞ ≤ max_reach·‖x‖∞``: BMR's α_max = 1e30 (taken
    whenever sᵀy ≤ 0, which is common here since r is not convex) would make the projection
    of ``x − αg`` lose every digit of x; a step this long already reaches the far face.

    Stops at relative stationarity ``spg_tol``, at ``max_iter``, when the line search stalls,
    or early when the polisher certifies a solution on the current, settled support that
    the iterate is already close to (then more SPG steps would only repeat it).
    """
    r, gr, Ax, Bx = quotient.evaluate(x)
    f, g = -direction * r, -direction * gr
    def alpha_max():
        return max_reach * np.abs(x).max() / max(np.abs(g).max(), 1e-300)

    pg = feasible.project(x - g) - x
    alpha = float(np.clip(1.0 / max(np.abs(pg).max(), 1e-300), alpha_min, alpha_max()))
    history = deque([f], maxlen=memory)
    J = problem.J
    support = x[J] > 0
    settled = 0
    for k in range(max_iter):
        if _stationarity(problem, scales, x, r, Ax, Bx) <= spg_tol:
            return x, k
        d = feasible.project(x - alpha * g) - x
        gtd = float(g @ d)
        if not gtd < 0:
            return x, k  # no descent direction left at this precision
        f_ref = max(history)
        t = 1.0
        while True:
            xt = x + t * d
            rt, grt, Axt, Bxt = quotient.evaluate(xt)
            ft = -direction * rt
            if ft <= f_ref + gamma * t * gtd:
                break
            t_quad = -0.5 * t * t * gtd / (ft - f - t * gtd)
            t = t_quad if sigma1 <= t_quad <= sigma2 * t else 0.5 * t
            if t < 1e-20:
                return x, k  # stalled: the polisher decides from here
        c = feasible.rescale(xt)
        xt, Axt, Bxt, grt = c * xt, c * Axt, c * Bxt, grt / c
        gt = -direction * grt
        s, y = xt - x, gt - g
        sty = float(s @ y)
        x, r, Ax, Bx, f, g = xt, rt, Axt, Bxt, ft, gt
        alpha = alpha_max() if sty <= 0 else float(np.clip(float(s @ s) / sty, alpha_min,
                                                           alpha_max()))
        history.append(f)
        new_support = x[J] > 0
        settled = settled + 1 if np.array_equal(new_support, support) else 0
        support = new_support
        if settled == SUPPORT_PATIENCE and polisher.try_support(x):
            return x, k + 1
    return x, max_iter


# ------------------------------------------------------------------------------------------
# polishing on the support
# ------------------------------------------------------------------------------------------


class _Polisher:
    """Turns an SPG iterate into exact solutions: eigenpairs of the reduced pencil on
    ``R = F ∪ S`` (S the support of x_J) with ``ξ_S > 0``, certified by :func:`certify_pair`.

    The supports tried are the exact positive support and supports at small relative
    thresholds, so a component still on its way to 0 does not spoil the polish.
    """

    def __init__(self, problem, A, B, scales, tol):
        self.problem, self.A, self.B, self.scales, self.tol = problem, A, B, scales, tol
        self.certified: list[EiCPSolution] = []
        self.tried: set = set()
        self.calls = 0

    def try_support(self, x, final: bool = False) -> bool:
        """Polish on the supports of x; True when a certified solution is close to x."""
        J, F = self.problem.J, self.problem.F
        top = np.abs(x).max()
        thresholds = (0.0, 1e-10, 1e-7, 1e-4) if final else (0.0,)
        close = False
        seen_now = set()
        for thr in thresholds:
            S = J[x[J] > thr * top]
            key = S.tobytes()
            # mid-run, each support is polished once; the final polish retries it, since
            # which eigenpairs are examined depends on x (alignment, the eigsh shift r(x))
            if key in seen_now or (key in self.tried and not final):
                continue
            seen_now.add(key)
            self.tried.add(key)
            R = np.union1d(F, S)
            if R.size == 0:
                continue
            for sol in self._polish(x, S, R):
                _add_distinct(self.certified, [sol], self.scales)
                xn = x / np.linalg.norm(x)
                close |= bool(np.linalg.norm(sol.x - xn) <= 1e-3)
        return close

    def _polish(self, x, S, R):
        self.calls += 1
        A_RR = _submatrix(self.A, R)
        B_RR = _submatrix(self.B, R)
        x_R = x[R]
        r = float(x @ (self.A @ x)) / float(x @ (self.B @ x))
        if R.size <= limits.DENSE_POLISH_LIMIT:
            lams, vecs = la.eigh(to_dense(A_RR), to_dense(B_RR))
        else:
            k = min(6, R.size - 1)
            lams, vecs = eigsh(sp.csc_matrix(A_RR), k=k, M=sp.csc_matrix(B_RR), sigma=r,
                               which="LM")
        in_S = np.isin(R, S)
        # orient each eigenvector along x, then keep those positive on S
        Bx_R = B_RR @ x_R
        overlap = vecs.T @ Bx_R
        vecs = vecs * np.where(overlap < 0, -1.0, 1.0)
        if in_S.any():
            positive = np.all(vecs[in_S] > 0, axis=0)
        else:
            positive = np.ones(lams.size, dtype=bool)
        order = np.argsort(-np.abs(overlap) / np.linalg.norm(vecs, axis=0))
        out = []
        for j in [j for j in order if positive[j]][:POLISH_CANDIDATES]:
            xi = np.zeros(self.problem.n)
            xi[R] = vecs[:, j]
            sol = certify_pair(self.problem, float(lams[j]), xi, self.scales)
            if sol.residual <= self.tol:
                out.append(sol)
        return out


def _submatrix(M, idx):
    if sp.issparse(M):
        return M[idx][:, idx]
    return M[np.ix_(idx, idx)]


def _add_distinct(found: list, new, scales, lam_rtol: float = 1e-9, x_atol: float = 1e-7) -> None:
    """Append the solutions of ``new`` that differ from every one in ``found`` (λ and x)."""
    for sol in new:
        s = scales[0] + abs(sol.lam) * scales[1]
        if not any(abs(sol.lam - f.lam) <= lam_rtol * max(s, 1.0)
                   and np.abs(sol.x - f.x).max() <= x_atol for f in found):
            found.append(sol)
