"""Proofs that a contact state's MEiCP has no divergence mode (real σ ≥ 0) in a σ-window,
by condensation onto the complementarity DOFs J (docs/critical-friction.md, "condensed
tests"):

    T1  σ = 0      G(0) ∈ R₀: a positive diagonal D with sym(DG(0)) ≻ 0 (one condensation)
    T2  windows    G(σ) ∈ R₀ for every σ in [0, σ_max], by certificates on windows
                   [σ_a, σ_b] from condensations at their ends (:mod:`.windows`, :mod:`.cover`)

(G(σ) of :mod:`meicp.contact.condensation`; the certificates of :mod:`meicp.lcp.certificates`.)  Every
certificate is decided with its rounding margin (the dense eigen-solve's and the
condensation's error) and a caller's relative ``tol``: a borderline case is not proved.

The condensations are those of :class:`meicp.contact.condenser.Condenser` (MUMPS: solves with a bounded
error, or Schur complements with a measured one).  Collective on ``comm``; the dense
certificates run on rank 0, the other ranks serve its condensations.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

from ...core.comm import mpi_comm
from ...lcp.certificates import optimise_scaling, pd_certificate
from ..condenser import Condenser
from ..on_root import decided_on_root
from .cover import Cover, cover


@dataclass(frozen=True)
class CondensedProof:
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
                        max_samples: int = 16) -> CondensedProof:
    """Prove that the MEiCP of ``pencil`` has no solution with σ in [0, σ_max].

    comm: the communicator (None: serial); collective.  pencil: a
    :class:`~meicp.contact.problem.Pencil` (SciPy or distributed; its ``maps`` and its
    lattice's K, M are read: the pieces K̃, M̃, N of the split pencil are built on every rank).
    sigma_max: the caller's certified upper end of the window (no solution above it, e.g. by
    an inertia of sym(σ_max B − A)); 0 asks for σ = 0 only; ``inf`` is allowed (the last
    window is [σ_a, ∞)).  tol: relative margin every certificate must clear on top of its
    rounding allowance.  method: ``"schur"``, ``"solves"`` or ``"auto"``
    (:mod:`meicp.contact.condenser`).  max_samples: condensations allowed for the windows.

    Contract: ``proved=True`` is a proof (every certificate re-checked with its margin; with
    the Schur method the condensation error is measured, as the statement says);
    ``proved=False`` proves nothing either way (a mode may or may not exist) and says why.
    T2 needs B diagonal (lumped mass: M̃ diagonal, N_M = 0) — a base contact or a frictional
    interface in centre-of-mass coordinates; where a one-row layer lies between two interfaces
    B is not diagonal and only σ_max = 0 can be proved (T1), a wider window is undecided.
    """
    comm = mpi_comm(comm)
    t_start = time.perf_counter()
    if not (sigma_max >= 0):
        raise ValueError(f"sigma_max must be ≥ 0, got {sigma_max}")
    if np.asarray(pencil.J).size == 0:
        return CondensedProof(False, "", "no complementarity DOFs: nothing to condense", np.nan, 0, ())
    with Condenser.of(pencil, comm, method=method) as cond:
        return _prove(comm, cond, sigma_max, tol, max_samples, t_start)


def _prove(comm, cond, sigma_max, tol, max_samples, t_start) -> CondensedProof:
    if sigma_max > 0 and not cond.pieces.mass_is_diagonal:
        return CondensedProof(False, "", "the σ-window certificates need a diagonal B (lumped mass); this pencil couples "
                               "contact and free DOFs through its mass (a one-row layer between two frictional "
                               "interfaces): only σ = 0 can be certified, the window is undecided", np.nan, 0, ())
    if not cond.prepare(need_tau=sigma_max > 0):
        return CondensedProof(False, "", cond.why, np.nan, 0, (), dict(cond.seconds))
    t = time.perf_counter()
    # rank 0 decides; the other ranks serve its requests (a σ to condense at, or SHARPER_TAU)
    out = decided_on_root(comm, lambda served: _decide(served, lambda: served(SHARPER_TAU), sigma_max, cond.tau,
                                                       tol, max_samples, cond.tau_scale),
                          lambda request: _serve(cond, request))
    secs = {**cond.seconds, "certify": time.perf_counter() - t, "total": time.perf_counter() - t_start}
    return replace(out, statement=f"{out.statement}; {cond.error_text()}", seconds=secs)


#: the request, served like a σ, that certifies the λ_min estimate as τ (:meth:`Condenser.sharper_tau`)
SHARPER_TAU = "sharper τ"


def _serve(cond: Condenser, request):
    return cond.sharper_tau() if request == SHARPER_TAU else cond.at(request)


def _decide(condense_at, sharper_tau, sigma_max, tau, tol, max_samples, scale=None) -> CondensedProof:
    """T1 then T2 on rank 0 (the statement without the condensation's error, no seconds)."""
    c0 = condense_at(0.0)
    G0 = c0.G()
    d, _ = optimise_scaling([G0], iters=40)
    cert = pd_certificate(G0, c0.error(), d, tol=tol)
    if not cert.proved:
        return CondensedProof(False, "", f"σ = 0 not excluded: no diagonal scaling D found with sym(DG(0)) ≻ 0 "
                              f"beyond rounding (margin {cert.margin:.2e})", cert.margin, 1, ())
    if sigma_max == 0:
        return CondensedProof(True, "condensed-pd", f"G(0) ∈ R₀: sym(DG(0)) ≻ 0 for a positive diagonal D (λ_min "
                              f"{cert.lam_min:.3e} > rounding {cert.rounding:.1e}): no σ = 0 mode", cert.margin, 1,
                              (0.0, 0.0))
    settings = Cover(1.0, tau, sigma_max=sigma_max, max_samples=max_samples, d_seed=d, tol=tol, scale=scale)
    cov = cover(condense_at, settings, sharper_tau=sharper_tau, scalings={0.0: d})
    n = len(cov.samples)
    if cov.proved:
        margin = min([cert.margin] + [w[2] for w in cov.windows])
        split = f", split at the scale {scale:.3g}" if scale and scale > cov.tau else ""
        return CondensedProof(True, "condensed-windows", f"G(σ) ∈ R₀ on every window of [0, {sigma_max:.6g}] "
                              f"({len(cov.windows)} windows, {n} condensations, τ = {cov.tau:.3g} certified{split})",
                              margin, n, (0.0, float(sigma_max)))
    covered = 0.0
    for a, b, *_ in sorted(cov.windows):
        if a <= covered:
            covered = max(covered, b)
    a, b, m = cov.failed
    return CondensedProof(False, "", f"window [{a:.6g}, {b:.6g}] not certified (margin {m:.2e}) after {n} "
                          f"condensations; proved free of modes: [0, {covered:.6g}]", m, n, (0.0, float(covered)))
