"""What an LDLᵀ inertia proves about an MEiCP's σ: the Rayleigh bound and the sign of a
symmetric pencil, each decided with a margin above rounding (the inertias themselves are
:mod:`meicp.petsc.inertia`'s).

For a symmetric pencil (A, B) with B SPD, the number of eigenvalues σ ≥ 0 equals the number
of nonnegative eigenvalues of A: a factorisation *proves* that none exists, which an
eigensolver that only looks near a target cannot.  For every MEiCP solution (x real,
``xᵀw = 0``) ``σ·xᵀBx = xᵀAx``, i.e. ``σ = xᵀsym(A)x / xᵀsym(B)x``, so the same count on
``sym(A) − τ·sym(B)`` with ``sym(B) ≻ 0`` bounds every solution's σ below τ, for any pencil.

A proof must survive rounding: it factors ``A + η·D`` (``D = diag|a_ii|``, η above the
factorisation's backward error, :func:`~meicp.petsc.inertia.rounding_margin`): negative
definite means ``D^-½ A D^-½ ≺ −η·I`` as computed, hence A ≺ 0 — whatever the scaling of A's
rows (a layer 10¹⁵ times softer keeps its proof).  When ``A + ηD`` is not negative definite
but ``A − ηD`` is, the largest eigenvalue of the diagonally scaled A lies within rounding of
0: undecided, never "stable".  Collective on the matrices' communicator.

This module is shared: the divergence verdict (:mod:`meicp.contact.divergence`), the friction
range, the critical friction, the modal verdict and the condenser's τ all rest on it; it
sits beside them, not inside the divergence package, which itself uses the friction range.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..lattice.node_blocks import node_of
from ..petsc.inertia import (diagonal_minimum, is_symmetric_matrix, nonnegative_count, order, rounding_margin,
                             shifted_symmetric_parts, symmetric_part_of)


@dataclass(frozen=True)
class SignProof:
    """Whether every eigenvalue of a symmetric pencil (A, B) is proved negative.

    proved: True (B ≻ 0 and A ≺ 0 with a margin above rounding: no σ ≥ 0), None (the
    largest eigenvalue of A lies within ``margin`` of 0: undecided), False (A has an
    eigenvalue above the margin, or B is not positive definite: the bound proves nothing).
    reason: one sentence saying which.  margin: the rounding margin η used.  above: the
    eigenvalues of A proved above the margin (0 unless ``proved`` is False with B ≻ 0).
    b_definite: whether B ≻ 0 was proved (False: no Rayleigh-quotient bound holds at all).
    """

    proved: bool | None
    reason: str
    margin: float
    above: int = 0
    b_definite: bool = True


def pencil_is_negative(A, B, *, symmetric: bool = False) -> SignProof | None:
    """For a symmetric pencil (A, B): a proof that no eigenvalue σ ≥ 0 exists (see
    :class:`SignProof`), or None when the pencil is not symmetric.  A, B: SciPy (factored
    on this process) or PETSc Mats (collective).  ``symmetric=True``: the caller built both
    symmetric, the check (a transpose of each) is skipped."""
    if not symmetric and (not is_symmetric_matrix(A) or not is_symmetric_matrix(B)):
        return None
    return negative_with_margin(A, B, "A")


def rayleigh_bound(A, B, tau: float = 0.0, *, decisive: bool = True, comm=None, groups=None) -> SignProof:
    """Whether ``sym(A) − τ·sym(B) ≺ 0`` with ``sym(B) ≻ 0``, both with a margin above rounding.

    Proved: no MEiCP solution has σ ≥ τ (τ = 0: no divergence mode at all).  Holds for a
    nonsymmetric pencil, a non-diagonal B included (a one-row layer between two frictional
    interfaces).  A, B: SciPy or PETSc (collective).  ``decisive=False`` spares the second factorisation that tells a
    borderline case (None) from a clear failure (False): a caller that only acts on
    ``proved is True`` gets False for both, with ``above`` the eigenvalues not proved below
    the margin.  ``comm``: SciPy matrices every rank holds are factored over it (None: this
    process alone); ``groups``: their rows' lattice nodes, to factor them by node
    (:func:`~meicp.petsc.inertia.nonnegative_count`)."""
    with shifted_symmetric_parts(A, B, tau) as (SA, SB):
        name = "sym(A)" if tau == 0.0 else f"sym(A) {'−' if tau > 0 else '+'} {abs(tau):.6g}·sym(B)"
        return negative_with_margin(SA, SB, name, decisive, comm, groups)


def pencil_bound(pen, tau: float, comm=None) -> SignProof:
    """:func:`rayleigh_bound` of a :class:`~meicp.contact.problem.Pencil` at ``tau``, not
    decisive; a SciPy pencil every rank holds is factored over ``comm``, node by node."""
    groups = None if pen.distributed else node_of(pen.maps.retained)
    return rayleigh_bound(pen.A, pen.B, tau, decisive=False, comm=comm, groups=groups)


def symmetric_part_definite(B) -> tuple[bool, str]:
    """Whether ``sym(B) ≻ 0`` (exactly for a diagonal B, else by an LDLᵀ inertia with a
    margin above rounding) and the sentence saying how.  SciPy or PETSc (collective)."""
    with symmetric_part_of(B) as SB:
        return positive_definite(SB)


def negative_with_margin(A, B, name: str, decisive: bool = True, comm=None, groups=None) -> SignProof:
    """:class:`SignProof` of the symmetric pencil (A, B), ``name`` naming A in its reason;
    ``comm``, ``groups`` as in :func:`rayleigh_bound`."""
    b_ok, b_text = positive_definite(B, comm)
    if not b_ok:
        return SignProof(False, b_text, 0.0, b_definite=False)
    eta = rounding_margin(order(A))
    above = nonnegative_count(A, eta, comm, groups)  # eigenvalues of D^-½ A D^-½ ≥ −η
    if above == 0:
        return SignProof(True, f"{name} + η·diag|·| is negative definite (η = {eta:.1e}, above rounding) and "
                               f"{b_text}", eta)
    if not decisive:
        return SignProof(False, f"{name} + η·diag|·| is not negative definite ({above} eigenvalue(s) of the diagonally "
                                f"scaled {name} ≥ −η, η = {eta:.1e}): the bound excludes nothing", eta, above)
    clearly = nonnegative_count(A, -eta, comm, groups)  # ... ≥ +η
    if clearly == 0:
        return SignProof(None, f"{above} eigenvalue(s) of {name} lie within rounding of 0 ({name} − η·diag|·| is "
                               f"negative definite, {name} + η·diag|·| is not; η = {eta:.1e}): undecided", eta)
    return SignProof(False, f"{name} has {clearly} eigenvalue(s) above rounding ({name} − η·diag|·| is not "
                            f"negative definite, η = {eta:.1e}): the bound excludes nothing", eta, clearly)


def positive_definite(B, comm=None) -> tuple[bool, str]:
    """Whether B ≻ 0: exactly for a diagonal B (every mass positive), else by the inertia of
    ``B − η·diag|B|``."""
    diagonal, smallest = diagonal_minimum(B)
    if diagonal:
        if smallest > 0:
            return True, f"B is diagonal with positive entries (smallest {smallest:.3g})"
        return False, f"B is diagonal with an entry {smallest:.3g} ≤ 0: the Rayleigh-quotient bound does not apply"
    n = order(B)
    eta = rounding_margin(n)
    if n - nonnegative_count(B, -eta, comm) == 0:  # every pivot of B − η·diag|B| positive
        return True, f"B − η·diag|B| is positive definite (η = {eta:.1e})"
    return False, "B is not proved positive definite: the Rayleigh-quotient bound does not apply"
