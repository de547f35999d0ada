"""Certified flutter-free intervals of μ for a family of sliding pencils (docs/flutter.md §6,
docs/critical-friction.md, "The flutter onset").

The sliding pencil ``(σB(μ) − A(μ))x = 0`` depends on μ linearly: ``A(μ) = A₀ + μA₁``,
``B(μ) = B₀ + μB₁`` (``B₁ = 0`` with lumped mass, B then diagonal, on a base contact and an
interface alike; a grazing contact, or a one-row layer between two interfaces, puts μ into B).  A non-real σ can only appear where two real eigenvalues
meet, so an interval of μ on which every eigenvalue stays real and simple is flutter-free.
:func:`cover_step` proves such an interval around one μ₀ from one dense eigen-decomposition:

*Lemma.*  Let X, Y be real, Λ = diag(λ) real, and at μ₀ let ``N_A = Y A(μ₀) X − Λ``,
``N_B = Y B(μ₀) X − I``, ``G = Y A₁ X``, ``E = Y B₁ X``.  For ``μ = μ₀ + δ`` with
``τ = ‖N_B‖∞ + |δ|‖E‖∞ < 1`` the pencil has the eigenvalues of
``(I + N_B + δE)⁻¹(Λ + N_A + δG) = Λ + S₀ + δS₁ + R``, ``S₀ = N_A − N_BΛ``, ``S₁ = G − EΛ``,
``‖R‖∞ ≤ τ(‖N_A‖∞ + |δ|‖G‖∞) + τ²/(1 − τ)(‖Λ‖∞ + ‖N_A‖∞ + |δ|‖G‖∞)``.  Gershgorin's disks
of that matrix have the real centres ``λᵢ + δ(S₁)ᵢᵢ`` and radii at most
``Σⱼ|(S₀)ᵢⱼ| + |δ|Σⱼ≠ᵢ|(S₁)ᵢⱼ| + ‖R‖∞``.  If the n disks are pairwise disjoint, each holds
exactly one eigenvalue; a disk centred on the real axis holds the conjugate of each of its
eigenvalues too, so that one eigenvalue is real: **every σ is real and simple — no
flutter**.  Disjointness is a pair of linear inequalities in |δ| per pair of disks, so the
largest Δ with all of them for |δ| ≤ Δ is explicit.

X, Λ come from LAPACK (QR of ``D^{-1/2}AD^{-1/2}`` when B = D is diagonal, QZ otherwise,
``eigh`` at a symmetric point), ``Y = (B(μ₀)X)⁻¹`` computed; nothing of their accuracy is
assumed: N_A, N_B, G, E are evaluated with a bound on their rounding error (``γ|Y||M||X|``,
row sums by matrix–vector products), so the interval is a proof for the pencil built from
the assembled K and M.  The columns of X are balanced (‖xᵢ‖ = ‖yᵢ‖, by powers of two) because
Gershgorin's row sums depend on that scaling.  Compared with the Bauer–Fike radius
``κ₂(X)·|δ|·‖C₁‖₂`` of the symmetrised matrix, these disks move with the first-order drift of
each eigenvalue and charge only each row's coupling: 3–5 times longer steps on the shipped
two-layer scene (measured), and the lemma covers a μ-dependent, nonsymmetric B as well.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sl
import scipy.sparse as sp

#: unit roundoff
U = np.finfo(float).eps / 2
#: pairs of disks compared at once (memory: a block of this many rows of n pairs)
PAIR_BLOCK = 256


@dataclass(frozen=True)
class PencilFamily:
    """``(A₀ + μA₁, B₀ + μB₁)`` (SciPy CSR, order r): one sliding pencil as μ varies, with
    the ``maps`` it was reduced with (:class:`~meicp.contact.maps.ReducedSystem`, for the mode
    shapes) and its grazing ``branch`` label ("" without grazing contacts)."""

    A0: sp.csr_matrix
    A1: sp.csr_matrix
    B0: sp.csr_matrix
    B1: sp.csr_matrix
    maps: object = None
    branch: str = ""
    #: why a cover may not start at μ = 0 (the onset's evidence)
    at_zero = "a degenerate eigenvalue of the symmetric pencil may split into a non-real pair at any μ > 0"

    @property
    def order(self) -> int:
        return self.A0.shape[0]

    @property
    def diagonal(self) -> bool:
        """B independent of μ, diagonal and positive (lumped mass, no grazing contact)."""
        if self.B1.count_nonzero():
            return False
        d = self.B0.diagonal()
        return bool(np.all(d > 0)) and self.B0.count_nonzero() == np.count_nonzero(d)

    @property
    def depends_on_mu(self) -> bool:
        return bool(self.A1.count_nonzero() or self.B1.count_nonzero())

    def at(self, mu: float) -> tuple[sp.csr_matrix, sp.csr_matrix]:
        """The pencil ``(A(μ), B(μ))``."""
        return (self.A0 + mu * self.A1).tocsr(), (self.B0 + mu * self.B1).tocsr()


@dataclass(frozen=True)
class CoverStep:
    """What one eigen-decomposition at ``mu`` proves: every μ' with |μ' − mu| ≤ ``radius`` has
    only real, simple σ (``radius`` 0: nothing, not even ``mu``).  ``real``: every computed
    eigenvalue was real (False: a non-real pair was computed there, flutter is possible);
    ``gap``: the smallest distance between two computed eigenvalues; ``why``: when nothing is
    proved, why."""

    mu: float
    radius: float
    real: bool
    gap: float = 0.0
    why: str = ""


def _is_symmetric(M) -> bool:
    return (M != M.T).nnz == 0


def _eigen(family: PencilFamily, mu: float):
    """Real eigenvalues (sorted) and real right eigenvectors of the pencil at ``mu``, or
    ``(None, why, real)`` when they are not all real and finite."""
    A, B = family.at(mu)
    A_dense = A.toarray()
    if family.diagonal:
        s = 1.0 / np.sqrt(family.B0.diagonal())
        C = s[:, None] * A_dense * s[None, :]
        if mu == 0 and _is_symmetric(family.A0):
            w, V = np.linalg.eigh(0.5 * (C + C.T))  # C is symmetric; the mean only fixes rounding
        else:
            w, V = sl.eig(C, overwrite_a=True)
        X = s[:, None] * V
    else:
        B_dense = B.toarray()
        if mu == 0 and _is_symmetric(family.A0) and _is_symmetric(family.B0):
            try:
                w, X = sl.eigh(A_dense, B_dense)
            except np.linalg.LinAlgError:
                w, X = sl.eig(A_dense, B_dense)
        else:
            w, X = sl.eig(A_dense, B_dense)
    if not np.all(np.isfinite(w)):
        return None, "an infinite or undefined eigenvalue", True
    if np.any(np.asarray(w).imag != 0):
        return None, "non-real eigenvalues computed", False
    w, X = np.asarray(w).real, np.asarray(X).real
    order = np.argsort(w, kind="stable")
    return (w[order], X[:, order]), "", True


def _gamma(n: int) -> float:
    """A generous bound on the relative rounding of a product of two n-term inner products."""
    return 1.01 * (2 * n + 10) * U


def _rows(M) -> np.ndarray:
    return np.asarray(abs(M).sum(axis=1)).ravel()


def cover_step(family: PencilFamily, mu: float) -> CoverStep:
    """The certified flutter-free interval ``[mu − radius, mu + radius]`` of ``family`` from
    one dense eigen-decomposition at ``mu`` (the lemma of the module docstring).  Serial,
    dense: O(r³)."""
    n = family.order
    if n == 0:
        return CoverStep(mu, np.inf, True, np.inf)
    try:
        with np.errstate(all="ignore"):
            found, why, real = _eigen(family, mu)
    except (np.linalg.LinAlgError, ValueError) as exc:
        return CoverStep(mu, 0.0, True, 0.0, f"the dense eigen-solve failed ({exc})")
    if found is None:
        return CoverStep(mu, 0.0, real, 0.0, why)
    lam, X = found
    gap = float(np.min(np.diff(lam))) if n > 1 else np.inf
    try:
        with np.errstate(all="ignore"):
            radius = _radius(family, mu, lam, X)
    except np.linalg.LinAlgError:  # B(μ)X singular to working precision: nothing to build on
        return CoverStep(mu, 0.0, True, gap, "the eigenvectors are singular to working precision")
    if not np.isfinite(radius) and n > 1:
        radius = 0.0
    if radius <= 0:
        return CoverStep(mu, 0.0, True, gap, f"two eigenvalues within rounding of each other (gap {gap:.2e})")
    return CoverStep(mu, float(radius), True, gap)


def _radius(family: PencilFamily, mu: float, lam: np.ndarray, X: np.ndarray) -> float:
    disks = Disks.of(family.A0, family.A1, family.B0, family.B1, mu, lam, X)
    return 0.0 if disks is None else disks.radius(disks.disjoint)


@dataclass
class Disks:
    """The Gershgorin disks of the lemma (module docstring) around the eigenvalues ``lam`` of
    ``(A(μ₀), B(μ₀))``, real or complex: disk i has the centre ``lam[i] + δ·drift[i]`` and a
    radius at most ``a[i] + |δ|·b[i] + ‖R‖∞`` for ``μ = μ₀ + δ``; :meth:`rest` bounds ‖R‖∞
    for ``|δ| ≤ Δ`` and ``cap`` is the largest Δ the lemma allows (τ < 1/2)."""

    lam: np.ndarray
    a: np.ndarray
    b: np.ndarray
    drift: np.ndarray
    nA: float
    nB: float
    nG: float
    nE: float
    amax: float
    cap: float
    #: with ``entries``: entrywise bounds |S₀| and |S₁| (S₁'s diagonal zeroed: it is ``drift``)
    #: and the row sums of their rounding errors, ``e0`` and ``e1``
    S0: np.ndarray | None = None
    S1: np.ndarray | None = None
    e0: np.ndarray | None = None
    e1: np.ndarray | None = None

    @classmethod
    def of(cls, A0, A1, B0, B1, mu: float, lam: np.ndarray, X: np.ndarray, *,
           entries: bool = False) -> "Disks | None":
        """The disks from the eigenvectors X (columns) at ``mu``, every product with a bound on
        its rounding error; None when ‖N_B‖∞ ≥ 1/2 (the eigenvectors too inaccurate for the
        lemma).  LinAlgError when B(μ₀)X is singular.  ``entries``: keep the entrywise
        bounds too (dense, order²), for disks scaled one at a time."""
        n = lam.size
        B = (B0 + mu * B1).tocsr()
        Y = np.linalg.inv(B @ X)
        # balance: ‖xᵢ‖ = ‖yᵢ‖ (powers of two, exact), so each row of Y·M·X weighs both alike
        p = np.exp2(np.round(0.5 * np.log2(np.linalg.norm(Y, axis=1) / np.linalg.norm(X, axis=0))))
        p = np.where(np.isfinite(p) & (p > 0), p, 1.0)
        X, Y = X * p[None, :], Y / p[:, None]
        # complex products: each multiply–add rounds up to about √2·2u, so a factor 4 is ample
        g = _gamma(n) * (4.0 if np.iscomplexobj(X) or np.iscomplexobj(Y) else 1.0)
        absY = np.abs(Y)
        xsum = np.abs(X).sum(axis=1)  # |X|·1

        def product(M):
            """Y·M·X and the row sums of a bound on its rounding error, γ|Y|(|M|(|X|1))."""
            return Y @ (M @ X), g * (absY @ (abs(M) @ xsum))

        P0, e_P0 = product(A0)
        P1, e_P1 = product(A1)
        Q0, e_Q0 = product(B0)
        Q1, e_Q1 = (product(B1) if B1.count_nonzero() else (np.zeros((n, n)), np.zeros(n)))
        alam = np.abs(lam)
        amax = float(np.max(alam))
        m = abs(mu)
        # N_A = P0 + μP1 − Λ, N_B = Q0 + μQ1 − I, G = P1, E = Q1, each with the row sums of its error
        N_A = P0 + mu * P1
        N_A[np.diag_indices(n)] -= lam
        e_NA = (e_P0 + m * e_P1) * (1 + 4 * U) + 4 * U * (_rows(P0) + m * _rows(P1) + alam)
        N_B = Q0 + mu * Q1
        N_B[np.diag_indices(n)] -= 1.0
        e_NB = (e_Q0 + m * e_Q1) * (1 + 4 * U) + 4 * U * (_rows(Q0) + m * _rows(Q1) + 1.0)
        rows_NA = _rows(N_A) * (1 + n * U) + e_NA
        rows_NB = _rows(N_B) * (1 + n * U) + e_NB
        nA, nB = float(rows_NA.max()), float(rows_NB.max())
        nG = float((_rows(P1) * (1 + n * U) + e_P1).max())
        nE = float((_rows(Q1) * (1 + n * U) + e_Q1).max())
        if not nB < 0.5:
            return None
        # S₀ = N_A − N_BΛ, wholly in the radii; S₁ = G − EΛ: its diagonal moves the centres
        a = (rows_NA + (np.abs(N_B) @ alam) * (1 + n * U) + e_NB * amax) * (1 + 4 * U)
        S1 = P1 - Q1 * lam[None, :]
        e_S1 = (e_P1 + e_Q1 * amax) * (1 + 4 * U) + 4 * U * (_rows(P1) + np.abs(Q1) @ alam)
        drift = np.diag(S1).copy()
        b = (_rows(S1) - np.abs(drift)) * (1 + n * U) + e_S1
        cap = (0.5 - nB) / nE * (1 - 1e-6) if nE > 0 else np.inf  # τ < 1/2 on the whole interval
        if not entries:
            return cls(lam, a, b, drift, nA, nB, nG, nE, amax, cap)
        S0 = (np.abs(N_A) + np.abs(N_B) * alam[None, :]) * (1 + (n + 4) * U)
        S1abs = np.abs(S1) * (1 + (n + 4) * U)
        S1abs[np.diag_indices(n)] = 0.0
        e0 = (e_NA + e_NB * amax) * (1 + 4 * U)
        return cls(lam, a, b, drift, nA, nB, nG, nE, amax, cap, S0, S1abs, e0, e_S1)

    def rest(self, delta: float) -> float:
        """The bound on ‖R‖∞ for |δ| ≤ delta (inf when τ ≥ 1/2)."""
        tau = self.nB + delta * self.nE
        if not tau < 0.5:
            return np.inf
        return (tau * (self.nA + delta * self.nG)
                + tau * tau / (1 - tau) * (self.amax + self.nA + delta * self.nG)) * (1 + 8 * U)

    def separation(self, lo: int, hi: int, r: float, centres: np.ndarray | None = None, drifts=None):
        """For the disks lo..hi−1 (or, given, other ``centres`` moving by ``drifts`` with the
        same radii) against every disk j: ``(top, slope)`` with the two disjoint for every
        |δ| ≤ Δ when ``Δ·slope < top`` (a disk and itself: top = inf)."""
        i = slice(lo, hi)
        c = self.lam[i] if centres is None else centres
        d = self.drift[i] if drifts is None else drifts
        gap = np.abs(self.lam[None, :] - c[:, None])
        need = self.a[i, None] + self.a[None, :] + 2 * r
        top = gap - need - 8 * U * (gap + need)
        slope = (np.abs(self.drift[None, :] - d[:, None]) + self.b[i, None] + self.b[None, :]) * (1 + 8 * U)
        idx = np.arange(lo, hi)
        top[idx - lo, idx] = np.inf
        return top, slope

    def disjoint(self, r: float) -> float:
        """The largest Δ with every pair of disks disjoint for |δ| ≤ Δ, ‖R‖∞ ≤ r (0: none):
        then each holds one eigenvalue, real when its centre is."""
        best = np.inf
        n = self.lam.size
        for lo in range(0, n, PAIR_BLOCK):
            top, slope = self.separation(lo, min(lo + PAIR_BLOCK, n), r)
            if np.any(top <= 0):
                return 0.0
            with np.errstate(divide="ignore"):
                best = min(best, float(np.min(top / slope)))
        return best * (1 - 1e-6)

    def radius(self, largest) -> float:
        """The largest Δ ≤ ``cap`` for which ``largest(‖R‖∞ bound)`` holds with the bound of
        that Δ itself (‖R‖∞ grows with Δ: halved until it does); 0 when none."""
        delta = min(largest(self.rest(0.0)), self.cap)
        if not np.isfinite(delta):  # nothing drifts or couples: only ‖R‖∞ limits the interval
            if self.nG == 0:
                return np.inf
            delta = 1e6
        for _ in range(200):
            if delta <= 0 or largest(self.rest(delta)) >= delta:
                return delta
            delta *= 0.5
        return 0.0


__all__ = ["CoverStep", "Disks", "PencilFamily", "cover_step"]
