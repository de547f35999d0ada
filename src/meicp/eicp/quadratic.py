"""The quadratic (M)EiCP of a damped lattice, dense and small (docs/damping.md).

Modes ``e^{λt}v`` of ``Mü + Cu̇ + Ku = F + R`` give, in the MEiCP's reduced coordinates,

    y = (λ²B + λD − A)x,   x_J ≥ 0,  y_J ≥ 0,  x_Jᵀy_J = 0,  y_F = 0,   λ real ≥ 0

(``A = −P̃KQ̃``, ``B = P̃MQ̃``, ``D = P̃CQ̃``); with D = 0 it is the MEiCP in σ = λ².

:func:`solve_quadratic_eicp` enumerates the supports ``S ⊆ J``: λ is a solution iff the
reduced quadratic pencil on ``R = F ∪ S`` has a real eigenvalue λ ≥ 0 with an eigenvector
``ξ_S > 0`` and dual feasibility ``(λ²B + λD − A)_{J∖S, R} ξ ≥ 0``.  Each support's
eigenvalues come from the dense companion linearisation (:func:`companion`): every λ near
the real axis is a candidate, whose null space is taken from the SVD of the real matrix
``Q(λ)_RR`` (a repeated eigenvalue's whole null space is searched for a feasible vector by
a linear program, as the undamped enumeration does), and every solution is certified row by
row on the original data (:func:`certify`).  A sign-feasible candidate whose certificate
fails is *unverified*: ``no_solution`` is claimed only without one.

:func:`quadratic_spectrum` gives every eigenvalue of the whole pencil with its rounding
radius and backward error: the damped flutter path's data.

Conditioning: λ = s·μ with ``s = sqrt(‖A‖/‖B‖)`` and the pencil divided by ``‖A‖`` (the
scaling of Fan, Lin and Van Dooren), so that the companion form's blocks have norm about 1.
"""

from __future__ import annotations

import itertools
import time
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sl
from scipy.optimize import linprog

from ..core import limits
from ..core.errors import ProblemError

#: relative certificate tolerance (as the undamped MEiCP's)
DEFAULT_TOL = 1e-10
#: a companion eigenvalue μ with |Im μ| ≤ REAL_SLACK·max(1, |μ|) is a candidate real one (a
#: defective triple eigenvalue splits by eps^(1/3) ≈ 6e-6): the certificate decides
REAL_SLACK = 1e-4
#: singular values of Q(λ)_RR up to this fraction of the largest span its null space
NULL_TOL = 1e-8
#: ξ_j > SUPPORT_TOL·‖ξ‖∞ counts as positive
SUPPORT_TOL = 1e-9
#: a sign-feasible candidate failing its certificate by less than this factor is unverified
UNVERIFIED_FACTOR = 1e3
#: a real candidate below lam_min by at most this much (relative to s) is tried at lam_min
#: itself: an exact λ = lam_min (a rigid slide that neither K nor C resists, λ = 0) is computed
#: off by eps·‖A‖/|yᴴDx|, unbounded as D → 0, and by √eps when it is a Jordan block (D x = 0);
#: the certificate at lam_min decides, so a wide band costs candidates, never a false solution.
#: A candidate within the band above lam_min (or just below it, above the rounding floor) is tried
#: at lam_min too: where both certify the
#: same mode, λ = lam_min is reported (its certificate, without the |λ|·|D| term in the row
#: scale, is the sharper; a rigid slide under dashpots of η = 10⁴ was reported at λ = 2e-6)
CLAMP_BAND = 1e-6


def _norm1(M: np.ndarray) -> float:
    return float(np.abs(M).sum(axis=0).max()) if M.size else 0.0


@dataclass(frozen=True)
class Scaling:
    """λ = s·μ, ``Q(λ) = ‖A‖ (μ²B̂ + μD̂ − Â)``: ``s``, and the factors of B, D, A."""

    s: float
    b: float
    d: float
    a: float

    @classmethod
    def of(cls, A: np.ndarray, B: np.ndarray) -> "Scaling":
        na, nb = _norm1(A) or 1.0, _norm1(B) or 1.0
        return cls(float(np.sqrt(na / nb)), 1.0 / nb, 1.0 / np.sqrt(na * nb), 1.0 / na)


def companion(A, B, D, *, second: bool = False):
    """``(L0, L1)`` with ``L0 z = μ L1 z`` the linearisation of ``μ²B + μD − A``.

    First companion form (default), ``z = (x, μx)``: ``L0 = [[0, I], [A, −D]]``,
    ``L1 = [[I, 0], [0, B]]``.  Second (``second=True``), ``z = (μx, x)``:
    ``L0 = [[−D, A], [I, 0]]``, ``L1 = [[B, 0], [0, I]]`` — an independent check."""
    n = A.shape[0]
    Z, I = np.zeros((n, n)), np.eye(n)
    if second:
        return np.block([[-D, A], [I, Z]]), np.block([[B, Z], [Z, I]])
    return np.block([[Z, I], [A, -D]]), np.block([[I, Z], [Z, B]])


#: B_RR with a larger condition estimate is not inverted: QZ on the companion pair instead
COND_LIMIT = 1e8


def _eig(A, B, D, *, left: bool = False, vectors: bool = True):
    """Eigenvalues μ (inf where infinite), right eigenvectors x (the quadratic's: first block
    of z; None unless ``vectors``), and when ``left`` the rounding radius of each μ, of
    ``μ²B + μD − A`` (scaled data).  B diagonal and positive: the standard eigenproblem of
    L1⁻¹L0; B well conditioned (eigenvalues only): the same through a solve with B; else QZ."""
    n = A.shape[0]
    d = np.diag(B)
    eps = np.finfo(float).eps
    diagonal = np.all(d > 0) and np.count_nonzero(B) == np.count_nonzero(d)
    if not (vectors or left) and not diagonal:
        lu = sl.lu_factor(B, check_finite=False)
        rcond, _ = sl.lapack.dgecon(lu[0], _norm1(B), norm="1")
        if rcond * COND_LIMIT > 1:
            S = np.block([[np.zeros((n, n)), np.eye(n)], [sl.lu_solve(lu, np.hstack([A, -D]), check_finite=False)]])
            return np.linalg.eigvals(S), None, None
    L0, L1 = companion(A, B, D)
    if diagonal:
        inv = np.concatenate([np.ones(n), 1.0 / d])
        S = inv[:, None] * L0
        if not (vectors or left):
            return np.linalg.eigvals(S), None, None
        out = sl.eig(S, left=left, right=True)
        mu, VR = out[0], out[-1]
        radius = None
        if left:
            VL = out[1]
            kappa = (np.linalg.norm(VL, axis=0) * np.linalg.norm(VR, axis=0)
                     / np.maximum(np.abs(np.einsum("ij,ij->j", VL.conj(), VR)), 1e-300))
            radius = 2 * n * (eps / 2) * (_norm1(S) + np.abs(mu)) * kappa
        return mu, VR[:n], radius
    out = sl.eig(L0, L1, left=left, right=vectors or left, homogeneous_eigvals=True)
    alpha, beta = out[0] if (vectors or left) else out
    infinite = np.abs(beta) * _norm1(L0) <= 2 * n * eps * np.abs(alpha) * _norm1(L1)
    mu = np.where(infinite, np.inf, alpha / np.where(infinite, 1.0, beta))
    if not (vectors or left):
        return mu, None, None
    VR = out[-1]
    radius = None
    if left:
        VL = out[1]
        kappa = (np.linalg.norm(VL, axis=0) * np.linalg.norm(VR, axis=0)
                 / np.maximum(np.abs(np.einsum("ij,ij->j", VL.conj(), L1 @ VR)), 1e-300))
        radius = np.where(infinite, np.inf,
                          2 * n * (eps / 2) * (_norm1(L0) + np.where(infinite, 0, np.abs(mu)) * _norm1(L1)) * kappa)
    return mu, VR[:n], radius


def backward_error(A, B, D, lam: complex, x: np.ndarray) -> float:
    """``‖Q(λ)x‖₂ / ((‖A‖₁ + |λ|‖D‖₁ + |λ|²‖B‖₁)‖x‖₂)`` of ``Q(λ) = λ²B + λD − A``."""
    x = np.asarray(x)
    scale = (_norm1(A) + abs(lam) * _norm1(D) + abs(lam) ** 2 * _norm1(B)) * np.linalg.norm(x)
    r = lam * lam * (B @ x) + lam * (D @ x) - A @ x
    return float(np.linalg.norm(r) / scale) if scale > 0 else float("inf")


@dataclass(frozen=True)
class QuadraticSpectrum:
    """Every eigenvalue λ of ``λ²B + λD − A`` (2n, inf for an infinite one), the quadratic's
    eigenvector of each (columns of ``x``, unit norm), the first-order rounding radius of
    each λ (``2n·u·(‖L0‖ + |μ|‖L1‖)·κ`` on the scaled companion form, mapped back), and the
    backward error of each pair on the original data."""

    lam: np.ndarray
    x: np.ndarray
    radius: np.ndarray
    residual: np.ndarray
    how: str


def quadratic_spectrum(A, B, D) -> QuadraticSpectrum:
    """The whole spectrum of the quadratic pencil (dense A, B, D), by the first companion
    form on the scaled data (module docstring)."""
    A, B, D = (np.asarray(M, dtype=float) for M in (A, B, D))
    sc = Scaling.of(A, B)
    mu, X, radius = _eig(sc.a * A, sc.b * B, sc.d * D, left=True)
    lam = sc.s * mu
    norms = np.linalg.norm(X, axis=0)
    X = X / np.where(norms > 0, norms, 1.0)
    finite = np.isfinite(lam)
    lf = np.where(finite, lam, 0.0)
    with np.errstate(over="ignore", invalid="ignore"):
        R = (B @ X) * lf ** 2 + (D @ X) * lf - A @ X  # every pair at once: three products
        scale = _norm1(A) + np.abs(lf) * _norm1(D) + np.abs(lf) ** 2 * _norm1(B)
        residual = np.where(finite & (scale > 0), np.linalg.norm(R, axis=0) / np.where(scale > 0, scale, 1.0),
                            np.inf)
    diagonal = np.count_nonzero(B) == np.count_nonzero(np.diag(B)) and np.all(np.diag(B) > 0)
    how = ("dense companion linearisation of λ²B + λD − A (QR of L1⁻¹L0, B diagonal)" if diagonal
           else "dense companion linearisation of λ²B + λD − A (QZ)")
    return QuadraticSpectrum(lam, X, sc.s * radius, residual, how)


# -- the quadratic MEiCP by enumeration of supports -----------------------------------------------


@dataclass(frozen=True)
class QuadraticSolution:
    """One certified solution: ``lam`` (real, the growth rate), ``x`` (‖x‖₂ = 1, x_J ≥ 0),
    ``y = (λ²B + λD − A)x``, ``support`` (the j ∈ J with x_j > 0), ``residual`` (the row-wise
    certificate, :func:`certify`) and its parts."""

    lam: float
    x: np.ndarray
    y: np.ndarray
    support: np.ndarray
    residual: float
    parts: dict = field(default_factory=dict)

    @property
    def sigma(self) -> float:
        return self.lam * self.lam


@dataclass
class QuadraticEiCPResult:
    """Every solution with λ ≥ lam_min (largest first), ``status``: ``solved`` (some),
    ``no_solution`` (none, every support visited and no candidate unverified: a proof),
    ``undecided`` (``message`` says why); ``supports`` visited, ``unverified`` candidates,
    ``seconds``."""

    solutions: list
    status: str
    supports: int
    unverified: int = 0
    message: str = ""
    seconds: float = 0.0
    method: str = "quadratic-enumerate"

    @property
    def success(self) -> bool:
        return self.status in ("solved", "no_solution")


def certify(A, B, D, J, lam: float, x: np.ndarray) -> tuple[float, dict, np.ndarray]:
    """``(residual, parts, y)`` of a candidate, row by row on the original data: row i is
    measured against ``s_i = max|A_i·| + |λ| max|D_i·| + λ² max|B_i·|`` (x scaled to ‖x‖₂ = 1):
    the eigen-residual on F and on the support, ``−min x_J``, ``−min y_J``, ``max |x_j y_j|``."""
    x = x / np.linalg.norm(x)
    y = lam * lam * (B @ x) + lam * (D @ x) - A @ x
    s = np.abs(A).max(axis=1) + abs(lam) * np.abs(D).max(axis=1) + lam * lam * np.abs(B).max(axis=1)
    s = np.where(s > 0, s, 1.0)
    inJ = np.zeros(x.size, dtype=bool)
    inJ[J] = True
    xJ, yJ = x[J], y[J]
    on = ~inJ | (inJ & (x > SUPPORT_TOL * np.abs(x).max()))
    parts = {"eigen": float(np.max(np.abs(y[on]) / s[on], initial=0.0)),
             "x_J": float(max(0.0, -xJ.min(initial=0.0))),
             "y_J": float(max(0.0, np.max(-yJ / s[J], initial=0.0))),
             "complementarity": float(np.max(np.abs(xJ * yJ) / s[J], initial=0.0))}
    return max(parts.values()), parts, y


def solve_quadratic_eicp(A, B, D, J, *, lam_min: float = 0.0, tol: float = DEFAULT_TOL,
                         max_j: int | None = None) -> QuadraticEiCPResult:
    """Every solution with real λ ≥ ``lam_min`` of the quadratic MEiCP (module docstring) by
    enumeration of the 2^|J| supports: dense A, B, D (n × n), J the complementarity
    positions.  ``max_j``: the most pairs enumerated (default ``limits.ENUMERATE_J``);
    more is a ProblemError."""
    t0 = time.perf_counter()
    A, B, D = (np.asarray(M, dtype=float) for M in (A, B, D))
    n = A.shape[0]
    if not (A.shape == B.shape == D.shape == (n, n)):
        raise ProblemError(f"A, B, D must be square of one size, got {A.shape}, {B.shape}, {D.shape}")
    if not all(np.all(np.isfinite(M)) for M in (A, B, D)):
        raise ProblemError("A, B, D must have finite entries")
    J = np.unique(np.asarray(J, dtype=np.int64))
    if J.size and (J[0] < 0 or J[-1] >= n):
        raise ProblemError(f"J must hold indices in [0, {n}), got {J.min()}..{J.max()}")
    limit = limits.ENUMERATE_J if max_j is None else int(max_j)
    if J.size > limit:
        raise ProblemError(f"the quadratic MEiCP has {J.size} complementarity pairs: enumerating its "
                           f"2^{J.size} supports is past the limit of {limit} pairs")
    F = np.setdiff1d(np.arange(n), J)
    sc = Scaling.of(A, B)
    As, Bs, Ds = sc.a * A, sc.b * B, sc.d * D
    floor = lam_min - 1e3 * np.finfo(float).eps * (abs(lam_min) + sc.s)
    band = lam_min - CLAMP_BAND * (abs(lam_min) + sc.s)
    found, unverified, visited = [], 0, 0
    for k in range(J.size + 1):
        for S in itertools.combinations(J.tolist(), k):
            S = np.array(S, dtype=np.int64)
            R = np.sort(np.concatenate([F, S]))
            visited += 1
            if R.size == 0:
                continue
            ix = np.ix_(R, R)
            mu = _eig(As[ix], Bs[ix], Ds[ix], vectors=False)[0]
            near = np.isfinite(mu) & (np.abs(mu.imag) <= REAL_SLACK * np.maximum(1.0, np.abs(mu)))
            for lam in _distinct(sc.s * mu[near].real):
                if lam < band:
                    continue
                if lam < floor:  # an exact λ = lam_min computed below it: certified at lam_min itself
                    lam = lam_min
                sols, doubt = _support_solutions(A, B, D, J, R, S, float(lam), tol)
                if lam != lam_min and abs(lam - lam_min) <= lam_min - band:  # within rounding of lam_min
                    at_min, _ = _support_solutions(A, B, D, J, R, S, float(lam_min), tol)
                    if at_min:
                        sols = at_min + [s for s in sols if not any(_same_mode(s, m) for m in at_min)]
                found += sols
                unverified += doubt
    solutions = _unique(found)
    solutions.sort(key=lambda s: -s.lam)
    seconds = time.perf_counter() - t0
    if solutions:
        return QuadraticEiCPResult(solutions, "solved", visited, unverified, seconds=seconds)
    if unverified:
        return QuadraticEiCPResult([], "undecided", visited, unverified, seconds=seconds, message=(
            f"{unverified} sign-feasible candidate(s) failed the certificate by less than {UNVERIFIED_FACTOR:g}× "
            "their own inaccuracy: they may hide a solution"))
    return QuadraticEiCPResult([], "no_solution", visited, seconds=seconds,
                               message=f"all {visited} supports: no real λ ≥ {lam_min:g}")


def _distinct(values: np.ndarray) -> list[float]:
    """The values, those within 1e-8 relative of each other merged (a repeated eigenvalue is
    handled once, through its whole null space)."""
    out = []
    for v in np.sort(values):
        if out and abs(v - out[-1]) <= 1e-8 * max(1.0, abs(v)):
            continue
        out.append(float(v))
    return out


def _support_solutions(A, B, D, J, R, S, lam: float, tol: float) -> tuple[list, int]:
    """The certified solutions at ``lam`` on support S (R = F ∪ S), and how many sign-feasible
    candidates were unverified (0 or 1)."""
    Q = lam * lam * B + lam * D - A
    QRR = Q[np.ix_(R, R)]
    _, sv, Vt = np.linalg.svd(QRR)
    null = Vt[sv <= NULL_TOL * max(sv[0], 1e-300)].T if sv.size else np.zeros((R.size, 0))
    if null.shape[1] == 0:
        null = Vt[-1:].T
    inS = np.isin(R, S)
    rest = np.setdiff1d(J, S)
    xi, doubt = _feasible_vector(null, inS, Q[np.ix_(rest, R)])
    if xi is None:
        return [], doubt
    x = np.zeros(A.shape[0])
    x[R] = xi
    residual, parts, y = certify(A, B, D, J, lam, x)
    if residual <= tol:
        x = x / np.linalg.norm(x)
        support = J[x[J] > SUPPORT_TOL * np.abs(x).max()]
        return [QuadraticSolution(lam, x, y, support, residual, parts)], 0
    return [], int(residual <= UNVERIFIED_FACTOR * tol)


def _feasible_vector(null: np.ndarray, inS: np.ndarray, dual_rows: np.ndarray) -> tuple[np.ndarray | None, int]:
    """``(ξ, 0)`` with ξ in span(``null``), ξ_S > 0 and ``dual_rows``·ξ ≥ 0 (up to rounding), or
    ``(None, doubt)``: the eigenvector itself (either sign) for a simple eigenvalue, a linear
    program over the null space for a repeated one.  ``doubt`` is 1 where no vector was found
    but one may exist: a repeated eigenvalue on the empty support (ξ ≠ 0 is no linear
    constraint) whose basis vectors all fail."""
    slack = 1e-8 * max(float(np.abs(dual_rows).sum(axis=1).max(initial=0.0)), 1.0)
    basis = [v for j in range(null.shape[1]) for v in (null[:, j], -null[:, j])]
    for xi in basis[:2] if null.shape[1] > 1 and inS.any() else basis:
        if _sign_ok(xi, inS) and np.all(dual_rows @ xi >= -slack):
            return xi, 0
    if null.shape[1] == 1:
        return None, 0
    if not inS.any():
        return None, 1
    k = null.shape[1]
    rows = np.vstack([-null[inS], -(dual_rows @ null)])
    rhs = np.concatenate([-np.ones(int(inS.sum())), np.zeros(dual_rows.shape[0])])
    res = linprog(np.zeros(k), A_ub=rows, b_ub=rhs, bounds=[(None, None)] * k, method="highs")
    if res.status != 0:
        return None, 0
    xi = null @ res.x
    return (xi, 0) if _sign_ok(xi, inS) else (None, 1)


def _sign_ok(xi: np.ndarray, inS: np.ndarray) -> bool:
    return not inS.any() or bool(np.all(xi[inS] > SUPPORT_TOL * np.abs(xi).max()))


def _same_mode(s, other, angle: float = 1e-6) -> bool:
    """Whether two solutions have one shape (up to sign; both normalised)."""
    return min(np.linalg.norm(s.x - other.x), np.linalg.norm(s.x + other.x)) <= angle


def _unique(solutions: list) -> list:
    """One solution per (λ, x) (a solution found on two supports at the boundary)."""
    out = []
    for s in solutions:
        if not any(abs(s.lam - o.lam) <= 1e-9 * max(1.0, abs(o.lam)) and _same_mode(s, o, 1e-7) for o in out):
            out.append(s)
    return out
