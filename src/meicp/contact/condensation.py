"""The MEiCP of a contact state condensed exactly onto its complementarity DOFs J.

For every assignment of states ``P̃ = Q̃ᵀ + P̃_μ`` (:mod:`.maps`: a slip row is
``s·e_tᵀ + μ·e_nᵀ``, so ``P̃_μ = diag(μ)·P̃₁`` has one ``μ·e_nᵀ`` row per slip DOF, all in
J), hence

    H(σ) = σB − A = σ(M̃ + N_M) + K̃ + N,
    K̃ = Q̃ᵀKQ̃ (symmetric),  M̃ = Q̃ᵀMQ̃ (SPD),  N = P̃_μKQ̃,  N_M = P̃_μMQ̃  (rows in J only).

On the free DOFs F (every DOF not in J) w_F = 0 gives ``x_F = −H_FF⁻¹H_FJ x_J`` with
``H_FF(σ) = σM̃_FF + K̃_FF`` symmetric positive definite for σ ≥ 0 (the lattice is held once
the contact DOFs are), and

    w_J = G(σ)x_J,   G(σ) = H_JJ − H_JF H_FF⁻¹ H_FJ = S(σ) + R(σ),
    S(σ) = Schur complement on J of σM̃ + K̃ (symmetric),
    R(σ) = P_JJ − P_JF H_FF⁻¹ H_FJ,  P = σN_M + N (the friction rows).

So a real σ ≥ 0 solves the MEiCP iff LCP(0, G(σ)) has a solution x_J ≠ 0: the tests of
:mod:`meicp.lcp.certificates` on the dense |J|×|J| matrix G decide it.  With μ as a
parameter (one μ for every contact, ``friction="unit"``) ``G = S + μR``.

The Ξ blocks ``KK = (σM̃ + K̃)_JF H_FF⁻¹ (σM̃ + K̃)_FJ``, ``NK = P_JF H_FF⁻¹ (σM̃ + K̃)_FJ``
and ``Z = P_JF H_FF⁻¹ P_JFᵀ`` serve the σ-windows (:mod:`.windows`).  Every block carries a
bound of its error: rigorous for the solves (:func:`condense`, from the residuals and a
certified lower bound τ of λ_min(K̃_FF, M̃_FF)), measured for MUMPS' Schur complement
(:mod:`meicp.petsc.schur`).  Pure NumPy/SciPy: the factorisations are the caller's.
"""
from __future__ import annotations

import time
from contextlib import AbstractContextManager
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spl

EPS = np.finfo(float).eps


@dataclass
class PencilPieces:
    """The split pencil (SciPy CSR): ``A = −(K̃ + N)``, ``B = M̃ + N_M``; J the
    complementarity positions.  ``N``, ``N_M`` carry the scene's μ (``friction="scene"``) or
    a unit μ (``"unit"``: μ is the caller's parameter)."""

    Kt: sp.csr_matrix
    Mt: sp.csr_matrix
    N: sp.csr_matrix
    NM: sp.csr_matrix
    J: np.ndarray

    @property
    def n(self) -> int:
        return self.Kt.shape[0]

    @property
    def F(self) -> np.ndarray:
        mask = np.ones(self.n, dtype=bool)
        mask[self.J] = False
        return np.flatnonzero(mask)

    def A(self, mu: float = 1.0) -> sp.csr_matrix:
        return (-(self.Kt + mu * self.N)).tocsr()

    def B(self, mu: float = 1.0) -> sp.csr_matrix:
        return (self.Mt + mu * self.NM).tocsr()

    def H(self, sigma: float, mu: float = 1.0) -> sp.csr_matrix:
        return (sigma * self.B(mu) - self.A(mu)).tocsr()

    @property
    def mass_is_diagonal(self) -> bool:
        """B diagonal for every μ: lumped mass, a base contact or an interface in centre-of-mass
        coordinates (the σ-windows need it)."""
        off = self.Mt - sp.diags(self.Mt.diagonal())
        return off.count_nonzero() == 0 and self.NM.count_nonzero() == 0

    def bordered(self, sigma: float) -> tuple[sp.csr_matrix, np.ndarray]:
        """``(𝓗, rows)``: 𝓗 = [[σM̃ + K̃, P_Jᵀ], [P_J, 0]] (symmetric, P = σN_M + N) and the
        rows J ∪ extra whose Schur complement is [[S, Rᵀ], [R, −Z]] (S, R, Z of σ)."""
        H0, H1, rows = self.bordered_parts()
        return (H0 + sigma * H1).tocsr(), rows

    def bordered_parts(self) -> tuple[sp.csr_matrix, sp.csr_matrix, np.ndarray]:
        """``(𝓗₀, 𝓗₁, rows)`` with 𝓗(σ) = 𝓗₀ + σ𝓗₁ (:meth:`bordered`), for callers that
        build 𝓗(σ) on one pattern for every σ (:attr:`~.condenser.Condenser.padded_parts`)."""
        N_J, NM_J = self.N[self.J], self.NM[self.J]
        H0 = sp.bmat([[self.Kt, N_J.T], [N_J, None]], format="csr")
        H1 = sp.bmat([[self.Mt, NM_J.T], [NM_J, None]], format="csr")
        return H0, H1, np.concatenate([self.J, self.n + np.arange(self.J.size)])


def pieces_of(K, M, maps, *, friction: str = "scene") -> PencilPieces:
    """Split the pencil of :func:`~meicp.contact.maps.reduced_system`'s maps (K, M SciPy).
    ``friction="scene"``: N with each contact's own μ (``diag(μ)·P̃₁``); ``"unit"``: μ = 1
    (``P̃₁``)."""
    if friction not in ("scene", "unit"):
        raise ValueError(f"friction must be 'scene' or 'unit', got {friction!r}")
    Q = maps.Q
    Pmu = maps.friction_rows() if friction == "scene" else maps.P1
    KQ, MQ = (K @ Q).tocsr(), (M @ Q).tocsr()
    out = [(Q.T @ KQ).tocsr(), (Q.T @ MQ).tocsr(), (Pmu @ KQ).tocsr(), (Pmu @ MQ).tocsr()]
    for X in out:
        X.eliminate_zeros()
    Kt = out[0]
    out[0] = (0.5 * (Kt + Kt.T)).tocsr()  # symmetric by construction; drop rounding asymmetry
    return PencilPieces(*out, np.asarray(maps.J))


@dataclass
class Condensed:
    """S(σ), R(σ) (dense, on J) with ``error_S``, ``error_R`` bounds of ‖Ŝ − S‖₂, ‖R̂ − R‖₂;
    the Ξ blocks ``KK``, ``NK``, ``Z`` (with ``error_Z``) when asked; ``error_kind`` says
    whether the errors are ``"bounded"`` (rigorous) or ``"measured"``."""

    sigma: float
    S: np.ndarray
    R: np.ndarray
    error_S: float
    error_R: float
    error_kind: str = "bounded"
    Z: np.ndarray | None = None
    error_Z: float = np.inf
    KK: np.ndarray | None = None
    NK: np.ndarray | None = None
    seconds: dict = field(default_factory=dict)

    def G(self, mu: float = 1.0) -> np.ndarray:
        return self.S + mu * self.R

    def error(self, mu: float = 1.0) -> float:
        return self.error_S + abs(mu) * self.error_R


#: a factorisation of H_FF: ``factor(H_FF)`` is a context manager giving ``solve(block)``
#: for dense blocks of right-hand sides (every rank holds the whole block)
Factor = Callable[[sp.csr_matrix], AbstractContextManager]


def condense(pieces: PencilPieces, sigma: float, factor: Factor, *, tau: float | None = None,
             xi: bool = False, block: int = 128) -> Condensed:
    """S(σ), R(σ) (and the Ξ blocks with ``xi``) by solves with one factor of H_FF(σ),
    ``block`` right-hand sides at a time (memory |F|·block doubles).

    Error bound: ``X̂ − X = H_FF⁻¹E`` with E the residual, ``‖H_FF⁻¹‖₂ ≤ 1/((τ + σ)·m_min)``
    (τ ≤ λ_min(K̃_FF, M̃_FF) certified, m_min the smallest entry of a diagonal M̃_FF — a
    non-diagonal mass, or no τ, gives infinite bounds); the residual's own rounding is
    charged entrywise (``γ(|H_FF||X̂| + |H_FJ|)``)."""
    J, F = pieces.J, pieces.F
    t0 = time.perf_counter()
    Kt, Mt = pieces.Kt, pieces.Mt
    P = (sigma * pieces.NM + pieces.N).tocsr()
    Hs = (sigma * Mt + Kt).tocsr()
    H_FF, H_FJ = Hs[F][:, F].tocsr(), Hs[F][:, J].tocsc()
    S, R = Hs[J][:, J].toarray(), P[J][:, J].toarray()
    KJF, PJF = Hs[J][:, F].tocsr(), P[J][:, F].tocsr()
    nJ = J.size
    KK = np.zeros((nJ, nJ)) if xi else None
    NK = np.zeros((nJ, nJ)) if xi else None
    Z = np.zeros((nJ, nJ)) if xi else None
    # ‖E‖_F² of the residuals E = H_FF X̂ − H_FJ, each computed residual r̂ within
    # γ(|H_FF||X̂| + |H_FJ|) of the exact one (γ = 2(k+1)·eps, k nonzeros per row: twice the
    # textbook γ_{k+1})
    absH = abs(H_FF)
    gam = 2 * (int(np.diff(H_FF.indptr).max(initial=0)) + 1) * EPS
    bound = {"X": 0.0, "Y": 0.0}

    def charge(key, X, rhs):
        r = H_FF @ X - rhs
        g = gam * (absH @ np.abs(X) + np.abs(rhs))
        bound[key] += float(np.sqrt((r * r).sum()) + np.sqrt((g * g).sum())) ** 2

    t1 = time.perf_counter()
    if F.size:  # else every retained DOF is a contact DOF (a one-row lattice): G(σ) = H_JJ(σ)
        with factor(H_FF) as solve:
            t1 = time.perf_counter()
            for b0 in range(0, nJ, block):
                b = slice(b0, min(nJ, b0 + block))
                rhs = H_FJ[:, b].toarray()
                X = solve(rhs)
                charge("X", X, rhs)
                KX, PX = KJF @ X, PJF @ X
                S[:, b] -= KX
                R[:, b] -= PX
                if xi:
                    KK[:, b], NK[:, b] = KX, PX
                    rhs_y = PJF[b].T.toarray()
                    Y = solve(rhs_y)
                    charge("Y", Y, rhs_y)
                    Z[:, b] = PJF @ Y
    t2 = time.perf_counter()
    err_S = err_R = err_Z = np.inf
    diagonal_mass = (Mt[F][:, F] - sp.diags(Mt[F][:, F].diagonal())).count_nonzero() == 0
    if tau is not None and tau > 0 and diagonal_mass and F.size:
        # ‖X̂ − X‖_F ≤ ‖E‖_F / λ_min(H_FF), then ‖K_JF(X̂ − X)‖₂ ≤ ‖K_JF‖_F ‖X̂ − X‖_F; the
        # dense products' own rounding is charged by the last term
        lam_lo = (tau + sigma) * Mt[F][:, F].diagonal().min()
        ex, ey = np.sqrt(bound["X"]) / lam_lo, np.sqrt(bound["Y"]) / lam_lo
        err_S = spl.norm(KJF, "fro") * ex + 10 * nJ * EPS * np.abs(S).max()
        err_R = spl.norm(PJF, "fro") * ex + 10 * nJ * EPS * np.abs(R).max(initial=0.0)
        if xi:
            err_Z = spl.norm(PJF, "fro") * ey + 10 * nJ * EPS * np.abs(Z).max(initial=0.0)
    elif not F.size:
        err_S = 10 * nJ * EPS * np.abs(S).max()
        err_R = 10 * nJ * EPS * np.abs(R).max(initial=0.0)
        err_Z = 0.0
    # S, KK and Z are symmetric in exact arithmetic: keep their symmetric parts (the bounds cover it)
    S = 0.5 * (S + S.T)
    if xi:
        Z, KK = 0.5 * (Z + Z.T), 0.5 * (KK + KK.T)
    return Condensed(float(sigma), S, R, float(err_S), float(err_R), "bounded", Z, float(err_Z), KK, NK,
                     {"factor": t1 - t0, "solves": t2 - t1})


def from_bordered_schur(pieces: PencilPieces, sigma: float, X: np.ndarray, relative_error: float) -> Condensed:
    """The :class:`Condensed` of the Schur complement ``X = [[S, Rᵀ], [R, −Z]]`` of
    :meth:`PencilPieces.bordered` onto its rows (e.g. MUMPS'), with errors
    ``relative_error·max|block|`` (``error_kind = "measured"``: the caller says how)."""
    nJ, J = pieces.J.size, pieces.J
    S = 0.5 * (X[:nJ, :nJ] + X[:nJ, :nJ].T)
    R = np.array(X[nJ:, :nJ])
    Z = -0.5 * (X[nJ:, nJ:] + X[nJ:, nJ:].T)
    # only the J × J blocks, rows J first: σM̃ + K̃ over every row is not free at every σ
    # (docs/benchmarks-notes.md)
    Hs_JJ = (sigma * pieces.Mt[J] + pieces.Kt[J]).tocsc()[:, J]
    P_JJ = (sigma * pieces.NM[J] + pieces.N[J]).tocsc()[:, J]
    KK = Hs_JJ.toarray() - S
    NK = P_JJ.toarray() - R
    scale = max(np.abs(S).max(), np.abs(R).max() if R.size else 0.0, 1e-300)
    e = relative_error * scale * nJ  # entrywise → ‖·‖₂ (≤ n·max entry)
    return Condensed(float(sigma), S, R, e, e, "measured", Z, e, KK, NK)


def lift(pieces: PencilPieces, sigma: float, xJ: np.ndarray, solve_FF: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
    """The whole reduced vector of ``x_J``: ``x_F = −H_FF(σ)⁻¹ H_FJ(σ) x_J`` (``solve_FF`` a
    solve with H_FF(σ))."""
    J, F = pieces.J, pieces.F
    x = np.zeros(pieces.n)
    x[J] = xJ
    if F.size:
        Hs = (sigma * pieces.Mt + pieces.Kt).tocsr()
        x[F] = -solve_FF(Hs[F][:, J] @ xJ)
    return x

