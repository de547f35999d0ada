"""The pencil scaled before its eigenvalues decide anything, and Newton refinement of a pair.

Why.  Support enumeration proves "no solution" from the eigenvalues of every reduced
pencil ``(A_RR, B_RR)``.  Those are computed to an absolute accuracy of about
``eps·‖A_RR‖`` and ``eps·‖B_RR‖``, which means nothing for a row of B that is 1e16 times
smaller than the others: with one layer's density 1e-16 the mode of the light layer
(σ ≈ 0.33/ρ) was computed as rounding noise on every support and the enumeration
"proved" stability.  With A·1e300 and B·1e-300 the products overflowed.  So the
enumeration works on

    Ã = 2^ea · D A D,   B̃ = 2^eb · D B D,   D = diag(2^e)

with ``e`` from Ruiz's symmetric equilibration of |B| (rows and columns of largest entry
≈ 1; for a diagonal B this is the mass normalisation, B̃ = I) and ``ea, eb`` making
``max|Ã| = max|B̃| = 1``.  Powers of two scale exactly, so ``(λ, x)`` solves the (M)EiCP of
(A, B) iff ``(λ̃, y) = (2^−E λ, D⁻¹x)`` solves that of (Ã, B̃), ``E = eb − ea``: D is
positive, so signs and complementarity are kept, and symmetry too.  λ is mapped back with
``ldexp`` (an overflow becomes ±inf: a λ beyond double precision, reported as such).

:func:`refine_pair` polishes a candidate by Newton's method on the bordered reduced system
in the original coordinates: eigenvalues computed on a graded matrix are accurate only
relative to its largest entries, and a few Newton steps make the row-wise residual small
where the pair is near a true one (and leave it large where it is rounding noise).
"""

from __future__ import annotations

import numpy as np

from ..core.matrix import ldexp, release
from .problem import EiCPProblem, certify_pair

#: bound on the equilibration exponents: scaled entries stay finite (2^800 < 1e308)
MAX_EXPONENT = 400
#: Ruiz sweeps at most; it stops when every row and column maximum is within 2× of 1
SWEEPS = 30


def _exponent(v) -> np.ndarray:
    """Integer exponents e with 2^e nearest v (v > 0)."""
    return np.round(np.log2(v)).astype(np.int64)


def symmetric_equilibration(absB: np.ndarray) -> np.ndarray:
    """Exponents e such that ``2^e_i |B_ij| 2^e_j`` has row and column maxima ≈ 1 (rows of B
    that are zero keep e = 0)."""
    e = np.zeros(absB.shape[0], dtype=np.int64)
    for _ in range(SWEEPS):
        S = np.ldexp(absB, e[:, None] + e[None, :])
        r = np.maximum(S.max(axis=1), S.max(axis=0))
        live = r > 0
        if not live.any() or np.abs(np.log2(r[live])).max() <= 1.0:
            break
        e[live] -= _exponent(np.sqrt(r[live]))
        np.clip(e, -MAX_EXPONENT, MAX_EXPONENT, out=e)
    return e


def _max_exponent(M: np.ndarray) -> int:
    """−(exponent of max|M|): 2^result·M has largest entry ≈ 1 (0 for a zero matrix)."""
    big = np.abs(M).max() if M.size else 0.0
    return -int(_exponent(big)) if big > 0 else 0


class PencilScaling:
    """``Ã, B̃`` (dense, the module docstring's scaling) and the maps between the two problems.

    ``balance="B"`` equilibrates |B| (λ of every size resolved relative to B̃'s rows);
    ``"A"`` equilibrates |A| instead, which resolves the λ near 0 that the first cannot
    when the rows of B differ by many orders (see :mod:`meicp.eicp.enumeration`)."""

    def __init__(self, A: np.ndarray, B: np.ndarray, balance: str = "B"):
        # max|A| = max|B| = 1 first, so that the equilibration cannot overflow the other matrix
        ea0, eb0 = _max_exponent(A), _max_exponent(B)
        A1, B1 = np.ldexp(A, ea0), np.ldexp(B, eb0)
        e = symmetric_equilibration(np.abs(B1 if balance == "B" else A1))
        E = e[:, None] + e[None, :]
        A1, B1 = np.ldexp(A1, E), np.ldexp(B1, E)
        ea1, eb1 = _max_exponent(A1), _max_exponent(B1)
        self.A, self.B = np.ldexp(A1, ea1), np.ldexp(B1, eb1)
        self.e = e
        self.lam_exponent = (eb0 + eb1) - (ea0 + ea1)  # λ = 2^E λ̃

    def lam(self, lam_scaled):
        """λ of the original problem: ±inf beyond double precision, NaN for a nonzero λ̃
        whose λ underflows (below the smallest normal number)."""
        lt = np.asarray(lam_scaled, dtype=np.float64)
        with np.errstate(over="ignore", under="ignore"):
            lam = np.ldexp(lt, self.lam_exponent)
        return np.where((lt != 0) & (np.abs(lam) < np.finfo(float).tiny), np.nan, lam)

    def lam_scaled(self, lam):
        """λ̃ for a λ bound of the original problem (None and ±inf pass through)."""
        if lam is None or not np.isfinite(lam):
            return lam
        with np.errstate(over="ignore", under="ignore"):
            return float(np.ldexp(lam, -self.lam_exponent))

    def x(self, Y: np.ndarray) -> np.ndarray:
        """Rows of Y (vectors of the scaled problem) as vectors of the original one, each
        normalised to ‖x‖∞ = 1 first so that 2^e cannot overflow."""
        Y = np.array(Y, dtype=np.float64, ndmin=2)
        with np.errstate(over="ignore", under="ignore", invalid="ignore"):
            X = np.ldexp(Y, self.e[None, :])
            big = np.abs(X).max(axis=1, keepdims=True)
            return X / np.where(big > 0, big, 1.0)


def refine_pair(A: np.ndarray, B: np.ndarray, R: np.ndarray, lam: float, x: np.ndarray, steps: int = 3):
    """Newton steps on ``F(ξ, λ) = ((A_RR − λB_RR)ξ, cᵀξ − 1)`` from the candidate (c: the
    start normalised, ``cᵀξ₀ = 1``).  Returns ``(λ, x)`` (x zero off R), or None when a step
    fails (singular bordered matrix, non-finite values)."""
    if not np.isfinite(lam):
        return None
    AR, BR = A[np.ix_(R, R)], B[np.ix_(R, R)]
    xi = x[R] / np.abs(x[R]).max()
    c = xi / (xi @ xi)
    k = R.size
    J = np.empty((k + 1, k + 1))
    J[k, :k], J[k, k] = c, 0.0
    with np.errstate(all="ignore"):
        for _ in range(steps):
            Bxi = BR @ xi
            J[:k, :k] = AR - lam * BR
            J[:k, k] = -Bxi
            try:
                d = np.linalg.solve(J, -np.concatenate([AR @ xi - lam * Bxi, [c @ xi - 1.0]]))
            except np.linalg.LinAlgError:
                return None
            if not np.all(np.isfinite(d)):
                return None
            xi, lam = xi + d[:k], lam + d[k]
    out = np.zeros(x.size)
    out[R] = xi
    return float(lam), out


# -- the iterative methods: one global scaling, λ mapped back ------------------------------

#: a pencil whose largest entries are within 2^±RANGE_EXPONENT of 1 is solved as given (no
#: copy); beyond, the iterative methods run on A·2^ea, B·2^eb (max|A| ≈ max|B| ≈ 1): with
#: A·1e300 and B·1e-300 their Rayleigh quotients, shifts and start eigenvalues overflowed
RANGE_EXPONENT = 100


def normalised(problem):
    """``(scaled, E)``: the problem with max|A| ≈ max|B| ≈ 1 and λ = 2^E·λ̃, or
    ``(problem, None)`` when its scales are within 2^±RANGE_EXPONENT (nothing to do)."""
    a, b = problem.scales()
    ea = -int(_exponent(a)) if a > 0 else 0
    eb = -int(_exponent(b))
    if abs(ea) <= RANGE_EXPONENT and abs(eb) <= RANGE_EXPONENT:
        return problem, None
    scaled = EiCPProblem(ldexp(problem.A, ea), ldexp(problem.B, eb), problem.J)
    return scaled, eb - ea


def scaled_value(value, E: int):
    """A λ-valued argument (lam_min, target, lam0) in the scaled pencil's units."""
    if value is None:
        return None
    with np.errstate(over="ignore", under="ignore"):
        return float(np.ldexp(float(value), -E))


def restore(problem, scaled, result, E: int, tol: float):
    """Map a result of the scaled problem back: λ = 2^E·λ̃, each solution re-certified on
    the original pencil; a λ beyond double precision makes the status ``out_of_range``."""
    kept, beyond = [], []
    for s in result.solutions:
        with np.errstate(over="ignore", under="ignore"):
            lam = float(np.ldexp(s.lam, E))
        if not np.isfinite(lam) or (s.lam != 0 and abs(lam) < np.finfo(float).tiny):
            beyond.append(s)
            continue
        sol = certify_pair(problem, lam, s.x)
        (kept if sol.residual <= tol else beyond).append(sol)
    result.solutions = kept
    result.candidates = beyond + list(result.candidates)
    result.coverage = dict(result.coverage, lam_exponent=E)
    if result.status == "solved" and not kept:
        result.status = "out_of_range"
        result.message = (f"certified on the pencil scaled to max|A| = max|B| = 1, but λ = 2^{E}·λ̃ is beyond "
                          f"double precision (λ̃ = {beyond[0].lam:.6g}; in candidates): {result.message}")
    elif result.status == "solved" and beyond:
        result.message += f"; {len(beyond)} more with λ beyond double precision (in candidates)"
    release(scaled.A)  # the scaled copies (a PETSc Mat's memory is not Python's)
    release(scaled.B)
    return result
