"""The certified bracket of the critical friction on the condensed σ = 0 problem (dense,
NumPy/SciPy): ``G_μ = S + μR`` of order |J| (:mod:`.condensation` at σ = 0 with a unit μ).

* Lower end, a proof: a positive diagonal D with sym(DS) ≻ 0 and sym(D(S + μ_lo R)) ≻ 0, both
  with rounding margins, proves G_μ ∈ R₀ — no σ = 0 mode — for every μ in [0, μ_lo]
  (:mod:`meicp.lcp.certificates`); D = I gives μ_PD = 1/λ_max(−sym R, S), an optimised D
  more, and segments with their own D extend it.
* Upper end, a mode: candidate solutions ``(μR + S)x = y``, x ≥ 0 ⊥ y ≥ 0 found by a search
  (the full support by shift-and-invert near μ_lo, an active set on supports from localised
  starts, every run of up to ``MAX_RUN`` consecutive contacts in one batch), each certified
  on the condensed problem here and lifted to the whole lattice by the caller.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sl
import scipy.sparse.linalg as spl

from ..core import limits
from ..eicp.problem import EiCPProblem, certify_pair
from ..lcp.certificates import (certified_mu_lower_bound, chain_mu_lower_bound, mu_bar, optimise_mu_scaling,
                                pd_certificate)

#: longest run of consecutive contacts tried as a support (modes localise at free edges)
MAX_RUN = 16
#: certificate residual a condensed candidate must reach before it is lifted
CANDIDATE_TOL = 1e-9


@dataclass
class LowerEnd:
    """``mu``: every μ in [0, mu] has no σ = 0 mode (0: nothing proved; inf: none at any μ);
    ``mu_pd``: the D = I bound; ``d``: the scaling; ``evidence``: one sentence; ``margin``:
    the smaller certified margin of the segment's ends."""

    mu: float
    mu_pd: float
    d: np.ndarray | None
    evidence: str
    margin: float


def lower_end(S: np.ndarray, R: np.ndarray, error_S: float, error_R: float, *, mu_max: float,
              tol: float = 0.0) -> LowerEnd:
    """The certified lower end on [0, mu_max] (module docstring)."""
    c0 = pd_certificate(S, error_S, None, tol=tol)
    mu_pd, _ = mu_bar(S, R)
    if not c0.proved:
        return LowerEnd(0.0, 0.0, None, f"S = S(0) not certified positive definite (margin {c0.margin:.2e}): "
                        "no lower bound", c0.margin)
    d, mu_d = optimise_mu_scaling(S, R)
    if not mu_d > mu_pd:
        d, mu_d = np.ones(S.shape[0]), mu_pd
    lo, a, b = certified_mu_lower_bound(S, R, error_S, error_R, d, min(mu_d, mu_max), tol=tol)
    scaled = "D = I" if np.all(d == 1) else "an optimised positive diagonal D"
    evidence = (f"sym(D(S + μR)) ≻ 0 at μ = 0 and μ = {lo:.10g} for {scaled} (margins {a.margin:.1e}, "
                f"{b.margin:.1e}; D = I alone: μ ≤ {mu_pd:.6g})")
    return LowerEnd(lo, mu_pd, d, evidence, min(a.margin, b.margin))


def extend_lower(low: LowerEnd, S, R, error_S: float, error_R: float, *, mu_cap: float, tol: float = 0.0,
                 attempts: int = 12, seconds: float = np.inf) -> LowerEnd:
    """Extend [0, low.mu] by segments with their own D, up to ``mu_cap`` (the best upper end),
    for at most ``attempts`` segments and ``seconds``."""
    if not 0 < low.mu < mu_cap:
        return low
    mu, segs = chain_mu_lower_bound(S, R, error_S, error_R, low.mu, mu_cap=mu_cap, max_attempts=attempts, tol=tol,
                                    seconds=seconds)
    if mu <= low.mu:
        return low
    tail = "the last [μ_k, ∞) by sym(DR) ≻ 0" if not np.isfinite(mu) else f"to μ = {mu:.10g}"
    return LowerEnd(min(mu, np.inf), low.mu_pd, low.d,
                    f"{low.evidence}, extended by {len(segs)} segment(s) with their own D, {tail}", low.margin)


def lower_from_mode(low: LowerEnd, S, R, error_S: float, error_R: float, mu_up: float, x: np.ndarray, *,
                    tol: float = 0.0) -> LowerEnd:
    """Tighten the lower end with the scaling a full-support mode suggests: at μ_up,
    G x = 0 with x > 0; if its left null vector y is positive too, D = diag(y/x) puts x in
    the null space of sym(DG), so μ̄(D) = μ_up and the certified segment reaches within
    rounding of it.  Returns the better of ``low`` and that segment."""
    if not np.all(x > 0) or not 0 < mu_up < np.inf:
        return low
    U = np.linalg.svd(S + mu_up * R)[0]
    y = U[:, -1] * np.sign(U[:, -1].sum())
    if not np.all(y > 0):
        return low
    d = y / x
    d /= d.max()
    mu_d, _ = mu_bar(S, R, d)
    lo, a, b = certified_mu_lower_bound(S, R, error_S, error_R, d, min(mu_d, mu_up), tol=tol)
    if lo <= low.mu:
        return low
    return LowerEnd(lo, low.mu_pd, d, f"sym(D(S + μR)) ≻ 0 at μ = 0 and μ = {lo:.10g} for D = diag(y/x) from the "
                    f"full-support mode x and its left null vector y (margins {a.margin:.1e}, {b.margin:.1e}; "
                    f"D = I alone: μ ≤ {low.mu_pd:.6g})", min(a.margin, b.margin))


def condensed_problem(S: np.ndarray, R: np.ndarray) -> EiCPProblem:
    """The EiCP in μ ``(μR − (−S))x = y`` on J (every condensed DOF complementary)."""
    return EiCPProblem.from_data(-S, R, np.arange(S.shape[0]))


def upper_candidates(S: np.ndarray, R: np.ndarray, *, near: float, mu_max: float, d=None,
                     good_enough: float = 0.0, seconds: float = np.inf) -> list:
    """Certified condensed σ = 0 modes ``[(μ, x)]`` with μ ≤ mu_max, smallest μ first.  The
    cheap sources first (the full support, the runs); the active-set starts (dense
    eigen-solves on supports of at most ``limits.MU_ACTIVE_SET_MAX`` contacts) only while no candidate
    ≤ ``good_enough`` is certified (e.g. just above the proved lower end: nothing smaller
    can exist) and for at most ``seconds``."""
    deadline = time.perf_counter() + seconds
    n = S.shape[0]
    problem = condensed_problem(S, R)
    out, seen = [], set()

    def take(raw):
        for mu, x in raw:
            if not (0 < mu <= mu_max) or x is None or round(mu, 12) in seen:
                continue
            sol = certify_pair(problem, mu, x)
            if sol.residual <= CANDIDATE_TOL:
                seen.add(round(mu, 12))
                out.append((float(mu), sol.x))

    take(_full_support(S, R, near))
    take(_runs(S, R, min(MAX_RUN, n)))
    _, v = mu_bar(S, R, d)
    starts = [] if v is None else [v, -v]
    for k in (1, 2, 3, 5, 8, 13):
        for idx in (np.arange(min(k, n)), np.arange(max(0, n - k), n)):
            s = np.zeros(n)
            s[idx] = 1.0
            starts.append(s)
    for s in starts + ([None] if n <= limits.MU_ACTIVE_SET_MAX else []):
        if (out and min(mu for mu, _ in out) <= good_enough) or time.perf_counter() > deadline:
            break
        take([_active_set(S, R, s)])
    return sorted(out, key=lambda t: t[0])


def _positive(x: np.ndarray) -> np.ndarray | None:
    x = x * np.sign(x.sum()) if x.sum() != 0 else x
    return x / np.abs(x).max() if np.all(x >= -1e-12 * np.abs(x).max()) else None


def _full_support(S, R, near: float, k: int = 6) -> list:
    """Real pairs of (−R)x = νSx (ν = 1/μ) with a one-signed x: full-support modes.  Dense
    for small orders, shift-and-invert at ν = 1/near (ARPACK on a dense LU) beyond."""
    n = S.shape[0]
    if n <= 300:
        w, V = sl.eig(-R, S)
    elif np.isfinite(near) and near > 0:
        try:
            w, V = spl.eigs(-R, k=k, M=S, sigma=1.0 / near, which="LM")
        except Exception:  # noqa: BLE001 — ARPACK failing means no candidate here, not an error
            return []
    else:
        return []
    out = []
    for wi, vi in zip(w, V.T):
        if not np.isfinite(wi) or abs(wi.imag) > 1e-10 * abs(wi) or wi.real <= 0:
            continue
        x = _positive(vi.real)
        if x is not None:
            out.append((1.0 / wi.real, x))
    return out


def _runs(S, R, max_run: int) -> list:
    """Every support that is a run of ≤ ``max_run`` consecutive positions, batched by length
    (Cholesky of S_TT, eig of L⁻¹(−R_TT)L⁻ᵀ); one-signed real eigenvectors only."""
    n = S.shape[0]
    found = []
    for L in range(1, max_run + 1):
        idx = np.arange(n - L + 1)[:, None] + np.arange(L)[None, :]
        ST = S[idx[:, :, None], idx[:, None, :]]
        RT = -R[idx[:, :, None], idx[:, None, :]]
        try:
            Li = np.linalg.inv(np.linalg.cholesky(ST))
        except np.linalg.LinAlgError:
            continue
        lam, Z = np.linalg.eig(Li @ RT @ np.swapaxes(Li, 1, 2))
        V = np.swapaxes(Li, 1, 2) @ Z
        real = np.abs(lam.imag) <= 1e-10 * np.maximum(1.0, np.abs(lam.real))
        lam, V = lam.real, V.real
        V = V * np.where(V.sum(axis=1, keepdims=True) < 0, -1.0, 1.0)
        ok = real & (V.min(axis=1) > 1e-12 * np.abs(V).max(axis=1)) & (lam > 0)
        for b, i in zip(*np.nonzero(ok)):
            x = np.zeros(n)
            x[idx[b]] = V[b, :, i]
            found.append((1.0 / float(lam[b, i]), x))
    return found


def _active_set(S, R, start, max_iter: int = 20):
    """An active set on supports T ⊆ J for the smallest-μ pair of LCP(0, S + μR) from the
    support of ``start`` (None: all of J): eigenpairs of (−R_TT, S_TT), drop negative x,
    add violated w.  Returns ``(μ, x)`` (inf, None if none)."""
    n = S.shape[0]
    T = np.arange(n) if start is None else np.flatnonzero(start > 1e-3 * np.abs(start).max())
    seen = set()
    for _ in range(max_iter):
        if T.size == 0 or T.size > limits.MU_ACTIVE_SET_MAX or tuple(T) in seen:
            break
        seen.add(tuple(T))
        w, V = sl.eig(-R[np.ix_(T, T)], S[np.ix_(T, T)])
        real = np.isfinite(w) & (np.abs(w.imag) <= 1e-10 * np.maximum(1, np.abs(w.real))) & (w.real > 0)
        cands = sorted(((w[k].real, V[:, k].real) for k in np.flatnonzero(real)), key=lambda t: -t[0])
        if not cands:
            break
        nu, xT = cands[0]
        for c in cands:
            if _positive(c[1]) is not None:
                nu, xT = c
                break
        xT = xT * np.sign(xT[np.argmax(np.abs(xT))])
        mu = 1.0 / nu
        x = np.zeros(n)
        x[T] = xT
        y = (S + mu * R) @ x
        scale = (np.abs(S).max() + mu * np.abs(R).max()) * np.abs(x).max()
        neg_x = np.flatnonzero(x < -1e-12 * np.abs(x).max())
        neg_y = np.setdiff1d(np.flatnonzero(y < -1e-10 * scale), T)
        if neg_x.size == 0 and neg_y.size == 0:
            return mu, x / np.abs(x).max()
        T = np.union1d(np.setdiff1d(T, neg_x), neg_y)
    return np.inf, None
