"""Certified intervals of μ without damped flutter (docs/damping.md, docs/critical-friction.md,
"The flutter onset").

The damped sliding pencil ``Q(λ) = λ²B(μ) + λD(μ) − A(μ)`` depends on μ linearly (``D = P̃CQ̃``
carries the friction rows as A does), and so does its first companion form
``L₀(μ)z = λL₁(μ)z``, ``L₀ = [[0, I], [A, −D]]``, ``L₁ = diag(I, B)`` (on the data scaled as
:class:`~meicp.eicp.quadratic.Scaling` does: λ = s·t, s > 0, which keeps the sign of Re λ and
whether λ is real).  Damped flutter is a non-real λ with Re λ > 0.  At μ = 0 every eigenvalue
has Re λ ≤ 0 (B ≻ 0, D ⪰ 0, −A ≻ 0), so flutter starts where a non-real pair crosses the
imaginary axis, or where two real eigenvalues meet right of it and leave the axis.

:func:`damped_cover_step` proves an interval around one μ₀ from one dense eigen-decomposition
of the companion form, with the Gershgorin disks of :class:`~meicp.contact.flutter_cover.Disks`
(the lemma of :mod:`~meicp.contact.flutter_cover`, over the complex numbers: the centres
``λᵢ + δ·(S₁)ᵢᵢ`` move on lines, δ real).  Every eigenvalue of the pencil at ``μ₀ + δ`` lies in
the union of the disks; when each disk either

- lies in the open left half-plane for every |δ| ≤ Δ (its eigenvalues decay), or
- meets no other disk, and neither does its mirror image in the real axis: it then holds
  exactly one eigenvalue λ, and λ̄ — an eigenvalue too, the pencil being real — lies in the
  mirror image, hence in no other disk, hence in this one: λ = λ̄ is real,

then no eigenvalue is non-real with Re λ ≥ 0: **no damped flutter** for |μ − μ₀| ≤ Δ.  Both
tests are linear in Δ per disk and per pair, so the largest Δ is explicit.  An eigenvalue on
the imaginary axis (a mode the damping does not reach) passes neither test: the cover then
proves nothing there, as it should.

These disks grow like |δ|·Σⱼ|(S₁)ᵢⱼ|, the whole first-order coupling, although an eigenvalue
moves off its line only at second order; a lightly damped mode (Re λ ≈ −10⁻⁴ against a
coupling of order 1) then allows steps of 10⁻⁴ only.  Up to :data:`SCALED_MAX` the step is
also tried with *each disk scaled on its own* (:func:`_scaled_proof`): conjugating by the
diagonal matrix with ``1/εᵢ`` at i and 1 elsewhere shrinks disk i's off-diagonal part to
``εᵢ·Fᵢ`` and grows every other disk j by ``Fⱼᵢ(1/εᵢ − 1)`` (F the bound on the off-diagonal
entries for |δ| ≤ Δ); the smallest εᵢ ≤ 1 that keeps disk i apart from all the others is the
larger root of a quadratic per pair.  Disk i then holds exactly one eigenvalue, and as
εⱼ ≤ 1 each scaled disk lies inside its disks of the other scalings, so the 2r scaled disks
are disjoint and hold one eigenvalue each: the two tests above apply to them unchanged.  The
scaled radius is of order Δ²·F²/gap — the second order — and the step is the larger of the
two proofs.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sl
import scipy.sparse as sp

from ..eicp.quadratic import Scaling
from .flutter_cover import PAIR_BLOCK, U, CoverStep, Disks, PencilFamily

#: companion forms up to this order are also tried with disks scaled one at a time (dense,
#: order² memory and work per trial Δ)
SCALED_MAX = 2000
#: trial steps of the scaled disks: doublings from the plain disks' step, then bisections
DOUBLINGS, BISECTIONS = 40, 8


@dataclass(frozen=True)
class QuadraticFamily(PencilFamily):
    """``λ²(B₀ + μB₁) + λ(D₀ + μD₁) − (A₀ + μA₁)`` (SciPy CSR, order r): one damped sliding
    pencil as μ varies — :class:`~meicp.contact.flutter_cover.PencilFamily` with the damping's
    ``D₀``, ``D₁`` (keywords); :meth:`at` gives ``(A, B, D)``."""

    D0: sp.csr_matrix = field(default=None, kw_only=True)
    D1: sp.csr_matrix = field(default=None, kw_only=True)
    #: why a cover may not start at μ = 0 (the onset's evidence)
    at_zero = "an eigenvalue on or near the imaginary axis (a mode the damping does not reach) may grow at any μ > 0"

    @property
    def depends_on_mu(self) -> bool:
        return super().depends_on_mu or bool(self.D1.count_nonzero())

    def at(self, mu: float) -> tuple[sp.csr_matrix, sp.csr_matrix, sp.csr_matrix]:
        """The pencil ``(A(μ), B(μ), D(μ))``."""
        return (*super().at(mu), (self.D0 + mu * self.D1).tocsr())

    def companion(self, scaling: Scaling):
        """``(L₀₀, L₀₁, L₁₀, L₁₁)`` with ``L₀(μ) = L₀₀ + μL₀₁``, ``L₁(μ) = L₁₀ + μL₁₁`` the first
        companion form of the pencil scaled by ``scaling`` (t = λ/s), SciPy CSR of order 2r."""
        n, sc = self.order, scaling
        I, Z = sp.identity(n, format="csr"), sp.csr_matrix((n, n))
        L00 = sp.bmat([[Z, I], [sc.a * self.A0, -sc.d * self.D0]], format="csr")
        L01 = sp.bmat([[Z, Z], [sc.a * self.A1, -sc.d * self.D1]], format="csr")
        L10 = sp.block_diag([I, sc.b * self.B0], format="csr")
        L11 = sp.block_diag([Z, sc.b * self.B1], format="csr")
        return L00, L01, L10, L11


def _exact_scaling(sc: Scaling) -> Scaling:
    """``sc`` rounded to powers of two (s = 2^k, a = 2^m, b = a·s², d = a·s): the scaled
    companion form is then the assembled pencil's exactly, so the cover proves something of
    the assembled pencil and not of one within rounding of it."""
    s, a = 2.0 ** round(np.log2(sc.s)), 2.0 ** round(np.log2(sc.a))
    return Scaling(s, a * s * s, a * s, a)


def _eigen(L0, L1, B_diagonal: bool):
    """Eigenvalues and right eigenvectors of the companion pair (dense, complex), or
    ``(None, why)`` when one is infinite or undefined."""
    if B_diagonal:  # L₁ diagonal and positive: the standard eigenproblem of L₁⁻¹L₀
        inv = 1.0 / L1.diagonal()
        lam, X = sl.eig(inv[:, None] * L0.toarray(), overwrite_a=True)
    else:
        lam, X = sl.eig(L0.toarray(), L1.toarray(), overwrite_a=True, overwrite_b=True)
    if not np.all(np.isfinite(lam)):
        return None, "an infinite or undefined eigenvalue"
    return (np.asarray(lam, dtype=complex), np.asarray(X, dtype=complex)), ""


def damped_cover_step(family: QuadraticFamily, mu: float) -> CoverStep:
    """The certified interval ``[mu − radius, mu + radius]`` without damped flutter of
    ``family`` from one dense eigen-decomposition of its companion form at ``mu`` (module
    docstring).  ``real`` is False when a non-real eigenvalue with Re λ > 0 was computed
    there.  Serial, dense: O((2r)³)."""
    n = family.order
    if n == 0:
        return CoverStep(mu, np.inf, True, np.inf)
    A, B, _ = family.at(mu)
    scaling = _exact_scaling(Scaling.of(A.toarray(), B.toarray()))
    L00, L01, L10, L11 = family.companion(scaling)
    L1 = (L10 + mu * L11).tocsr()
    try:
        with np.errstate(all="ignore"):
            found, why = _eigen((L00 + mu * L01).tocsr(), L1, family.diagonal)
    except (np.linalg.LinAlgError, ValueError) as exc:
        return CoverStep(mu, 0.0, True, 0.0, f"the dense eigen-solve failed ({exc})")
    if found is None:
        return CoverStep(mu, 0.0, True, 0.0, why)
    lam, X = found
    real = not np.any((lam.real > 0) & (lam.imag != 0))
    try:
        with np.errstate(all="ignore"):
            disks = Disks.of(L00, L01, L10, L11, mu, lam, X, entries=2 * n <= SCALED_MAX)
            radius = 0.0 if disks is None else disks.radius(_flutter_free(disks))
            if disks is not None and disks.S0 is not None:
                radius = _scaled_radius(disks, radius, max(1.0, abs(mu)))
    except np.linalg.LinAlgError:
        return CoverStep(mu, 0.0, real, 0.0, "the eigenvectors are singular to working precision")
    closest = float(np.min(-lam.real[np.abs(lam.imag) > 0], initial=np.inf))
    if not np.isfinite(radius):
        radius = 0.0 if n > 1 else radius
    if radius <= 0:
        why = ("a non-real eigenvalue with Re λ > 0 computed" if not real else
               f"an eigenvalue within rounding of the imaginary axis or of another (closest non-real pair at "
               f"Re λ = {-closest * scaling.s:.2e})")
        return CoverStep(mu, 0.0, real, closest, why)
    return CoverStep(mu, float(radius), real, closest)


def _flutter_free(disks: Disks):
    """``largest(r)`` for :meth:`Disks.radius`: the largest Δ with every disk, for |δ| ≤ Δ,
    in the open left half-plane or alone together with its mirror image (module docstring)."""
    lam, a, b, drift = disks.lam, disks.a, disks.b, disks.drift

    def largest(r: float) -> float:
        top = -lam.real - a - r - 8 * U * (np.abs(lam.real) + a + r)
        slope = (np.abs(drift.real) + b) * (1 + 8 * U)
        with np.errstate(divide="ignore", invalid="ignore"):
            left = np.where(top > 0, np.where(slope > 0, top / slope, np.inf), 0.0)
        best = np.inf
        n = lam.size
        for lo in range(0, n, PAIR_BLOCK):
            hi = min(lo + PAIR_BLOCK, n)
            if np.all(left[lo:hi] >= best):
                continue  # these disks stay left of the axis at least as long: no pair needed
            alone = np.full(hi - lo, np.inf)
            for centres, drifts in ((None, None), (lam[lo:hi].conj(), drift[lo:hi].conj())):
                t, s = disks.separation(lo, hi, r, centres, drifts)
                if centres is not None:  # a mirror image meets its own disk: allowed
                    idx = np.arange(lo, hi)
                    t[idx - lo, idx] = np.inf
                with np.errstate(divide="ignore", invalid="ignore"):
                    q = np.where(t > 0, np.where(s > 0, t / s, np.inf), 0.0)
                alone = np.minimum(alone, q.min(axis=1))
            best = min(best, float(np.min(np.maximum(left[lo:hi], alone))))
            if best <= 0:
                return 0.0
        return best * (1 - 1e-6)

    return largest


def _scaled_radius(disks: Disks, proved: float, scale: float) -> float:
    """The longest step proved by the scaled disks, starting from the plain disks' ``proved``
    (doubled while it holds, then bisected); ``proved`` when they do no better."""
    good = proved
    trial = 2 * proved if proved > 0 else 1e-6 * scale
    bad = np.inf
    for _ in range(DOUBLINGS):
        if trial > disks.cap or not _scaled_proof(disks, trial):
            bad = trial
            break
        good, trial = trial, 2 * trial
    if good == 0 or not np.isfinite(bad):
        return good
    for _ in range(BISECTIONS):
        mid = 0.5 * (good + bad)
        good, bad = (mid, bad) if _scaled_proof(disks, mid) else (good, mid)
    return good


def _scaled_proof(disks: Disks, delta: float) -> bool:
    """Whether the disks scaled one at a time (module docstring) prove "no damped flutter"
    for every |δ| ≤ ``delta``."""
    lam, drift = disks.lam, disks.drift
    n = lam.size
    r = disks.rest(delta)
    if not np.isfinite(r):
        return False
    F = disks.S0 + delta * disks.S1
    own = np.diag(disks.S0).copy()  # S₀'s diagonal stays in each disk's own radius, unscaled
    F[np.diag_indices(n)] = 0.0
    rr = (r + disks.e0 + delta * disks.e1) * (1 + 4 * U)  # R and rounding: by rows only
    rows = F.sum(axis=1) * (1 + n * U)
    eps = np.empty(n)
    for lo in range(0, n, PAIR_BLOCK):
        hi = min(lo + PAIR_BLOCK, n)
        idx = np.arange(lo, hi)
        dist = np.abs(lam[lo:hi, None] - lam[None, :])
        gap = dist - delta * np.abs(drift[lo:hi, None] - drift[None, :]) * (1 + 8 * U)
        col = F[:, lo:hi].T  # col[i, j] = F_ji: what scaling disk i puts into disk j
        rest = own[lo:hi, None] + rr[lo:hi, None] + (rows[None, :] - col) + own[None, :]
        h = gap - rest - 8 * U * (dist + rest + rows[None, :])
        c = (col + rr[None, :]) * (1 + 4 * U)
        Fi = rows[lo:hi, None]
        disc = h * h - 4 * Fi * c
        fine = (h > 0) & (disc >= 0)
        fine[idx - lo, idx] = True
        if not fine.all():
            return False
        root = np.sqrt(np.maximum(disc, 0.0))
        with np.errstate(divide="ignore", invalid="ignore"):
            low = np.where(fine, 2 * c / (h + root), 0.0) * (1 + 16 * U)
            high = np.where(Fi > 0, (h + root) / (2 * Fi), np.inf) * (1 - 16 * U)
        low[idx - lo, idx], high[idx - lo, idx] = 0.0, np.inf
        e = low.max(axis=1)
        if np.any(e > np.minimum(high.min(axis=1), 1.0)):
            return False
        eps[lo:hi] = e
    radius = (eps * rows + own + rr) * (1 + 8 * U)
    reach = lam.real + delta * np.abs(drift.real) + radius
    left = reach + 8 * U * (np.abs(lam.real) + radius) < 0
    for i in np.flatnonzero(~left):  # alone with its mirror image: real
        mirror = np.abs(lam[i].conjugate() - lam) - delta * np.abs(drift[i].conjugate() - drift) * (1 + 8 * U)
        mirror[i] = np.inf
        if not np.all(mirror - (radius[i] + radius) * (1 + 8 * U) - 8 * U * np.abs(lam[i]) > 0):
            return False  # NaN included
    return True


__all__ = ["QuadraticFamily", "damped_cover_step"]
