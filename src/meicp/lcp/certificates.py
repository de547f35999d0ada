"""Certificates that ``LCP(0, G)`` has no solution ``x ≠ 0`` (G ∈ R₀), with rounding margins.

These are facts about the LCP matrix class of G, so they live beside :mod:`.classes`; the
contact layer applies them to the MEiCP condensed onto its complementarity DOFs
(:mod:`meicp.contact.condensation`), where G(σ) = S(σ) + μR(σ) is dense and of order |J|.

At a solution ``x ≥ 0, x ≠ 0`` of LCP(0, G) every product ``x_j (Gx)_j`` vanishes, hence
``xᵀDGx = 0`` for every diagonal D.  So, for a positive diagonal D::

    sym(DG) = (DG + GᵀD)/2 ≻ 0   ⇒   G ∈ R₀           (scaled positive definiteness)

(D = I is plain positive definiteness; the existence of such a D is Lyapunov diagonal
stability, which implies that G is a P-matrix).  A test decides only with a margin: the
computed λ_min must exceed the dense eigen-solve's rounding plus ``max(d)·ε``, ε a bound of
``‖Ĝ − G‖₂`` supplied by the caller (the condensation's error).

With μ as the parameter, ``G_μ = S + μR``: one D with ``sym(DS) ≻ 0`` and
``sym(D(S + μ₁R)) ≻ 0`` certifies every μ ∈ [0, μ₁] (the positive definite cone is convex),
and the largest such μ₁ for a given D is ``μ̄(D) = 1/λ_max(−sym(DR), sym(DS))``.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sl
import scipy.optimize as so
import scipy.sparse.linalg as spl

EPS = np.finfo(float).eps
#: allowance for LAPACK's symmetric eigenvalues: |λ̂ − λ| ≤ p(n)·u·‖X‖₂ with p modest; we
#: charge ``EIG_ROUNDING·n·u·‖X‖₂`` (generous)
EIG_ROUNDING = 10.0
#: relative steps below a computed μ̄ at which a segment's far end is certified
SHRINKS = tuple(m * 10.0 ** e for e in range(-7, 0) for m in (1, 2, 5)) + (0.5,)
#: orders above which μ̄ uses Lanczos on a Cholesky factor instead of a dense eigen-solve
DENSE_LIMIT = 300


def sym(X: np.ndarray) -> np.ndarray:
    return 0.5 * (X + X.T)


def scaled(G: np.ndarray, d: np.ndarray | None) -> np.ndarray:
    """sym(DG) for D = diag(d) (d None: sym(G))."""
    return sym(G if d is None else d[:, None] * G)


def norm2_bound(X: np.ndarray) -> float:
    """An upper bound of ‖X‖₂ for a symmetric X: ‖X‖∞ (≥ ‖X‖₂ since ‖X‖₂² ≤ ‖X‖₁‖X‖∞).
    A rounding allowance only needs an upper bound, and the 2-norm's SVD costs several times
    the certificate it allows for (docs/benchmarks-notes.md, lcp)."""
    return float(np.abs(X).sum(axis=1).max(initial=0.0))


def eig_rounding(X: np.ndarray, norm: float | None = None) -> float:
    """The allowance for the rounding of LAPACK's eigenvalues of the symmetric X
    (``norm``: an upper bound of ‖X‖₂ when the caller has one)."""
    return EIG_ROUNDING * X.shape[0] * EPS * (norm2_bound(X) if norm is None else norm)


@dataclass
class PDCertificate:
    """λ_min(sym(DG)) as computed, its ``rounding`` allowance (eigen-solve + ‖D‖·ε) and the
    eigenvector; ``proved`` iff ``margin = lam_min − rounding > 0``."""

    lam_min: float
    rounding: float
    d: np.ndarray | None
    vector: np.ndarray

    @property
    def margin(self) -> float:
        return self.lam_min - self.rounding

    @property
    def proved(self) -> bool:
        return self.margin > 0


def pd_certificate(G: np.ndarray, error: float, d: np.ndarray | None = None, *, tol: float = 0.0) -> PDCertificate:
    """λ_min(sym(DG)) with its rounding allowance: the dense eigen-solve's, ``max(d)·error``
    (error: a bound of ‖Ĝ − G‖₂) and ``tol·‖sym(DG)‖∞`` (a caller's extra relative margin,
    against a bound of the 2-norm)."""
    X = scaled(G, d)
    w, V = sl.eigh(X, subset_by_index=[0, 0])
    return PDCertificate(float(w[0]), _allowance(X, d, error, tol), d, V[:, 0])


def pd_margin(G: np.ndarray, error: float, d: np.ndarray | None = None, *, tol: float = 0.0) -> float:
    """The :class:`PDCertificate` margin of :func:`pd_certificate`, or −inf without the
    eigen-solve when a Cholesky already shows it is not positive (:func:`below_allowance`):
    for tests that only need the margin of a proof that holds."""
    X = scaled(G, d)
    allowance = _allowance(X, d, error, tol)
    if below_allowance(X, allowance):
        return -np.inf
    return float(sl.eigh(X, eigvals_only=True, subset_by_index=[0, 0])[0]) - allowance


def _allowance(X: np.ndarray, d: np.ndarray | None, error: float, tol: float) -> float:
    """The rounding allowance of λ_min(X), X = sym(DG) (see :func:`pd_certificate`)."""
    norm = norm2_bound(X)
    return eig_rounding(X, norm) + (1.0 if d is None else float(np.max(d))) * error + tol * norm


def below_allowance(X: np.ndarray, allowance: float) -> bool:
    """Whether the Cholesky factorisation of ``sym(X) − allowance·I`` breaks down: λ_min(sym X)
    then lies below the allowance (up to the factorisation's rounding), so a
    :func:`pd_certificate` with that allowance would not prove ``X ≻ 0``.  A cheap rejection
    (a Cholesky costs a fraction of the eigenvalue it spares); ``False`` proves nothing."""
    Y = sym(X) - allowance * np.eye(X.shape[0])
    try:
        sl.cholesky(Y, lower=True, check_finite=False)
    except np.linalg.LinAlgError:
        return True
    return False


def optimise_scaling(Gs: list[np.ndarray], d0: np.ndarray | None = None, iters: int = 60,
                     step: float = 0.5, target: float | None = None) -> tuple[np.ndarray, float]:
    """A positive diagonal d maximising ``min_i λ_min(sym(D G_i)) / mean(d)`` (λ_min of a
    matrix linear in d is concave; the ratio is scale invariant): supergradient ascent on
    log d (``d_j v_j (Gv)_j``, v the eigenvector of λ_min), the step halved on failure.
    Returns the best ``(d, value)``; stops once the value exceeds ``target``."""
    n = Gs[0].shape[0]
    logd = np.zeros(n) if d0 is None else np.log(d0)
    best_d, best = np.exp(logd), -np.inf
    # the ascent needs λ_min and its vector to a few digits, not to rounding: single precision
    # above DENSE_LIMIT, where it is faster (docs/benchmarks-notes.md, lcp); every
    # certificate is recomputed in double
    precision = np.float32 if n > DENSE_LIMIT else np.float64
    for _ in range(iters):
        d = np.exp(logd - logd.max())
        vals = []
        for G in Gs:
            w, V = sl.eigh(scaled(G, d).astype(precision, copy=False), subset_by_index=[0, 0])
            vals.append((float(w[0]), V[:, 0].astype(np.float64), G))
        lam, v, G = min(vals, key=lambda t: t[0])
        value = lam / d.mean()
        if value > best:
            best, best_d = value, d.copy()
        else:
            step *= 0.5
        if target is not None and best > target:
            break
        g = d * v * (G @ v) / d.mean() - value * d / (n * d.mean())
        nrm = np.abs(g).max()
        if nrm == 0 or step < 1e-4:
            break
        logd = np.log(best_d) + step * g / nrm
    return best_d, float(best)


def mu_bar(S: np.ndarray, R: np.ndarray, d: np.ndarray | None = None, *, v0=None):
    """``(μ̄, v)``: 1/λ_max(−sym(DR), sym(DS)) and the top eigenvector; (0, None) when sym(DS)
    is not positive definite, (inf, None) when −sym(DR) has no positive eigenvalue.  Orders
    above DENSE_LIMIT use a Cholesky factor and Lanczos warm-started from ``v0`` (inside
    optimisations only: a final bound is re-certified by :func:`pd_certificate`)."""
    A, Bm = scaled(S, d), -scaled(R, d)
    n = A.shape[0]
    if n <= DENSE_LIMIT:
        try:
            w, V = sl.eigh(Bm, A, subset_by_index=[n - 1, n - 1])
        except np.linalg.LinAlgError:
            return 0.0, None
        return (1.0 / w[0], V[:, 0]) if w[0] > 0 else (np.inf, None)
    try:
        L = sl.cholesky(A, lower=True)
    except np.linalg.LinAlgError:
        return 0.0, None

    def op(y):
        z = sl.solve_triangular(L, y, lower=True, trans="T")
        return sl.solve_triangular(L, Bm @ z, lower=True)
    lin = spl.LinearOperator((n, n), matvec=op, dtype=float)
    start = None if v0 is None else L.T @ v0
    try:
        w, Y = spl.eigsh(lin, k=1, which="LA", v0=start, tol=1e-10, ncv=min(n, 40))
    except spl.ArpackNoConvergence:
        w, V = sl.eigh(Bm, A, subset_by_index=[n - 1, n - 1])
        return (1.0 / w[0], V[:, 0]) if w[0] > 0 else (np.inf, None)
    v = sl.solve_triangular(L, Y[:, 0], lower=True, trans="T")
    return (1.0 / w[0], v) if w[0] > 0 else (np.inf, None)


def lam_min_sym(X: np.ndarray) -> float:
    """λ_min of a symmetric X (−inf if a large X is not positive definite: Cholesky fails)."""
    n = X.shape[0]
    if n <= DENSE_LIMIT:
        return float(sl.eigh(X, eigvals_only=True, subset_by_index=[0, 0])[0])
    try:
        c = sl.cho_factor(X)
    except np.linalg.LinAlgError:
        return -np.inf
    lin = spl.LinearOperator((n, n), matvec=lambda y: sl.cho_solve(c, y), dtype=float)
    w = spl.eigsh(lin, k=1, which="LA", return_eigenvectors=False, tol=1e-8, ncv=min(n, 30))
    return float(1.0 / w[0])


def _descent_mu_scaling(S, R, iters: int = 80, step: float = 0.5, keep: float = 0.05):
    """Descent on θ = 1/μ̄ in log d (gradient ``−d_j v_j ((R + θS)v)_j``), keeping
    λ_min(sym(DS))/mean(d) ≥ ``keep`` × its D = I value (a margin left at μ = 0)."""
    n = S.shape[0]
    d = np.ones(n)
    floor = keep * lam_min_sym(sym(S))
    mu, v = mu_bar(S, R, d)
    best_d, best = d.copy(), mu
    if not np.isfinite(mu) or mu == 0:
        return best_d, best
    for _ in range(iters):
        theta = 1.0 / mu
        g = -d * v * ((R + theta * S) @ v)
        g -= g.mean()
        nrm = np.abs(g).max()
        if nrm == 0:
            break
        trial = np.exp(np.log(best_d) - step * g / nrm)
        trial /= trial.max()
        mu_t, v_t = mu_bar(S, R, trial, v0=v)
        if mu_t > best and lam_min_sym(scaled(S, trial)) / trial.mean() >= floor:
            best, best_d, d, mu, v = mu_t, trial, trial, mu_t, v_t
            step *= 1.2
        else:
            step *= 0.5
            if step < 1e-5:
                break
        if not np.isfinite(best):
            break
    return best_d, float(best)


def optimise_mu_scaling(S: np.ndarray, R: np.ndarray, iters: int = 150, keep: float = 0.05):
    """A positive diagonal d maximising μ̄(d): L-BFGS on log d with ``∂θ/∂log d_j =
    −d_j v_j ((R + θS)v)_j`` (θ = 1/μ̄, an extreme generalized eigenvalue), falling back to a
    plain descent if the optimum leaves λ_min(sym(DS))/mean(d) below ``keep`` × its D = I
    value.  Returns ``(d, μ̄)`` (μ̄ as computed: certify with :func:`certified_mu_lower_bound`)."""
    n = S.shape[0]
    state = {"v": None}

    def fun(logd):
        d = np.exp(logd - logd.max())
        mu, v = mu_bar(S, R, d, v0=state["v"])
        if mu == 0 or v is None:
            return (1e6 if mu == 0 else 0.0), np.zeros(n)
        state["v"] = v
        theta = 1.0 / mu
        return theta, -d * v * ((R + theta * S) @ v)

    mu1, _ = mu_bar(S, R)
    if not np.isfinite(mu1) or mu1 == 0:
        return np.ones(n), mu1
    res = so.minimize(fun, np.zeros(n), jac=True, method="L-BFGS-B", options={"maxiter": iters})
    d = np.exp(res.x - res.x.max())
    mu, _ = mu_bar(S, R, d)
    floor = keep * lam_min_sym(sym(S))
    if mu > mu1 and lam_min_sym(scaled(S, d)) / d.mean() >= floor:
        return d, float(mu)
    return _descent_mu_scaling(S, R, keep=keep)


def certified_mu_lower_bound(S, R, error_S: float, error_R: float, d: np.ndarray | None,
                             mu_guess: float, *, tol: float = 0.0):
    """The largest μ ≤ ``mu_guess`` (shrunk by 10⁻⁷, 2·10⁻⁷, 5·10⁻⁷, 10⁻⁶, … relative) for
    which both ends sym(DS) and sym(D(S + μR)) pass :func:`pd_certificate` with their
    margins: every μ in [0, μ] is then certified.  Returns ``(μ_lo, cert_0, cert_μ)``; μ_lo = 0
    if none passes."""
    c0 = pd_certificate(S, error_S, d, tol=tol)
    if not c0.proved:
        return 0.0, c0, c0
    if not np.isfinite(mu_guess):
        mu_guess = 1e6
    c1 = c0
    for shrink in SHRINKS:
        mu = mu_guess * (1 - shrink)
        c1 = pd_certificate(S + mu * R, error_S + mu * error_R, d, tol=tol)
        if c1.proved:
            return float(mu), c0, c1
    return 0.0, c0, c1


def chain_mu_lower_bound(S, R, error_S: float, error_R: float, mu_start: float, *, growth: float = 2.0,
                         min_step: float = 1e-3, mu_cap: float = 1e4, max_attempts: int = 40, tol: float = 0.0,
                         seconds: float = np.inf):
    """Extend a certified [0, μ_start] by segments [μ_k, μ_{k+1}], each with its own D
    certifying both ends (convexity: every μ between).  Every third attempt tries the ray
    [μ_k, ∞): one D with sym(D G_μk) ≻ 0 and sym(DR) ≻ 0 certifies every μ ≥ μ_k (G_μ is a
    positive combination of the two).  Stops after ``seconds`` (what is proved by then
    stands).  Returns ``(μ_lo, segments)``."""
    mu_k, segs, step, attempts = mu_start, [], growth, 0
    deadline = time.perf_counter() + seconds
    while step - 1.0 > min_step and mu_k < mu_cap and attempts < max_attempts and time.perf_counter() < deadline:
        attempts += 1
        Ga, ea = S + mu_k * R, error_S + mu_k * error_R
        if attempts % 3 == 1:
            d, _ = optimise_scaling([Ga, R], iters=40)
            if pd_certificate(Ga, ea, d, tol=tol).proved and pd_certificate(R, error_R, d, tol=tol).proved:
                segs.append((mu_k, np.inf))
                return np.inf, segs
        mu_t = min(mu_k * step, mu_cap) if mu_k > 0 else 1e-3
        Gb, eb = S + mu_t * R, error_S + mu_t * error_R
        d, _ = optimise_scaling([Ga, Gb], iters=40)
        if pd_certificate(Ga, ea, d, tol=tol).proved and pd_certificate(Gb, eb, d, tol=tol).proved:
            segs.append((mu_k, mu_t))
            mu_k = mu_t
            step = min(step * 1.5, growth)
        else:
            step = 1.0 + 0.5 * (step - 1.0)
    return mu_k, segs
