"""Proofs that a contact state's MEiCP has no divergence mode (real σ ≥ 0) in a σ-window,
by condensation onto the complementarity DOFs J (docs/critical-friction.md, "condensed
tests"):

    T1  σ = 0      G(0) ∈ R₀: a positive diagonal D with sym(DG(0)) ≻ 0 (one condensation)
    T2  windows    G(σ) ∈ R₀ for every σ in [0, σ_max], by certificates on windows
                   [σ_a, σ_b] from condensations at their ends (:mod:`.windows`)

(G(σ) of :mod:`.condensation`; the certificates of :mod:`meicp.lcp.certificates`.)  Every
certificate is decided with its rounding margin (the dense eigen-solve's and the
condensation's error) and a caller's relative ``tol``: a borderline case is not proved.

The condensations are MUMPS Schur complements of the bordered matrix
[[σM̃ + K̃, P_Jᵀ], [P_J, 0]] (``method="schur"``; its error is *measured*, by solves with a
separate MUMPS factor of K̃_FF along probe vectors, and charged ×100) or solves with one
MUMPS factor of H_FF(σ) per sample (``method="solves"``: error *bounded* from the residuals
and a certified lower bound τ of λ_min(K̃_FF, M̃_FF)).  Collective on ``comm``; the dense
certificates run on rank 0, the other ranks serve its condensations.
"""
from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from ..lattice.assembly import assemble_scipy
from ..lcp.certificates import optimise_scaling, pd_certificate
from ..petsc.comm import mpi_comm
from ..petsc.eigen import solve_ghep
from ..petsc.inertia import pencil_is_negative
from ..petsc.mat import destroying, mat_from_scipy
from ..petsc.schur import MumpsFactor, dense_schur, mumps_factor
from .condensation import Condensed, PencilPieces, condense, from_bordered_schur, pieces_of
from .windows import cover

log = logging.getLogger("meicp")

#: ``method="auto"`` condenses by solves (rigorous error bound) while |F|·|J| stays below this
SOLVES_LIMIT = 2e7
#: the Schur complement's measured relative error is charged this many times over
PROBE_SAFETY = 100.0
#: floor of the charged relative error of a Schur complement (MUMPS' backward error level)
SCHUR_ERROR_FLOOR = 1e-13


@dataclass(frozen=True)
class DivergenceProof:
    """What :func:`prove_no_divergence` established.

    proved: True only if no MEiCP solution has σ in ``window`` (the whole asked window);
    test: ``"condensed-pd"`` (T1: σ_max = 0, G(0) ∈ R₀ by scaled positive definiteness),
    ``"condensed-windows"`` (T2) or ``""`` when not proved; statement: one sentence saying
    what was proved or what stopped it; margin: the smallest certified margin (λ_min minus
    its rounding allowance) over the certificates used, ≤ 0 or nan when not proved;
    samples: condensations (σ samples) made; window: the σ-interval proved free of
    divergence modes, ``(0.0, σ)`` — when not proved, the part covered from 0 (possibly
    ``(0.0, 0.0)``: σ = 0 alone) or ``()`` (nothing)."""

    proved: bool
    test: str
    statement: str
    margin: float
    samples: int
    window: tuple
    seconds: dict = field(default_factory=dict, compare=False)


def prove_no_divergence(comm, pencil, sigma_max: float, *, tol: float = 1e-10, method: str = "auto",
                        max_samples: int = 16) -> DivergenceProof:
    """Prove that the MEiCP of ``pencil`` has no solution with σ in [0, σ_max].

    comm: the communicator (None: serial); collective.  pencil: a
    :class:`~meicp.contact.problem.Pencil` (SciPy or distributed; only its ``model`` and
    ``maps`` are read: the pieces K̃, M̃, N of the split pencil are rebuilt on every rank).
    sigma_max: the caller's certified upper end of the window (no solution above it, e.g. by
    an inertia of sym(σ_max B − A)); 0 asks for σ = 0 only; ``inf`` is allowed (the last
    window is [σ_a, ∞)).  tol: relative margin every certificate must clear on top of its
    rounding allowance.  method: ``"schur"``, ``"solves"`` or ``"auto"`` (module docstring).

    Contract: ``proved=True`` is a proof (every certificate re-checked with its margin);
    ``proved=False`` proves nothing either way (a mode may or may not exist) and says why.
    T2 needs a base contact with lumped mass (B diagonal: M̃ diagonal, N_M = 0); with a
    frictional interface only σ_max = 0 can be proved (T1), a wider window is undecided.
    """
    comm = mpi_comm(comm)
    rank = 0 if comm is None else comm.Get_rank()
    t_start = time.perf_counter()
    if not (sigma_max >= 0):
        raise ValueError(f"sigma_max must be ≥ 0, got {sigma_max}")
    if method not in ("auto", "schur", "solves"):
        raise ValueError(f"method must be 'auto', 'schur' or 'solves', got {method!r}")
    J = np.asarray(pencil.J)
    if J.size == 0:
        return DivergenceProof(False, "", "no complementarity DOFs: nothing to condense", np.nan, 0, ())
    K, M = assemble_scipy(pencil.model)
    pieces = pieces_of(K, M, pencil.maps)
    del K, M
    if sigma_max > 0 and not pieces.mass_is_diagonal:
        return DivergenceProof(False, "", "the σ-window certificates need a diagonal B (a base contact with lumped "
                               "mass); this pencil couples contact and free DOFs through its mass (a frictional "
                               "interface): only σ = 0 can be certified, the window is undecided", np.nan, 0, ())
    F = pieces.F
    KFF, MFF = pieces.Kt[F][:, F].tocsr(), pieces.Mt[F][:, F].tocsr()
    secs = {}
    t = time.perf_counter()
    tau, why = _certified_tau(comm, KFF, MFF)
    secs["tau"] = time.perf_counter() - t
    if tau is None:
        return DivergenceProof(False, "", why, np.nan, 0, (), secs)
    if method == "auto":
        method = "solves" if F.size * J.size <= SOLVES_LIMIT else "schur"
    t = time.perf_counter()
    rel_schur = _schur_error(comm, pieces) if method == "schur" else None
    secs["probe"] = time.perf_counter() - t

    def condense_at(sigma: float) -> Condensed:
        if method == "solves":
            return condense(pieces, sigma, mumps_factor(comm), tau=tau, xi=True)
        H, rows = pieces.bordered(sigma)
        return from_bordered_schur(pieces, sigma, dense_schur(comm, H, rows, symmetric=True), rel_schur)

    t = time.perf_counter()
    if comm is None or comm.Get_size() == 1:
        out = _decide(condense_at, sigma_max, tau, tol, max_samples)
    elif rank == 0:
        def served(sigma):
            comm.bcast(sigma, root=0)
            return condense_at(sigma)
        try:
            out = _decide(served, sigma_max, tau, tol, max_samples)
        finally:
            comm.bcast(None, root=0)
    else:
        while (sigma := comm.bcast(None, root=0)) is not None:
            condense_at(sigma)
        out = None
    if comm is not None and comm.Get_size() > 1:
        out = comm.bcast(out, root=0)
    secs["certify"] = time.perf_counter() - t
    secs["total"] = time.perf_counter() - t_start
    err_kind = "bounded from the solves' residuals" if method == "solves" else \
        f"measured ({rel_schur:.1e} relative, charged; not a proof of the error)"
    proved, test, statement, margin, samples, window = out
    return DivergenceProof(proved, test, f"{statement}; condensation error {err_kind}", margin, samples,
                           window, secs)


def _decide(condense_at, sigma_max, tau, tol, max_samples):
    """T1 then T2 on rank 0: ``(proved, test, statement, margin, samples, window)``."""
    c0 = condense_at(0.0)
    G0 = c0.G()
    d, _ = optimise_scaling([G0], iters=40)
    cert = pd_certificate(G0, c0.error(), d, tol=tol)
    if not cert.proved:
        return (False, "", f"σ = 0 not excluded: no diagonal scaling D found with sym(DG(0)) ≻ 0 beyond rounding "
                f"(margin {cert.margin:.2e})", cert.margin, 1, ())
    if sigma_max == 0:
        return (True, "condensed-pd", f"G(0) ∈ R₀: sym(DG(0)) ≻ 0 for a positive diagonal D (λ_min "
                f"{cert.lam_min:.3e} > rounding {cert.rounding:.1e}): no σ = 0 mode", cert.margin, 1, (0.0, 0.0))
    cov = cover(condense_at, 1.0, tau, sigma_max=sigma_max, max_samples=max_samples, d_seed=d, tol=tol)
    n = len(cov.samples)
    if cov.proved:
        margin = min([cert.margin] + [w[2] for w in cov.windows])
        return (True, "condensed-windows", f"G(σ) ∈ R₀ on every window of [0, {sigma_max:.6g}] ({len(cov.windows)} "
                f"windows, {n} condensations, τ = {tau:.3g})", margin, n, (0.0, float(sigma_max)))
    covered = 0.0
    for a, b, *_ in sorted(cov.windows):
        if a <= covered:
            covered = max(covered, b)
    a, b, m = cov.failed
    return (False, "", f"window [{a:.6g}, {b:.6g}] not certified (margin {m:.2e}) after {n} condensations; "
            f"proved free of modes: [0, {covered:.6g}]", m, n, (0.0, float(covered)))


def _certified_tau(comm, KFF, MFF) -> tuple[float | None, str]:
    """A certified lower bound τ > 0 of λ_min(K̃_FF, M̃_FF): half a SLEPc estimate, proved by
    the inertia of τM̃_FF − K̃_FF (:func:`~meicp.petsc.inertia.pencil_is_negative`), which
    also proves K̃_FF ≻ 0 (the lattice held once the contact DOFs are)."""
    if KFF.shape[0] == 0:
        return np.inf, ""
    with destroying(mat_from_scipy(comm, KFF), mat_from_scipy(comm, MFF)) as (Kp, Mp):
        try:
            pairs = solve_ghep(Kp, Mp, nev=1, target=0.0)
            est = float(pairs.values[0])
            for v in pairs.vectors:
                v.destroy()
        except Exception as exc:  # noqa: BLE001 — no estimate means no proof, not an error
            return None, f"λ_min(K̃_FF, M̃_FF) not estimated ({exc}): the condensation is not certified"
        if not est > 0:
            return None, (f"K̃_FF is not positive definite (λ_min ≈ {est:.2e}): the lattice is not held once the "
                          "contact DOFs are, the condensation is undefined")
        tau = 0.5 * est
        with destroying(mat_from_scipy(comm, (tau * MFF - KFF).tocsr())) as (Ap,):
            sign = pencil_is_negative(Ap, Mp)
    if sign is None or sign.proved is not True:
        return None, f"τ = {tau:.3e} ≤ λ_min(K̃_FF, M̃_FF) not certified ({'' if sign is None else sign.reason})"
    return tau, ""


def _schur_error(comm, pieces: PencilPieces) -> float:
    """The relative error of MUMPS' Schur complement of the σ = 0 bordered matrix, measured
    along three probes v (ones, two seeded random): ‖(Ĝ − G)v‖ / (‖v‖·max|Ĝ|) with Gv from a
    separate MUMPS factor of K̃_FF; charged ×PROBE_SAFETY, at least SCHUR_ERROR_FLOOR."""
    H, rows = pieces.bordered(0.0)
    X = dense_schur(comm, H, rows, symmetric=True)
    c = from_bordered_schur(pieces, 0.0, X, 0.0)
    G = c.G()
    J, F = pieces.J, pieces.F
    rng = np.random.default_rng(14)
    V = np.column_stack([np.ones(J.size), rng.standard_normal((J.size, 2))])
    H0 = pieces.H(0.0).tocsr()
    with MumpsFactor(comm, pieces.Kt[F][:, F], symmetric=True) as solve:
        XF = solve(H0[F][:, J] @ V)
    GV = H0[J][:, J] @ V - H0[J][:, F] @ XF
    rel = np.linalg.norm(G @ V - GV, axis=0) / (np.linalg.norm(V, axis=0) * max(np.abs(G).max(), 1e-300))
    return float(max(PROBE_SAFETY * rel.max(), SCHUR_ERROR_FLOOR))
