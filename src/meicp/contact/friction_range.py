"""The friction up to which a contact state is proved free of divergence modes: what an
*undecided* divergence verdict can still state (issue 14, item 3).

Scale every contact line's μ by t ∈ [0, 1] with the contact states held: the pencil is
affine in t, ``A(t) = −(P̃₀ + t·P̃_μ) K Q̃`` and ``B(t) = (P̃₀ + t·P̃_μ) M Q̃``
(``P̃_μ = diag(μ)·P̃₁``: :meth:`~meicp.contact.maps.ReducedSystem.friction_rows`; K and M the
pencil's own, assembled once).  The Rayleigh bound of
:func:`meicp.contact.rayleigh.rayleigh_bound` — ``sym A(t) ≺ 0`` and ``sym B(t) ≻ 0``, so every
MEiCP solution has ``σ = xᵀsym(A)x / xᵀsym(B)x < 0`` — holds on a convex set of t: proved at
t = 0 (frictionless, held lattice) and at ``t_R`` it holds on all of ``[0, t_R]``.  ``t_R`` is
found by halving from the scene's μ (where the caller's verdict already failed) and then
geometric bisection, at most ``FACTORISATIONS`` LDLᵀ inertias.  The bound weakens as the
lattice grows (the condensed proofs of :mod:`.divergence.condensed` are sharper but cost a
condensation per σ-window and per μ); it is a statement of what was proved, no more.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from ..petsc.mat import combination, destroying
from ..petsc.pencil import reduced_pencil
from .problem import Pencil
from .rayleigh import rayleigh_bound

#: LDLᵀ inertias (each about one sparse factorisation of the pencil) spent locating t_R
FACTORISATIONS = 8
#: the search stops once the unproved and the proved t are within this ratio
RESOLUTION = 1.1


@dataclass(frozen=True)
class FrictionRange:
    """``scale``: t_R — with every μ scaled by any t in [0, t_R] the state has no divergence
    mode (proved; 0: nothing proved); ``failed``: the smallest t tried that was not proved
    (the search's other end); ``friction``: contact line → its μ·t_R; ``statement``: one
    sentence; ``factorisations``: inertias spent."""

    scale: float
    failed: float
    friction: dict = field(default_factory=dict)
    statement: str = ""
    factorisations: int = 0


def proved_friction_range(pen: Pencil, *, unproved_at: float = 1.0,
                          budget: int = FACTORISATIONS) -> FrictionRange:
    """The :class:`FrictionRange` of the pencil's contact states (collective on the pencil's
    communicator).  ``unproved_at``: a scale t already known not to be proved (the scene's
    own μ, t = 1, when the caller's Rayleigh bound failed there)."""
    red = pen.maps
    mus = {line.name: line.friction for line in pen.lines if line.friction > 0}
    if not mus or red.J.size == 0:
        return FrictionRange(0.0, unproved_at, {}, "no friction in the sliding contacts' rows", 0)
    A_mu, B_mu = reduced_pencil(pen.K, pen.M, red.friction_rows(), red.Q, red.retained)
    spent = 0

    def proved(t: float) -> bool:
        nonlocal spent
        spent += 1
        # A(t) = A − (1 − t)·A_μ with A_μ = −P̃_μKQ̃ (likewise B)
        with destroying(combination(pen.A, -(1.0 - t), A_mu), combination(pen.B, -(1.0 - t), B_mu)) as (At, Bt):
            return rayleigh_bound(At, Bt, 0.0, decisive=False).proved is True

    with destroying(A_mu, B_mu):
        if not proved(0.0):
            return FrictionRange(0.0, 0.0, {}, "no friction range proved: the Rayleigh bound fails already "
                                 "without friction (the lattice is not held once the sliding contacts slide, or "
                                 "sym(B) is not positive definite)", spent)
        lo, hi = 0.0, float(unproved_at)
        while spent < budget and (lo == 0.0 or hi / lo > RESOLUTION):
            t = hi / 2 if lo == 0.0 else math.sqrt(lo * hi)
            if proved(t):
                lo = t
            else:
                hi = t
    friction = {name: mu * lo for name, mu in mus.items()}
    if lo == 0.0:
        text = (f"stability is proved without friction only (the Rayleigh bound fails at {hi:.3g}× the scene's "
                f"friction; {spent} inertias)")
    else:
        at = ", ".join(f"μ ≤ {v:.4g} ({name})" for name, v in friction.items())
        text = (f"with these contact states stability is proved for friction up to {lo:.3g}× the scene's: {at} "
                f"(Rayleigh bound at both ends of the μ-segment, LDLᵀ inertias; not proved at {hi:.3g}×; "
                f"{spent} inertias)")
    return FrictionRange(lo, hi, friction, text, spent)
