"""The LCP, its result and its certificate.

LCP(q, M): find ``x ≥ 0`` with ``w = Mx + q ≥ 0`` and ``xᵀw = 0`` (docs/design.md §2.1).

Certificate (relative, so that it means the same at any scale of the data, and row by row,
so that it means the same whatever the scale of each row): with ``sx = max|x|`` and the
row scales ``s_i = max(|q_i|, max_j |M_ij|·sx)``,

    residual = max( max(0, -min x) / sx,  max_i max(0, -w_i) / s_i,  max_i |x_i w_i| / (sx·s_i) )

(a row scaled by 1e-300 is held to the same relative standard as the others: with one
global scale ``max|M|·max|x|`` its violations would pass whatever they are).

It is recomputed from ``M`` and ``q`` by :func:`certify`, never taken from a solver's own
bookkeeping; a result is ``solved`` only if ``residual ≤ tol``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..core.matrix import (checked_matrix, is_petsc_mat, matrix_shape, matvec, max_abs_entry, row_max_abs,
                           to_dense)
from ..core.results import SOLVED, Result, brief, brief_text
from ..core.validation import as_vector

#: default relative certificate tolerance
DEFAULT_TOL = 1e-10


@dataclass(frozen=True)
class LCPProblem:
    """A validated LCP: ``M`` (ndarray or CSR), ``q`` (float64 vector)."""

    M: object
    q: np.ndarray

    @classmethod
    def from_data(cls, M, q) -> "LCPProblem":
        """Validate ``M`` (ndarray, SciPy sparse or PETSc Mat) and ``q`` (NumPy, full length)."""
        M = checked_matrix(M, "M")  # a PETSc Mat is checked in place (collective), not copied
        return cls(M, as_vector(q, matrix_shape(M)[0], "q"))

    @property
    def distributed(self) -> bool:
        """True for a PETSc Mat: products and scales are then collective."""
        return is_petsc_mat(self.M)

    def matvec(self, x: np.ndarray) -> np.ndarray:
        return matvec(self.M, x)

    @property
    def n(self) -> int:
        return self.q.shape[0]

    @property
    def sparse(self) -> bool:
        return sp.issparse(self.M)

    @cached_property
    def matrix_scale(self) -> float:
        return max_abs_entry(self.M)

    @cached_property
    def row_scales(self) -> np.ndarray:
        """``max_j |M_ij|`` per row (collective once for a PETSc Mat, then cached)."""
        return row_max_abs(self.M)

    def dense(self) -> np.ndarray:
        return to_dense(self.M)


@dataclass
class LCPResult(Result):
    """Result of :func:`meicp.solve_lcp`.

    x, w: the solution and ``w = Mx + q`` (recomputed); ``None`` when nothing was found.
    method: the method that produced this result (after ``auto`` and fallbacks).
    min_x, min_w, complementarity: the certificate's parts (``complementarity = |xᵀw|``).
    solutions: for ``enumerate``, every solution found (list of x); otherwise ``[x]`` or [].
    attempts: for ``auto``, the (method, status, message) of every method tried.
    """

    x: np.ndarray | None = None
    w: np.ndarray | None = None
    method: str = ""
    min_x: float = float("nan")
    min_w: float = float("nan")
    complementarity: float = float("nan")
    solutions: list = field(default_factory=list)
    attempts: list = field(default_factory=list)

    def __repr__(self) -> str:
        if self.success:
            return (f"LCPResult(solved by {self.method}: x={brief(self.x)}, residual {self.residual:.1e}, "
                    f"{self.iterations} iterations)")
        return f"LCPResult({self.status} ({self.method or 'no method'}): {brief_text(self.message)})"

    def summary(self) -> str:
        head = f"{self.method}: {self.status}"
        if self.x is not None:
            head += (f", residual {self.residual:.2e} (min x {self.min_x:.2e}, min w {self.min_w:.2e}, "
                     f"|xᵀw| {self.complementarity:.2e}), {self.iterations} iterations")
        return head + (f" — {self.message}" if self.message else "")


def relative_residual(problem: LCPProblem, x: np.ndarray) -> tuple[float, np.ndarray]:
    """The certificate residual of ``x`` and the recomputed ``w``."""
    # max() below would drop a NaN: a non-finite x or w never passes
    if not np.all(np.isfinite(x)):
        return float("inf"), np.full(problem.n, np.nan)
    w = problem.matvec(x) + problem.q
    if not np.all(np.isfinite(w)):
        return float("inf"), w
    sx = float(np.max(np.abs(x))) if x.size else 0.0
    sw = np.maximum(np.abs(problem.q), problem.row_scales * sx)
    sw = np.where(sw > 0, sw, 1.0)  # a zero scale means w_i = 0 exactly
    sx = sx if sx > 0 else 1.0
    with np.errstate(over="ignore"):  # (x/sx)·(w/sw): x·w itself overflows at x ≈ 1e200
        r = max(0.0, -float(np.min(x)) / sx, float(np.max(-w / sw)),
                float(np.max(np.abs(x / sx) * np.abs(w / sw))))
    return (r if np.isfinite(r) else float("inf")), w


def certify(problem: LCPProblem, result: LCPResult, x, tol: float = DEFAULT_TOL,
            failure_status: str = "certificate_failed") -> LCPResult:
    """Fill ``result`` with ``x``, its ``w`` and certificate; ``solved`` only if it passes.

    A solver calls this with its candidate; if the candidate fails, the status becomes
    ``failure_status`` and the message says by how much — the candidate is kept for
    inspection but the result is not a success.
    """
    x = np.asarray(x, dtype=np.float64)
    r, w = relative_residual(problem, x)
    result.x, result.w, result.residual = x, w, r
    result.min_x, result.min_w = float(np.min(x)), float(np.min(w))
    with np.errstate(over="ignore", invalid="ignore"):
        result.complementarity = abs(float(x @ w))
    if r <= tol:
        result.status = SOLVED
        result.solutions = result.solutions or [x]
    else:
        result.status = failure_status
        note = f"certificate residual {r:.2e} > tol {tol:.0e}"
        result.message = f"{result.message}; {note}" if result.message else note
    return result


def refine_on_support(problem: LCPProblem, x: np.ndarray) -> np.ndarray | None:
    """Re-solve ``M_SS x_S = -q_S`` on the support of ``x`` (pivoting and iterative methods
    identify the support correctly long before their iterate is accurate).  The support is
    where ``x_i > w_i``.  ``None`` if the block is singular or the re-solve leaves the orthant."""
    if problem.distributed:
        return None  # the iterative PETSc solvers are already at working accuracy
    S = np.flatnonzero(x > problem.matvec(x) + problem.q)
    if S.size == 0:
        return np.zeros_like(x)
    M = problem.M
    try:
        if problem.sparse:
            xs = spla.spsolve(M[S][:, S].tocsc(), -problem.q[S])
        else:
            xs = np.linalg.solve(M[np.ix_(S, S)], -problem.q[S])
    except (np.linalg.LinAlgError, RuntimeError):
        return None
    if not np.all(np.isfinite(xs)) or np.any(xs < 0):
        return None
    out = np.zeros_like(x)
    out[S] = xs
    return out


def best_of(problem: LCPProblem, *candidates) -> np.ndarray:
    """The candidate with the smallest certificate residual (``None`` entries skipped)."""
    scored = [(relative_residual(problem, x)[0], i, x) for i, x in enumerate(candidates) if x is not None]
    return min(scored, key=lambda t: (t[0], t[1]))[2]
