"""The value of the zero-sum matrix game with payoff ``M`` (seed 002 §4, docs/design.md §3.2; the
seed's erratum in §12).

Convention (seed 002 eq. (17)): the row player ("the structure") picks ``x`` in the
simplex Δ to *minimise* ``xᵀMy``, the column player ("the environment") picks ``y`` in Δ
to *maximise* it::

    v(M) = min_{x∈Δ} max_{y∈Δ} xᵀMy = min_{x∈Δ} max_j (Mᵀx)_j = max_{y∈Δ} min_i (My)_i

(the last equality is von Neumann's minimax theorem).  Two linear programs compute it,
one per player, and each optimal strategy is a certificate on its own side:

    upper = max_j (Mᵀx)_j  ≥  v(M)  ≥  min_i (My)_i = lower

so ``upper − lower`` (the duality gap, relative to ``max|M|``) is the residual.  We solve
both LPs rather than read ``y`` off the first LP's multipliers because each strategy is
then checked by its own product with ``M``, independently of the LP solver's sign
conventions.

Why the value matters for the LCP: ``v(M) > 0`` iff some ``y ≥ 0`` has ``My > 0`` (M is
an S-matrix), iff ``LCP(q, M)`` is feasible for every ``q``.  Every Q-matrix is an
S-matrix (take ``q < 0``), so ``v(M) ≤ 0`` proves that ``M`` is not Q: for every
``q < 0`` the LCP has no feasible point at all.  The seed's uniform-strategy numbers for
the 3×3 tridiagonal matrix are wrong; the value is 1/5 at ``x* = y* = (0.3, 0.4, 0.3)``.
"""

from __future__ import annotations

from dataclasses import dataclass
import time

import numpy as np
import scipy.sparse as sp
from scipy.optimize import linprog

from ..core.results import SOLVED, Result
from ..core.validation import as_matrix, checked_keywords, scale

#: duality gap, relative to max|M|, below which the value is certified
GAP_TOL = 1e-9

_HIGHS_OPTIONS = {"primal_feasibility_tolerance": 1e-10, "dual_feasibility_tolerance": 1e-10}


@dataclass
class GameValue(Result):
    """Value and optimal strategies of the matrix game ``min_x max_y xᵀMy``.

    value: midpoint of ``[lower, upper]``; equals v(M) to within ``residual·max|M|``.
    x: the row (minimising) player's optimal strategy, in the simplex.
    y: the column (maximising) player's optimal strategy, in the simplex.
    lower: ``min_i (My)_i`` — a proven lower bound on v(M) (y guarantees at least this).
    upper: ``max_j (Mᵀx)_j`` — a proven upper bound on v(M) (x concedes at most this).
    residual: ``(upper − lower) / max|M|``, the relative duality gap; ``status`` is
        ``"solved"`` only when it is at most ``GAP_TOL``.
    """

    value: float = float("nan")
    x: np.ndarray | None = None
    y: np.ndarray | None = None
    lower: float = float("nan")
    upper: float = float("nan")

    def __repr__(self) -> str:
        return f"GameValue({self.value:.6g} in [{self.lower:.6g}, {self.upper:.6g}], {self.status})"

    def to_dict(self) -> dict:
        return {
            "value": _plain(self.value),
            "x": None if self.x is None else [float(t) for t in self.x],
            "y": None if self.y is None else [float(t) for t in self.y],
            "lower": _plain(self.lower),
            "upper": _plain(self.upper),
            "status": self.status,
            "residual": _plain(self.residual),
            "message": self.message,
        }


def _plain(v: float):
    """A float for JSON, with NaN as None."""
    v = float(v)
    return None if np.isnan(v) else v


def _to_simplex(z: np.ndarray) -> np.ndarray:
    """Clip LP round-off (tiny negatives) and renormalise, so the strategy is exactly in Δ."""
    z = np.clip(np.asarray(z, dtype=np.float64), 0.0, None)
    total = z.sum()
    if not total > 0:
        return np.full(z.shape, 1.0 / z.size)
    return z / total


def _minimiser_lp(A):
    """``min t  s.t.  Aᵀx ≤ t·1, 1ᵀx = 1, x ≥ 0``: the row player's optimal ``x`` for payoff A."""
    m, n = A.shape
    if sp.issparse(A):
        A_ub = sp.hstack([A.T.tocsr(), -sp.csr_matrix(np.ones((n, 1)))], format="csr")
        A_eq = sp.csr_matrix(np.concatenate([np.ones(m), [0.0]])[None, :])
    else:
        A_ub = np.hstack([A.T, -np.ones((n, 1))])
        A_eq = np.concatenate([np.ones(m), [0.0]])[None, :]
    c = np.zeros(m + 1)
    c[-1] = 1.0
    bounds = [(0.0, None)] * m + [(None, None)]
    res = linprog(c, A_ub=A_ub, b_ub=np.zeros(n), A_eq=A_eq, b_eq=[1.0], bounds=bounds,
                  method="highs", options=_HIGHS_OPTIONS)
    return res


@checked_keywords()
def game_value(M) -> GameValue:
    """Value ``v(M) = min_{x∈Δ} max_{y∈Δ} xᵀMy`` with both optimal strategies, certified.

    ``M`` may be dense or SciPy sparse, and need not be square (x has one entry per row,
    y one per column).  The row player's LP gives ``x`` (upper bound), the column
    player's LP — the same LP for the payoff ``−Mᵀ``, since ``v(M) = −v(−Mᵀ)`` — gives
    ``y`` (lower bound).  Raises :class:`~meicp.core.errors.ProblemError` on bad input.
    """
    t0 = time.perf_counter()
    M = as_matrix(M, "M", square=False)
    s = scale(M)
    A = M / s  # the LP sees entries of size ≤ 1; everything is scaled back at the end
    row = _minimiser_lp(A)
    col = _minimiser_lp(-A.T)  # minimising max_i (−Ay)_i is maximising min_i (Ay)_i
    result = GameValue(timings={"lp": time.perf_counter() - t0})
    result.iterations = int(getattr(row, "nit", 0) or 0) + int(getattr(col, "nit", 0) or 0)
    if row.status != 0 or col.status != 0:
        result.status = "lp_failed"
        result.message = (f"the game LP did not solve (row player: {row.message}; "
                          f"column player: {col.message})")
        return result
    m, n = A.shape
    x = _to_simplex(row.x[:m])
    y = _to_simplex(col.x[:n])
    upper = float(np.max(np.asarray(A.T @ x).ravel())) * s
    lower = float(np.min(np.asarray(A @ y).ravel())) * s
    result.x, result.y = x, y
    result.upper, result.lower = upper, lower
    result.value = 0.5 * (upper + lower)
    result.residual = max(upper - lower, 0.0) / s
    if result.residual <= GAP_TOL:
        result.status = SOLVED
        result.message = (f"v(M) = {result.value:.6g}: x guarantees xᵀMy ≤ {upper:.6g} for every y, "
                          f"y guarantees xᵀMy ≥ {lower:.6g} for every x")
    else:
        result.status = "certificate_failed"
        result.message = (f"duality gap {result.residual:.3g}·max|M| exceeds {GAP_TOL:g}: "
                          f"v(M) is only known to lie in [{lower:.6g}, {upper:.6g}]")
    return result


__all__ = ["GameValue", "game_value", "GAP_TOL"]
