"""Damping proportional to stiffness and mass (Rayleigh damping, ``C = cK + αM``): the damped
divergence problem *is* the undamped MEiCP (docs/damping.md, "Proportional damping").

When every bond's viscosity is the same multiple c of its stiffness (one relaxation time η/k
in every layer, band and bonded interface) and ``[damping] mass = α``, then ``C = cK + αM``
entry by entry, so for any contact maps ``D = P̃CQ̃ = −cA + αB`` and

    λ²B + λD − A = (1 + cλ)·(σ(λ)B − A),      σ(λ) = (λ² + αλ)/(1 + cλ).

For λ ≥ 0 the factor 1 + cλ is positive (y and w = y/(1 + cλ) have the same signs, the same
zeros) and σ(λ) increases from σ(0) = 0 to ∞, so (λ, x) solves the quadratic MEiCP with
λ ≥ 0 exactly when (σ(λ), x) solves the undamped MEiCP with σ ≥ 0, on the same support.
The undamped verdict of the same pencil (A and B alone, every path at every size:
:func:`~meicp.contact.divergence.driver.divergence_of`) therefore decides the damped one —
its proofs prove, its modes map to damped modes λ = λ(σ), the root ≥ 0 of
``λ² + (α − cσ)λ − σ = 0``, each certified again on the quadratic MEiCP itself, row by row
(:func:`meicp.petsc.damped_refine.quadratic_certificate`).  The same identity puts every
eigenvalue of the quadratic sliding pencil on a root of that scalar equation at an eigenvalue
σ of (A, B) (``det Q(λ) = (1 + cλ)ⁿ det(σ(λ)B − A)``).

Proportional here means ``|η − c·k| ≤ PROPORTIONAL_ROUNDING·η`` on every pair of materials a
bond joins: the input's own rounding (0.1 / 5 and 0.02 differ in the last bit), far inside the
proofs' margins (``tol`` 1e-10 of the matrices' scale).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, replace

import numpy as np

from ..core.comm import mpi_comm
from ..core.matrix import max_abs_entry
from ..eicp.problem import lam_floor
from ..petsc.flutter_quadratic import QuadraticPencilOps
from ..petsc.mat import distributed
from .damped_modes import CERTIFICATE_TOL, certified_mode
from .divergence.driver import divergence_of
from .divergence.verdict import DivergenceProof, DivergenceVerdict
from .flutter_verdict import RESIDUAL_TOL, SAME, FlutterCandidate, RejectedPair

log = logging.getLogger("meicp")

#: how far η may be from c·k, in units of η's rounding, and still count as proportional
PROPORTIONAL_ROUNDING = 8 * np.finfo(float).eps
#: the proof test of a damped verdict decided by the undamped one
TEST = "proportional-damping"


@dataclass(frozen=True)
class ProportionalDamping:
    """``C = stiffness·K + mass·M`` (c ≥ 0 and α ≥ 0, not both 0)."""

    stiffness: float
    mass: float

    def sigma_of(self, lam):
        """σ(λ) = (λ² + αλ)/(1 + cλ): the undamped σ whose pencil the damped one is at λ."""
        return (lam * lam + self.mass * lam) / (1 + self.stiffness * lam)

    def lam_of(self, sigma: float) -> float:
        """The root λ ≥ 0 of ``λ² + (α − cσ)λ − σ = 0`` for σ ≥ 0 (σ a few ulps below 0, an
        exact σ = 0 computed in rounding, gives λ within rounding of 0): the inverse of
        :meth:`sigma_of` on [0, ∞)."""
        p = self.mass - self.stiffness * sigma
        disc = p * p + 4 * sigma
        root = math.sqrt(max(disc, 0.0))
        # the form without cancellation: −p + root when p ≤ 0, 2σ/(p + root) when p > 0
        return 0.5 * (root - p) if p <= 0 else 2 * sigma / (p + root)

    def describe(self) -> str:
        parts = ([f"{self.stiffness:g}·K"] if self.stiffness else []) + ([f"{self.mass:g}·M"] if self.mass else [])
        return "C = " + " + ".join(parts)


def growing_root(damping: ProportionalDamping, sigma: complex) -> complex:
    """The root of ``λ² + (α − cσ)λ − σ = 0`` with the larger real part (the other is
    ``−(α − cσ) − λ``): the damped eigenvalue an undamped eigenvalue σ gives that grows the
    faster.  Formed without cancellation (the product of the roots is −σ)."""
    p = damping.mass - damping.stiffness * complex(sigma)
    root = np.sqrt(p * p + 4 * complex(sigma))
    big = -0.5 * (p + root) if (p.conjugate() * root).real >= 0 else -0.5 * (p - root)  # |big| the larger
    other = -complex(sigma) / big if big != 0 else 0j
    return big if big.real >= other.real else other


def bonded_pairs(model) -> tuple[np.ndarray, np.ndarray]:
    """``(k, η)`` of every pair of materials some bond of the lattice joins (the bonds a
    frictional interface cuts do not count): the coefficients C and K are assembled from."""
    pairs = model.bonded_materials
    return (np.array([model.kmat[a, b] for a, b in pairs], dtype=float),
            np.array([model.cmat[a, b] for a, b in pairs], dtype=float))


def proportional_damping(model) -> ProportionalDamping | None:
    """The proportional damping of a :class:`~meicp.lattice.model.LatticeModel`, or None when
    it has none or its damping is not proportional: every pair of materials a bond joins has
    ``η = c·k`` with one c (within :data:`PROPORTIONAL_ROUNDING`)."""
    if not model.damped:
        return None
    k, eta = bonded_pairs(model)
    if not k.size:  # no bond: only α·M, proportional to the mass alone
        return ProportionalDamping(0.0, float(model.damping_mass))
    c = float(eta[0] / k[0])
    if not np.all(np.abs(eta - c * k) <= PROPORTIONAL_ROUNDING * np.maximum(eta, c * k)):
        return None
    return ProportionalDamping(c, float(model.damping_mass))


def proportional_divergence(pen, scene, comm, damping: ProportionalDamping, lam_min: float, tol: float,
                            options) -> DivergenceVerdict:
    """The damped divergence verdict of ``pen`` from the undamped verdict of its A and B
    (module docstring): the same proof, or its modes mapped to λ ≥ 0 and certified on the
    quadratic MEiCP; modes with σ = λ² ≥ lam_min listed.  Collective."""
    undamped = divergence_of(pen, scene, comm, "auto", 0.0, tol, options)
    head = (f"damping proportional to stiffness and mass ({damping.describe()}): λ²B + λD − A = (1 + cλ)(σB − A) "
            f"with σ = (λ² + αλ)/(1 + cλ), so the undamped MEiCP of the same pencil decides it")
    proof = undamped.proof
    window = proof.sigma_window
    if window:  # the undamped σ-window as σ = λ², the damped results' unit
        window = tuple(damping.lam_of(float(s)) ** 2 if math.isfinite(s) else s for s in window)
    if undamped.stable is not False:
        text = f"{head}: {undamped.evidence}"
        return DivergenceVerdict([], undamped.stable, text, undamped.eicp,
                                 replace(proof, test=TEST if undamped.stable else "", sigma_window=window,
                                         statement=f"{head}: {proof.statement}"))
    modes, notes = _mapped_modes(pen, comm, damping, undamped)
    if not modes:
        text = (f"undecided: {head}; it found divergence ({undamped.evidence}), but no mapped mode passed the "
                f"quadratic MEiCP's certificate {CERTIFICATE_TOL:g}: {'; '.join(notes)}")
        return DivergenceVerdict([], None, text, undamped.eicp, DivergenceProof("", text))
    listed = [m for m in modes if lam_min == 0 or m.sigma >= lam_min]
    growth = ", ".join(f"{np.sqrt(m.sigma):.6g}" for m in modes[:3])
    text = (f"{head}: {len(modes)} certified damped divergence mode(s), growth rate λ = {growth} "
            f"({'; '.join(notes)}; the undamped verdict: {undamped.evidence})")
    return DivergenceVerdict(listed, False, text, undamped.eicp,
                             replace(proof, test=TEST, sigma_window=window, statement="certified mode(s)"))


def _mapped_modes(pen, comm, damping: ProportionalDamping, undamped: DivergenceVerdict) -> tuple[list, list]:
    """The undamped verdict's modes (every solution with σ ≥ 0 of its EiCP result) as damped
    modes λ = λ(σ), each certified on the quadratic MEiCP; and a note on each."""
    red = pen.maps
    scales = (max_abs_entry(pen.A), max_abs_entry(pen.B))
    solutions = [s for s in getattr(undamped.eicp, "solutions", None) or [] if s.lam >= lam_floor(0.0, scales)]
    modes, notes = [], []
    with distributed(mpi_comm(comm), pen.A, pen.B, pen.damping()) as mats, QuadraticPencilOps(*mats) as ops:
        for sol in solutions:
            lam = max(damping.lam_of(float(sol.lam)), 0.0)  # 0 within rounding: ≥ 0
            mode, why = certified_mode(ops, red, lam, np.asarray(sol.x, dtype=float))
            notes.append(f"σ = {sol.lam:.6g} → λ = {lam:.8g}: " + (why if mode else f"{why}, not certified"))
            if mode is not None:
                modes.append(mode)
    modes.sort(key=lambda m: -m.sigma)
    log.info("damped divergence (proportional damping): %s", "; ".join(notes) or "no undamped mode")
    return modes, notes


def mapped_flutter(ops, damping: ProportionalDamping, candidates, margin) -> tuple[list, list, int]:
    """The damped flutter modes of an undamped search's certified modes ``candidates``
    (:class:`~meicp.contact.flutter_verdict.FlutterCandidate`, σ non-real, x on every rank):
    each σ gives λ = :func:`growing_root`, with x an eigenvector of Q(λ) = (1 + cλ)(σ(λ)B − A).
    ``(modes, rejected, damped_out)``: FlutterCandidates with σ = λ² whose backward error on
    Q itself (``ops``: :class:`~meicp.petsc.flutter_quadratic.QuadraticPencilOps`) passes the
    residual gate and whose Re λ and Im λ exceed ``margin(λ, residual, x)``; RejectedPairs; and
    how many grow no faster than their margin (the damping holds them).  Collective."""
    lo, hi = ops.A.getOwnershipRange()
    modes, rejected, damped_out = [], [], 0
    for cand in candidates:
        lam, x = growing_root(damping, cand.sigma), np.asarray(cand.x)
        if lam.imag < 0:  # the conjugate pair: its eigenvector conjugated
            lam, x = lam.conjugate(), x.conjugate()
        res = ops.residual(lam, x[lo:hi])
        r = margin(lam, res, x)
        if res > RESIDUAL_TOL:
            rejected.append(RejectedPair(lam * lam, res))
        elif any(abs(lam * lam - m.sigma) <= SAME * abs(m.sigma) for m in modes):
            continue  # σ and its conjugate give one mode
        elif lam.real > r and lam.imag > r:
            modes.append(FlutterCandidate(lam * lam, x, res, 2 * abs(lam) * r + r * r,
                                          f"{cand.found_by}, λ = {lam:.6g} of σ = {cand.sigma:.6g}"))
        else:
            damped_out += 1
    return modes, rejected, damped_out


__all__ = ["ProportionalDamping", "bonded_pairs", "growing_root", "mapped_flutter", "proportional_damping", "proportional_divergence"]
