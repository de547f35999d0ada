"""The cross-check of an enumerated critical friction on the σ-problem with the mass: a σ ≥ 0
mode must exist just above μ_c, and where modes exist below it they must be born at σ > 0,
each decided by enumerating the whole reduced pencil at that μ (every contact's μ set to it:
:meth:`~meicp.contact.maps.ReducedSystem.with_friction`).

On a damped lattice the enumeration is the quadratic MEiCP's (real λ ≥ 0, σ = λ²), and the
check above μ_c is left out: there a λ = 0 mode moves to λ ≈ c·(μ − μ_c)/(ξᵀDx), which is
negative when the friction rows make ξᵀDx < 0 — the mode then exists *below* μ_c instead,
and the check below finds where it starts (docs/damping.md)."""

from __future__ import annotations

import numpy as np

from ...core import limits
from ...core.errors import ConvergenceError
from ...eicp.quadratic import solve_quadratic_eicp
from ...eicp.solve import solve_eicp
from ..damped import damping_matrix
from ..maps import grazing_cases, reduced_system
from ..problem import pencil_of

#: a σ ≥ 0 mode whose σ is above this multiple of max|A|/max|B| where modes start is born at
#: σ > 0 (a pair of real σ out of a complex pair: flutter turning into divergence), not
#: through σ = 0 — no contradiction of μ_c, which is about σ = 0
BORN_ABOVE_ZERO = 1e-6


def largest_sigma(lattice, lines, mu) -> float | None:
    """The largest σ ≥ 0 of a mode with every contact's friction set to μ (enumeration; the
    lattice's K, M, which μ does not change), relative to max|A|/max|B|; None without a mode."""
    best = None
    for case in grazing_cases(lines):
        maps = reduced_system(lattice.model, lines, case).with_friction(mu)
        pen = pencil_of(lattice, lines, case, maps=maps)
        if pen.A is None:
            continue  # every DOF held: no mode (as in analyze)
        A, B = pen.A.toarray(), pen.B.toarray()
        if pen.damped:
            r = solve_quadratic_eicp(A, B, damping_matrix(pen).toarray(), pen.J, lam_min=0.0,
                                     max_j=limits.EICP_MAX_J)
            found = [max(sol.lam, 0.0) ** 2 for sol in r.solutions]
        else:
            r = solve_eicp(A, B, J=pen.J, method="enumerate", lam_min=0.0, max_j=limits.EICP_MAX_J)  # internal: no budget
            found = [sol.lam for sol in r.solutions]
        if found:
            sigma = max(found) / (np.abs(A).max() / max(np.abs(B).max(), 1e-300))
            best = sigma if best is None else max(best, sigma)
    return best


def check_by_bisection(lattice, lines, mu_c, mu_max, tol) -> tuple[str, float | None]:
    """Existence of a σ ≥ 0 mode against μ_c: one just above it, and where modes exist below
    it (or, without μ_c, at ``mu_max``) they must start at σ > 0 — a pair born there, not a
    σ = 0 crossing that μ as an eigenvalue missed.  Returns ``(note, start)``: a note for the
    evidence ("" when modes start at μ_c) and the μ where the modes found below start (a μ
    with a certified mode; None when none was found below).  With damping a mode must exist
    on one side of μ_c at least (the λ = 0 mode moves to one).  ConvergenceError on a
    contradiction."""
    def sigma_at(mu):
        return largest_sigma(lattice, lines, mu)

    damped = lattice.model.damped
    top = mu_c * (1 - 1e-6) - 1e-12 if np.isfinite(mu_c) else mu_max
    above = sigma_at(mu_c * (1 + 1e-6) + 1e-12) if np.isfinite(mu_c) else None
    if np.isfinite(mu_c) and not damped and above is None:
        raise ConvergenceError(f"no σ ≥ 0 mode just above μ_c = {mu_c:.8g}: μ as an eigenvalue and "
                               "existence disagree")
    sigma = None if top < 0 else sigma_at(top)
    if sigma is None:
        if damped and np.isfinite(mu_c) and above is None:
            raise ConvergenceError(f"no damped divergence mode on either side of μ_c = {mu_c:.8g}, where a λ = 0 "
                                   "mode is certified: μ as an eigenvalue and existence disagree")
        return "", None
    start, at_zero = 0.0, sigma_at(0.0)
    if at_zero is not None:
        sigma = at_zero
    else:  # bisect down to where modes start, keeping the largest σ there
        lo, hi = 0.0, top
        while hi - lo > tol * max(1.0, hi):
            mid = 0.5 * (lo + hi)
            found = sigma_at(mid)
            lo, hi, sigma = (lo, mid, found) if found is not None else (mid, hi, sigma)
        start = hi
    where = f"below μ_c = {mu_c:.8g}" if np.isfinite(mu_c) else f"with no σ = 0 mode up to μ = {mu_max:g}"
    if sigma <= BORN_ABOVE_ZERO:
        raise ConvergenceError(f"σ ≥ 0 modes start at μ ≈ {start:.8g} with σ ≈ 0, {where}: a σ = 0 crossing that "
                               "μ as an eigenvalue missed")
    if start == 0.0:  # without friction the pencil is symmetric: unstable already, no crossing involved
        return (f"; divergence modes exist {where} already at μ = 0 (σ = {sigma:.3g}·max|A|/max|B|; enumeration "
                "of the σ-problem)"), 0.0
    return (f"; divergence modes exist {where}, from μ ≈ {start:.8g}, born at σ = {sigma:.3g}·max|A|/max|B| > 0 "
            "(a pair of real σ, not through σ = 0; enumeration of the σ-problem)"), start
