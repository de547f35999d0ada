"""The dense path of the flutter analysis (docs/flutter.md): every eigenvalue of a sliding
pencil by LAPACK, each with its rounding radius, and the verdict — a proof either way
unless borderline (:mod:`meicp.contact.flutter` chooses the path).

QR on D^{-1/2}AD^{-1/2} when B = D is diagonal, else QZ; each eigenvalue's radius
``r = n·u·(‖A‖₁ + |σ|‖B‖₁)·κ(σ)``, κ from the left and right eigenvectors: non-real when
|Im σ| > r; certified real when |Im σ| ≤ r and its disk meets no other; else borderline.
flutter = True with a certified non-real mode, False when every eigenvalue is certified real
(a proof), None otherwise.  A symmetric A with symmetric positive definite B is proved
flutter-free without QZ.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sl
import scipy.sparse as sp

from .flutter_growth import FlutterGrowth, dense_growth
from .flutter_verdict import RESIDUAL_TOL, FlutterCandidate, PencilFlutter, RejectedPair
from .result import growth_frequency

#: the bracket of a pencil proved flutter-free: no non-real eigenvalue at all
NO_FLUTTER = FlutterGrowth(0.0, 0.0, "no flutter (a proof)")


def _norm1(M: np.ndarray) -> float:
    return float(np.abs(M).sum(axis=0).max()) if M.size else 0.0


def _fastest_first(modes: list) -> list:
    return sorted(modes, key=lambda m: (-growth_frequency(m.sigma)[0], -abs(m.sigma.imag)))


def _normalise(x: np.ndarray) -> np.ndarray:
    """‖x‖₂ = 1 with its largest entry real positive (a canonical phase)."""
    x = np.asarray(x, dtype=complex)
    k = int(np.argmax(np.abs(x)))
    return x / (x[k] / abs(x[k]) * np.linalg.norm(x)) if x[k] != 0 else x


def backward_error(A, B, sigma: complex, x: np.ndarray, norm_A: float, norm_B: float) -> float:
    """‖Ax − σBx‖₂ / ((‖A‖₁ + |σ|‖B‖₁)‖x‖₂) (A, B dense or SciPy), evaluated on A/‖A‖₁ and
    B/‖B‖₁ so that extreme scales do not overflow; inf when it still cannot be evaluated
    (such a pair is never certified)."""
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        x = x / np.linalg.norm(x)
        ratio = norm_B / norm_A
        r = (A @ x) / norm_A - (sigma * ratio) * ((B @ x) / norm_B)
        value = np.linalg.norm(r) / (1.0 + abs(sigma) * ratio)
    return float(value) if np.isfinite(value) and np.isfinite(ratio) and ratio > 0 else float("inf")


def _symmetric_definite(A: np.ndarray, B: np.ndarray) -> bool:
    if not (np.array_equal(A, A.T) and np.array_equal(B, B.T)):
        return False
    try:
        np.linalg.cholesky(B)
    except np.linalg.LinAlgError:
        return False
    return True


def dense_flutter(A, B, *, residual_tol: float = RESIDUAL_TOL, radius_factor: float | None = None) -> PencilFlutter:
    """Every flutter mode of the pencil (A, B) (NumPy or SciPy, serial) and the verdict, a
    proof either way unless borderline (module docstring).  ``radius_factor``: the multiple
    of u·(‖A‖ + |σ|‖B‖)·κ that counts as rounding (default n)."""
    A = A.toarray() if sp.issparse(A) else np.asarray(A, dtype=float)
    B = B.toarray() if sp.issparse(B) else np.asarray(B, dtype=float)
    n = A.shape[0]
    if n == 0:
        return PencilFlutter(False, evidence="no retained DOF: nothing can move (a proof)", complete=True,
                             growth=NO_FLUTTER)
    if _symmetric_definite(A, B):
        return PencilFlutter(False, evidence="symmetric A and symmetric positive definite B: every σ is real "
                                             "(no friction coupling reaches the retained DOFs) — a proof",
                             complete=True, growth=NO_FLUTTER)
    if not (np.all(np.isfinite(A)) and np.all(np.isfinite(B))):
        return PencilFlutter(None, evidence="the pencil has entries that are not finite: undecided",
                             growth=FlutterGrowth(0.0, None, "entries not finite: no bound"))
    try:
        with np.errstate(over="ignore", invalid="ignore", divide="ignore", under="ignore"):
            return _dense_spectrum(A, B, residual_tol, radius_factor)
    except (np.linalg.LinAlgError, ValueError) as exc:  # QZ did not converge, or NaN came out
        return PencilFlutter(None, evidence=f"the dense eigen-solve (LAPACK) failed ({exc}): undecided",
                             growth=FlutterGrowth(0.0, None, "the dense eigen-solve failed: no bound"))


def _dense_spectrum(A: np.ndarray, B: np.ndarray, residual_tol: float, radius_factor) -> PencilFlutter:
    n = A.shape[0]
    norm_A, norm_B = _norm1(A), _norm1(B)
    d = np.diag(B)
    if np.all(d > 0) and np.count_nonzero(B) == np.count_nonzero(d):
        s = 1.0 / np.sqrt(d)
        C = s[:, None] * A * s[None, :]
        w, VL, VR = sl.eig(C, left=True, right=True)
        X = s[:, None] * VR
        kappa = (np.linalg.norm(VL, axis=0) * np.linalg.norm(VR, axis=0)
                 / np.maximum(np.abs(np.einsum("ij,ij->j", VL.conj(), VR)), 1e-300))
        scale = _norm1(C) + np.abs(w)
        infinite = np.zeros(n, dtype=bool)
        how = "dense QR of D^-1/2 A D^-1/2 (B = D diagonal)"
    else:
        (alpha, beta), VL, VR = sl.eig(A, B, left=True, right=True, homogeneous_eigvals=True)
        # infinite: β at the rounding level of B *relative to* α on A's scale (|σ|·‖B‖ beyond
        # ‖A‖/(n·u)); without the norms a change of units (K ×1e7, M ÷1e7, every σ ×1e14) made
        # every finite σ past 1/(n·u) "infinite" and the dense path proved flutter absent
        infinite = np.abs(beta) * norm_A <= n * np.finfo(float).eps * np.abs(alpha) * norm_B
        w = np.where(infinite, np.inf, alpha / np.where(infinite, 1.0, beta))
        X = VR
        kappa = (np.linalg.norm(VL, axis=0) * np.linalg.norm(VR, axis=0)
                 / np.maximum(np.abs(np.einsum("ij,ij->j", VL.conj(), B @ VR)), 1e-300))
        scale = norm_A + np.where(infinite, 0.0, np.abs(w)) * norm_B
        how = "dense QZ of (A, B)"
    factor = float(n) if radius_factor is None else radius_factor
    radius = np.where(infinite, np.inf, factor * (np.finfo(float).eps / 2) * scale * kappa)
    radius = np.where(np.isfinite(radius), radius, np.inf)  # no bound: never certified either way
    unresolved = ~infinite & ~np.isfinite(w)
    finite = ~infinite & ~unresolved
    nonreal = finite & (np.abs(w.imag) > radius)
    near_axis = finite & ~nonreal
    certified_real = np.zeros(n, dtype=bool)
    fin = np.flatnonzero(finite)
    order = fin[np.argsort(w[fin].real)]
    re = w[order].real
    reach = radius[order].max() if order.size else 0.0
    for i in np.flatnonzero(near_axis):  # certified when its disk meets no other eigenvalue's disk
        lo = np.searchsorted(re, w[i].real - radius[i] - reach, "left")
        hi = np.searchsorted(re, w[i].real + radius[i] + reach, "right")
        near = order[lo:hi]
        near = near[near != i]
        certified_real[i] = not np.any(np.abs(w[near] - w[i]) <= radius[near] + radius[i])
    borderline = (near_axis & ~certified_real) | unresolved
    modes, rejected = [], []
    for i in np.flatnonzero(nonreal & (w.imag > 0)):
        res = backward_error(A, B, complex(w[i]), X[:, i], norm_A, norm_B)
        if res <= residual_tol:
            modes.append(FlutterCandidate(complex(w[i]), _normalise(X[:, i]), res, float(radius[i]), how))
        else:
            rejected.append(RejectedPair(complex(w[i]), res))
    counts = {"eigenvalues": n, "nonreal_pairs": int(nonreal.sum()) // 2,
              "certified_real": int(certified_real.sum()), "borderline": int(borderline.sum()),
              "infinite": int(infinite.sum()), "rejected": len(rejected)}
    flutter = True if modes else (None if borderline.any() or rejected else False)
    infinite_note = f", {int(infinite.sum())} infinite (not modes)" if infinite.any() else ""
    rejected_note = (f", {len(rejected)} non-real pair(s) failing the residual gate {residual_tol:g} "
                     "(not reported)" if rejected else "")
    evidence = (f"{how} of all {n} eigenvalues{infinite_note}: {counts['nonreal_pairs']} non-real pair(s), "
                f"{counts['certified_real']} certified real, {counts['borderline']} borderline "
                f"(non-reality at rounding level){rejected_note}"
                + (" — a proof" if flutter is not None else ": undecided"))
    growth = dense_growth(w, radius, ~infinite & ~certified_real, modes, how)
    return PencilFlutter(flutter, _fastest_first(modes), evidence, complete=True, counts=counts, rejected=rejected,
                         growth=growth)
