"""Condensed λ-windows: a proof at any size that the damped quadratic MEiCP
``y = (λ²B + λD − A)x`` has no real λ ≥ 0, where the damped Rayleigh bound proves nothing
(docs/damping.md, "condensed λ-windows") — the damped counterpart of the undamped σ-windows
(:mod:`.divergence.windows`), for any damping, proportional or not.

Lumped mass (B diagonal, no mass in the friction rows: a base contact or an interface in
centre-of-mass coordinates) and P̃₀ = Q̃ᵀ.  Split as in :mod:`.condensation`, with
C̃ = Q̃ᵀCQ̃ and the friction rows N_C = P̃_μCQ̃ of D:

    H(λ) = λ²B + λD − A = K̃ + λC̃ + λ²M̃ + N + λN_C        (N, N_C: rows J only).

On the free DOFs F, ``H_FF(λ) = K̃_FF + λC̃_FF + λ²M̃_FF`` is symmetric positive definite and
non-decreasing in λ ≥ 0 (K̃_FF ≻ 0 proved by an inertia, C̃ ⪰ 0, M̃ ≻ 0), so on a window
[λ_a, λ_b] its inverse X(λ) lies between X_b = X(λ_b) and X_a = X(λ_a).  With
``a(λ) = K̃_JF + λC̃_JF`` and ``b(λ) = N_JF + λN_C,JF``, w_F = 0 gives ``w_J = G(λ)x_J``,

    G(λ) = H_JJ(λ) − (a + b) X aᵀ,

and a solution at λ needs G(λ) ∉ R₀.  For a positive diagonal W and β > 0 the square
completed as ``pᵀXr ≤ pᵀX_a r + (p − βr)ᵀ(X_a − X_b)(p − βr)/(4β)`` gives, on the whole window,

    sym(W G(λ)) ⪰ 𝓜(λ) = sym(W[H_JJ(λ) − (a + b)X_a aᵀ]) − Π(λ)(X_a − X_b)Π(λ)ᵀ/(4β),
    Π = (W − βI)a + W b,

a matrix polynomial 𝓜₀ + λ𝓜₁ + λ²𝓜₂: it is at least its chord less (λ_b − λ_a)²/4·λ_max(𝓜₂)⁺,
and λ_min of the chord at least the smaller at the ends.  So ``λ_min 𝓜(λ_a)`` and
``λ_min 𝓜(λ_b)`` above ``(λ_b − λ_a)²/4·λ_max(𝓜₂)⁺`` and their rounding prove G(λ) ∈ R₀ on the
window (sym(WG) ≻ 0, while a solution has xᵀWGx = Σ W_jj x_j w_j = 0).  Every block that needs,
``Ξ(λ) = U X(λ) Uᵀ`` for ``U = [K̃_JF; C̃_JF; N_JF; N_C,JF]`` (4|J| rows), is one MUMPS Schur
complement of the bordered ``[[H_FF(λ), Uᵀ], [U, 0]]`` per sample λ, its error measured by
probes.  The windows cover [0, λ_max], λ_max the ceiling of every solution
(``λ² − νλ − γ ≤ 0``, ν of the damped Rayleigh bound, γ Gershgorin's bound of the scaled
sym(A)); a failed window is split in log(λ + scale) until a budget of samples.  Collective;
the dense certificates on rank 0, the other ranks serve its condensations.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import scipy.linalg as sl
import scipy.sparse as sp

from ..core.comm import mpi_comm
from ..core.progress import Ticker
from ..lattice.node_blocks import NodeBlocks, node_of
from ..lcp.certificates import EPS, eig_rounding, norm2_bound, optimise_scaling
from ..petsc.inertia import diagonal_scale, rounding_margin
from ..petsc.schur import schur_series
from .condensation import pieces_of
from .condenser import InteriorSolve
from .condenser_certificates import PROBE_SAFETY, SCHUR_ERROR_FLOOR, refined_solve
from .damped_rayleigh import congruence_slack, friction_shift
from .on_root import decided_on_root

log = logging.getLogger("meicp")

#: condensations (λ samples) a proof may make
MAX_SAMPLES = 16
#: the samples whose Schur complement's error is measured (the first: λ = 0, as the σ-windows
#: measure theirs at σ = 0 alone); the others are charged the same, relative to their own
#: largest entry.  A measurement costs about two condensations (10⁶ DOFs: 5 s against 2.2 s)
MEASURED = 1
#: where a failed window is split: in log(λ + SPLIT_SCALE·λ_max)
SPLIT_SCALE = 1e-3
#: rounding of the sums that form 𝓜₀, 𝓜₁, 𝓜₂ from the blocks, in units of their size
FORMING_ROUNDING = 64 * EPS
#: the β tried per window, in units of mean(W) (as the undamped windows)
BETAS = (0.25, 0.5, 1.0, 2.0, 4.0)
#: the blocks of U: K̃_JF, C̃_JF, N_JF, N_C,JF; their power of λ in a(λ), b(λ); and which
#: are a's (the symmetric part) and b's (the friction rows)
POWER = (0, 1, 0, 1)
SYMMETRIC = (True, True, False, False)


@dataclass
class DampedPieces:
    """The split damped pencil (SciPy CSR, every rank): ``A = −(K̃ + N)``, ``B = M̃`` (diagonal),
    ``D = C̃ + N_C``; ``J`` the complementarity positions, ``slack`` s with ``C̃ + s·M̃ ⪰ 0`` (the
    rounding of the congruence Q̃ᵀCQ̃, :func:`~.damped_rayleigh.congruence_slack`), ``nu`` with
    ``sym(D) ⪰ −ν·B``."""

    Kt: sp.csr_matrix
    Ct: sp.csr_matrix
    Mt: sp.csr_matrix
    N: sp.csr_matrix
    NC: sp.csr_matrix
    J: np.ndarray
    slack: float
    nu: float

    @cached_property
    def F(self) -> np.ndarray:
        mask = np.ones(self.Kt.shape[0], dtype=bool)
        mask[self.J] = False
        return np.flatnonzero(mask)

    def H_JJ(self) -> list[np.ndarray]:
        """The J × J block of H(λ) as its three coefficients (λ⁰, λ¹, λ²), dense."""
        J = self.J
        return [(M[J].tocsc()[:, J]).toarray() for M in (self.Kt + self.N, self.Ct + self.NC, self.Mt)]

    def U(self) -> sp.csr_matrix:
        """``[K̃_JF; C̃_JF; N_JF; N_C,JF]`` (4|J| × |F|)."""
        J, F = self.J, self.F
        return sp.vstack([M[J].tocsc()[:, F] for M in (self.Kt, self.Ct, self.N, self.NC)]).tocsr()

    def H_FF(self, lam: float) -> sp.csr_matrix:
        F = self.F
        H = self.Kt if lam == 0 else self.Kt + lam * self.Ct + (lam * lam) * self.Mt
        return (H[F].tocsc()[:, F]).tocsr()

    def ceiling(self) -> float:
        """λ_max: no solution has λ above it.  A solution has ``λ²·xᵀBx + λ·xᵀDx − xᵀAx = 0``
        (xᵀw = 0), with sym(D) ⪰ −νB and sym(A) ⪯ γB (:meth:`gamma`), so ``λ² − νλ − γ ≤ 0``."""
        return ceiling_of(self.nu, self.gamma())

    def gamma(self) -> float:
        """γ ≥ 0 with sym(A) ⪯ γB: Gershgorin's discs of B^-½ sym(A) B^-½, rounded up."""
        s = 1.0 / np.sqrt(self.Mt.diagonal())
        S = sp.diags(s) @ (-0.5 * ((self.Kt + self.N) + (self.Kt + self.N).T)) @ sp.diags(s)
        S = sp.csr_matrix(S)
        radius = np.asarray(abs(S).sum(axis=1)).ravel() - np.abs(S.diagonal())
        gamma = float(np.max(S.diagonal() + radius)) * (1 + 1e-12) + 16 * EPS * float(abs(S).max())
        return max(gamma, 0.0)


def ceiling_of(nu: float, gamma: float) -> float:
    """The largest root of ``λ² − νλ − γ``, rounded up: it grows with ν and with γ."""
    return 0.5 * (nu + np.sqrt(nu * nu + 4 * gamma)) * (1 + 1e-12)


def damped_pieces(pen) -> tuple[DampedPieces | None, str]:
    """``(pieces, "")`` of a damped pencil, or ``(None, why not)`` where the windows do not
    apply (B not diagonal, P̃₀ ≠ Q̃ᵀ, mass in the friction rows).  SciPy, every rank alike."""
    maps, lattice = pen.maps, pen.lattice
    K, M = lattice.whole()
    C = lattice.damping()
    nu, why = friction_shift(maps, C, M)  # None where B is not diagonal positive or P̃₀ ≠ Q̃ᵀ
    if nu is None:
        return None, why
    stiffness = pieces_of(K, M, maps)  # K̃, M̃, N, N_M, as the undamped condensation splits them
    viscous = pieces_of(C, M, maps)     # the same split of C: C̃ in K̃'s place, N_C in N's
    if stiffness.NM.count_nonzero():
        return None, "the friction rows carry mass (B is not diagonal for every μ)"
    b = stiffness.Mt.diagonal()  # B = M̃ + N_M, diagonal (friction_shift checked it), N_M = 0
    return DampedPieces(stiffness.Kt, viscous.Kt, sp.diags(b).tocsr(), stiffness.N, viscous.N, np.asarray(maps.J),
                        congruence_slack(maps, C, b), nu), ""


@dataclass
class Sample:
    """The condensation at λ: ``Xi`` = U X(λ) Uᵀ (dense, symmetric) and a bound ``error`` of
    ‖Ξ̂ − Ξ‖₂ (measured: MUMPS' Schur complement has no residual)."""

    lam: float
    Xi: np.ndarray
    error: float

    def block(self, i: int, j: int) -> np.ndarray:
        k = self.Xi.shape[0] // 4
        return self.Xi[i * k:(i + 1) * k, j * k:(j + 1) * k]


class DampedCondenser:
    """The Schur complements Ξ(λ) of the bordered ``[[H_FF(λ), Uᵀ], [U, 0]]``, one MUMPS analysis
    for every λ (:func:`~meicp.petsc.schur.schur_series` with its quadratic term), and the
    inertia that proves the lattice held (K̃_FF ≻ 0).  Collective; a context manager."""

    def __init__(self, comm, pieces: DampedPieces, retained: np.ndarray):
        self.comm, self.pieces = comm, pieces
        F, U = pieces.F, pieces.U()
        self.U = U
        self.nF, self.nU = F.size, U.shape[0]
        zero_U = sp.csr_matrix((self.nU, self.nU))
        self.KFF = pieces.H_FF(0.0)
        parts = [sp.bmat([[self.KFF, U.T], [U, zero_U]], format="csr")]
        for M in (pieces.Ct, pieces.Mt):
            MFF = M[F].tocsc()[:, F]
            parts.append(sp.bmat([[MFF, None], [None, zero_U]], format="csr"))
        nodes = node_of(np.asarray(retained)[F])
        pad = NodeBlocks(np.concatenate([nodes, nodes.max(initial=-1) + 1 + np.arange(self.nU)])).pad
        pad((abs(parts[0]) + abs(parts[1]) + abs(parts[2])).tocsr())  # one pattern for all three
        H0, H1, H2 = (pad(P) for P in parts)
        self.rows = self.nF + np.arange(self.nU)
        self.series = schur_series(comm, H0, H1, self.rows, H2)
        self.tau: float | None = None
        self.measured: list[float] = []
        self.seconds: dict = {}

    def __enter__(self) -> "DampedCondenser":
        return self

    def __exit__(self, *exc) -> None:
        self.series.destroy()

    def held(self) -> str:
        """"" when K̃_FF − 2ηD ≻ 0 is proved by the inertia of an exact factorisation (η the
        rounding margin, D = diag|K̃_FF|), which also certifies τ = η·min(D/m) ≤
        λ_min(K̃_FF, M̃_FF); else why not.  Collective."""
        t = time.perf_counter()
        eta, d = rounding_margin(self.nF), diagonal_scale(self.KFF)
        if not getattr(self.series, "interior", False):
            return "no DMUMPS with interior inertias loaded: the lattice is not proved held"
        shift = np.zeros(self.nF + self.nU)
        shift[:self.nF] = -2.0 * eta * d
        negative, null = self.series.factor(0.0, diagonal=shift, exact=True)
        self.seconds["held"] = time.perf_counter() - t
        if negative or null:
            return (f"K̃_FF is not proved positive definite ({negative + null} pivot(s) of K̃_FF − 2η·diag (η = "
                    f"{eta:.1e}) not positive): the lattice is not held once the contact DOFs are")
        m = self.pieces.Mt.diagonal()[self.pieces.F]
        self.tau = float(eta * np.min(d / m))
        return ""

    def at(self, lam: float) -> Sample:
        """Ξ(λ) with its error: relative to its largest entry, the largest measured at the first
        :data:`MEASURED` samples (the cover's first is λ = 0).  Collective."""
        t = time.perf_counter()
        Xi = -self.series(lam)
        Xi = 0.5 * (Xi + Xi.T)
        scale = max(float(np.abs(Xi).max()), 1e-300)
        if len(self.measured) < MEASURED:
            self.measured.append(self._measure(lam, Xi, scale))
            self.seconds["probe"] = self.seconds.get("probe", 0.0) + time.perf_counter() - t
        self.seconds["condense"] = self.seconds.get("condense", 0.0) + time.perf_counter() - t
        return Sample(float(lam), Xi, max(self.measured) * scale * self.nU)

    def _measure(self, lam: float, Xi: np.ndarray, scale: float) -> float:
        """The relative error of Ξ̂(λ) along three probes v, against solves with H_FF(λ) refined
        on the same factor, charged ×PROBE_SAFETY, at least SCHUR_ERROR_FLOOR."""
        U = self.U
        solve = refined_solve(InteriorSolve(self.comm, self.series, np.arange(self.nF), lam), self.pieces.H_FF(lam))
        rng = np.random.default_rng(31)
        V = np.column_stack([np.ones(self.nU), rng.standard_normal((self.nU, 2))])
        reference = U @ solve(U.T @ V)
        rel = np.linalg.norm(Xi @ V - reference, axis=0) / (np.linalg.norm(V, axis=0) * scale)
        return max(PROBE_SAFETY * float(rel.max()), SCHUR_ERROR_FLOOR)


class NothingToCondense:
    """The condenser of a pencil whose every retained DOF is a contact DOF (a one-row lattice):
    G(λ) = H_JJ(λ) itself, Ξ = 0 exactly."""

    tau = np.inf

    def __init__(self, pieces: DampedPieces):
        self.nU = 4 * pieces.J.size
        self.seconds: dict = {}

    def __enter__(self) -> "NothingToCondense":
        return self

    def __exit__(self, *exc) -> None:
        pass

    def held(self) -> str:
        return ""

    def at(self, lam: float) -> Sample:
        return Sample(float(lam), np.zeros((self.nU, self.nU)), 0.0)


@dataclass
class WindowParts:
    """What a window's bound is made of for one scaling w, before β is chosen: 𝓜(β) =
    ``base − Q₀/(4β) + Q₁/4 − β·Q₂/4`` per power of λ (:func:`window_parts`), and the errors."""

    base: list
    Q0: list
    Q1: list
    Q2: list
    base_error: list
    delta_error: float
    w: np.ndarray

    def at(self, beta: float) -> tuple[list, list]:
        """``(𝓜₀, 𝓜₁, 𝓜₂)`` at β and bounds of their errors: the blocks' (as charged), and the
        rounding of this combination, relative to its terms."""
        coeff_max = {True: float(np.abs(self.w - beta).max()), False: float(self.w.max())}
        M, err = [], list(self.base_error)
        for k in range(3):
            M.append(self.base[k] - self.Q0[k] / (4 * beta) + 0.25 * self.Q1[k] - (0.25 * beta) * self.Q2[k])
            err[k] += FORMING_ROUNDING * (norm2_bound(self.Q0[k]) / (4 * beta) + 0.25 * norm2_bound(self.Q1[k])
                                          + 0.25 * beta * norm2_bound(self.Q2[k]))
        for i in range(4):
            for j in range(4):
                err[POWER[i] + POWER[j]] += (coeff_max[SYMMETRIC[i]] * coeff_max[SYMMETRIC[j]] * self.delta_error
                                             / (4 * beta))
        return M, err


def window_parts(pieces_JJ, a: Sample, b: Sample, w: np.ndarray, spread: float) -> WindowParts:
    """The β-free parts of the window [a.lam, b.lam]'s bound for the scaling w (module
    docstring).  With ``Π = (W − βS)a' + …`` (S: 1 on a's blocks, 0 on b's) each
    ``Π_i Δ_ij Π_jᵀ/(4β)`` is ``wΔw/(4β) − (s_iΔw + s_j wΔ)/4 + β s_i s_j Δ/4``; ``spread`` κρ ≥ 0:
    X_a, X_b widened to X_a/(1 − κρ), X_b/(1 + κρ) for the rounding of C̃ ⪰ 0
    (:func:`ordering_spread`)."""
    up, down = 1.0 / (1.0 - spread), 1.0 / (1.0 + spread)
    err = [0.0, 0.0, 0.0]
    wmax = float(w.max())
    for i in range(4):  # the blocks of (a + b)X_a aᵀ, each charged its error
        for j in (0, 1):
            err[POWER[i] + POWER[j]] += wmax * up * (a.error)
    M = [w[:, None] * Mk for Mk in _coefficients(pieces_JJ, a, up)]
    base = [0.5 * (Mk + Mk.T) for Mk in M]
    n = w.size
    Q0, Q1, Q2 = ([np.zeros((n, n)) for _ in range(3)] for _ in range(3))
    for i in range(4):
        for j in range(4):
            k = POWER[i] + POWER[j]
            delta = up * a.block(i, j) - down * b.block(i, j)
            Q0[k] += w[:, None] * delta * w[None, :]
            if SYMMETRIC[i]:
                Q1[k] += delta * w[None, :]
            if SYMMETRIC[j]:
                Q1[k] += w[:, None] * delta
            if SYMMETRIC[i] and SYMMETRIC[j]:
                Q2[k] += delta
    Q0, Q1, Q2 = ([0.5 * (Q + Q.T) for Q in part] for part in (Q0, Q1, Q2))
    return WindowParts(base, Q0, Q1, Q2, err, up * a.error + down * b.error, w)


def ordering_spread(pieces: DampedPieces, tau: float, lo: float, hi: float) -> float:
    """κρ with X(λ) ⪯ X_a/(1 − κρ) and X(λ) ⪰ X_b/(1 + κρ) on [lo, hi]: H_FF(λ) − H_FF(λ_a) =
    (λ − λ_a)(C̃ + (λ + λ_a)M̃) ⪰ −ρM̃ with ρ = (hi − lo)·max(0, s − 2lo) (C̃ ⪰ −sM̃), and
    M̃ ⪯ H_FF/τ (H_FF ⪰ K̃_FF ⪰ τM̃)."""
    rho = (hi - lo) * max(0.0, pieces.slack - 2 * lo)
    held = tau - 0.25 * pieces.slack ** 2  # H_FF(λ_a) ⪰ K̃_FF − λ_a(s − λ_a)M̃ ⪰ (τ − s²/4)M̃
    return rho / held if held > 0 else (0.0 if rho == 0 else np.inf)


def window_margin(pieces_JJ, a: Sample, b: Sample, w: np.ndarray, spread: float, tol: float = 0.0
                  ) -> tuple[float, float]:
    """The certified margin of the window [a.lam, b.lam] for the scaling w (> 0 proves it, in
    units of mean(w)) and the β that gave it: the best over :data:`BETAS`."""
    return window_margin_over([(pieces_JJ, a, b)], w, spread, tol)


def window_margin_over(ends: list, w: np.ndarray, spread: float, tol: float = 0.0) -> tuple[float, float]:
    """:func:`window_margin` for one scaling and one β at several ``ends`` — ``(pieces_JJ, a, b)``
    of one window at several μ (:mod:`.damped_mu_windows`) — the smallest margin of the ends."""
    if not spread < 1:
        return -np.inf, np.nan
    parts = [(window_parts(pieces_JJ, a, b, w, spread), a.lam, b.lam) for pieces_JJ, a, b in ends]
    best = (-np.inf, np.nan)
    for f in BETAS:
        beta = f * float(np.mean(w))
        margin = min(_margin(part.at(beta), lo, hi, w, tol) for part, lo, hi in parts)
        if margin > best[0]:
            best = (margin, beta)
        if margin > 0:
            break
    return best


def _margin(polynomial, lo: float, hi: float, w: np.ndarray, tol: float) -> float:
    """The certified margin of the window [lo, hi] from its bound ``((𝓜₀, 𝓜₁, 𝓜₂), errors)``."""
    (M0, M1, M2), (e0, e1, e2) = polynomial
    # the blocks' error, at its largest over the window (λ ≥ 0), and the sums' own rounding
    error = e0 + hi * e1 + hi * hi * e2
    error += FORMING_ROUNDING * (norm2_bound(M0) + hi * norm2_bound(M1) + hi * hi * norm2_bound(M2))
    scale = float(np.mean(w))
    least = np.inf
    for lam in (lo, hi):
        X = M0 + lam * M1 + (lam * lam) * M2
        low = float(sl.eigh(X, eigvals_only=True, subset_by_index=[0, 0])[0])
        least = min(least, low - eig_rounding(X) - tol * norm2_bound(X))
        if least <= error:  # not proved whatever the rest: its margin is at most this
            return (least - error) / scale
    top = float(sl.eigh(M2, eigvals_only=True, subset_by_index=[M2.shape[0] - 1, M2.shape[0] - 1])[0])
    curve = 0.25 * (hi - lo) ** 2 * (max(top, 0.0) + eig_rounding(M2))
    return (least - curve - error) / scale


def _coefficients(pieces_JJ, s: Sample, up: float = 1.0) -> list[np.ndarray]:
    """``H_JJ(λ) − (a + b)·(up·X)·aᵀ`` with X the sample's, as its coefficients of λ⁰, λ¹, λ²
    (dense): the blocks (i: a or b, j: a) of Ξ, each at the power POWER[i] + POWER[j]."""
    M = [np.array(H, dtype=float) for H in pieces_JJ]
    for i in range(4):
        for j in (0, 1):
            M[POWER[i] + POWER[j]] -= up * s.block(i, j)
    return M


def G_at(pieces_JJ, s: Sample) -> np.ndarray:
    """G(λ) = H_JJ(λ) − (a + b) X aᵀ at a sample (dense)."""
    M0, M1, M2 = _coefficients(pieces_JJ, s)
    return M0 + s.lam * M1 + (s.lam * s.lam) * M2


@dataclass
class DampedWindows:
    """What :func:`prove_no_damped_divergence` established: ``proved`` (no real λ ≥ 0),
    ``statement``, ``windows`` ((λ_a, λ_b, margin)), ``samples`` made, ``lam_max``, ``seconds``."""

    proved: bool
    statement: str
    windows: list = field(default_factory=list)
    samples: int = 0
    lam_max: float = np.nan
    seconds: dict = field(default_factory=dict)


def cover_windows(condense_at, pieces_JJ, tau: float, pieces: DampedPieces, lam_max: float, tol: float,
           max_samples: int, *, pending: list | None = None, condensed=None, hints: dict | None = None,
           used: dict | None = None) -> tuple[bool, list, dict, tuple | None]:
    """Rank 0: windows from 0 to λ_max, a failed one split in log(λ + scale).  ``pending``: the
    windows to try first (default [0, λ_max]; they must cover it from 0); ``condensed()``: the
    condensations made so far, for the budget (default this call's); ``hints``: a scaling per
    window's λ_a to try before optimising one; ``used``: filled with the scaling that proved
    each window."""
    samples: dict = {}
    scalings: dict = {}
    hints = {} if hints is None else hints
    condensed = condensed or (lambda: len(samples))

    def at(lam):
        if lam not in samples:
            samples[lam] = condense_at(lam)
        return samples[lam]

    scale = SPLIT_SCALE * lam_max
    pending, proved = list(pending or [(0.0, lam_max)]), []
    ticker = Ticker("damped λ-windows", interval=0.0)
    while pending:
        lo, hi = pending.pop(0)
        a, b = at(lo), at(hi)
        spread = ordering_spread(pieces, tau, lo, hi)
        margin, w = -np.inf, None
        # a scaling given, or the one optimised at λ = 0, often proves a window as it is: the 40
        # eigen-solves of an optimised one only when it does not
        for tried in (hints.get(lo), scalings.get(0.0) if lo not in scalings else None):
            if tried is not None and margin <= 0:
                margin, w = window_margin(pieces_JJ, a, b, tried, spread, tol)[0], tried
        if margin <= 0:
            if lo not in scalings:
                scalings[lo], _ = optimise_scaling([G_at(pieces_JJ, a)], d0=hints.get(lo, scalings.get(0.0)),
                                                   iters=40)
            w = scalings[lo]
            margin, _ = window_margin(pieces_JJ, a, b, w, spread, tol)
        ticker.say(lambda: f"window [{lo:.4g}, {hi:.4g}] {'proved' if margin > 0 else 'split'}; "
                           f"{len(proved) + (margin > 0)} proved, {condensed()} condensation(s)")
        if margin > 0:
            proved.append((lo, hi, margin))
            if used is not None:
                used[lo] = w
            continue
        mid = float(np.sqrt((lo + scale) * (hi + scale)) - scale)
        if condensed() >= max_samples or not lo < mid < hi:
            return False, proved, samples, (lo, hi, margin)
        pending[:0] = [(lo, mid), (mid, hi)]
    return True, proved, samples, None


def prove_no_damped_divergence(pen, comm=None, *, tol: float = 1e-10, max_samples: int = MAX_SAMPLES
                               ) -> DampedWindows:
    """Prove that the damped pencil's quadratic MEiCP has no real λ ≥ 0 by condensed λ-windows
    (module docstring).  ``proved=False`` proves nothing either way and says why.  Collective
    on ``comm`` (default the pencil's)."""
    comm = mpi_comm(pen.comm if comm is None else comm)
    t0 = time.perf_counter()
    pieces, why = damped_pieces(pen)
    if pieces is None:
        return DampedWindows(False, f"condensed λ-windows not tried: {why}")
    if pieces.J.size == 0:
        return DampedWindows(False, "condensed λ-windows not tried: no complementarity DOFs")
    lam_max = pieces.ceiling()
    t1 = time.perf_counter()
    with (DampedCondenser(comm, pieces, pen.maps.retained) if pieces.F.size else NothingToCondense(pieces)) as cond:
        cond.seconds.update(pieces=t1 - t0, setup=time.perf_counter() - t1)
        why = cond.held()
        if why:
            return DampedWindows(False, f"condensed λ-windows: {why}", lam_max=lam_max, seconds=dict(cond.seconds))
        pieces_JJ = pieces.H_JJ()
        proved, windows, samples, failed = decided_on_root(
            comm, lambda served: _summary(*cover_windows(served, pieces_JJ, cond.tau, pieces, lam_max, tol, max_samples)),
            cond.at)
        seconds = {**cond.seconds, "total": time.perf_counter() - t0}
    n = len(samples)
    errors = max(samples.values()) if samples else 0.0
    if proved:
        how = ("Schur complements by MUMPS, error measured (≤ {:.1e} charged; a measurement, not a bound)".format(errors)
               if pieces.F.size else "nothing to condense: every retained DOF is a contact DOF, G(λ) = H_JJ(λ)")
        return DampedWindows(True, f"condensed λ-windows: G(λ) ∈ R₀ on every window of [0, {lam_max:.6g}] "
                             f"({len(windows)} windows, {n} condensations; no solution has λ above {lam_max:.6g}: "
                             f"λ² − νλ − γ ≤ 0, ν = {pieces.nu:.3g}); {how} (a proof)", windows, n, lam_max, seconds)
    lo, hi, margin = failed
    covered = 0.0
    for a, b, _ in sorted(windows):
        covered = b if a <= covered else covered
    return DampedWindows(False, f"condensed λ-windows: window [{lo:.6g}, {hi:.6g}] not certified (margin "
                         f"{margin:.2e}) after {n} condensations; no solution in [0, {covered:.6g}]",
                         windows, n, lam_max, seconds)


def _summary(proved, windows, samples, failed):
    """What rank 0 broadcasts: the samples' errors, not their blocks."""
    return proved, windows, {lam: s.error / max(float(np.abs(s.Xi).max()), 1e-300) / s.Xi.shape[0]
                             for lam, s in samples.items()}, failed
