"""The (mixed) eigenvalue complementarity problem, its solutions and their certificates.

Convention (docs/design.md §4.1, seed 000 (2)-(3)): find λ ∈ ℝ and x ≠ 0 with

    w = (λB − A)x,   x_J ≥ 0,  w_J ≥ 0,  x_Jᵀw_J = 0,   w_F = 0   (F = complement of J).

The EiCP is J = all.  A solution is reported with ``‖x‖₂ = 1`` and the sign that makes
``x_J ≥ 0`` (with ``eᵀx_J > 0`` when ``x_J ≠ 0``; when ``x_J = 0`` the sign is the one that
makes ``w_J ≥ 0``, and if both do, the largest entry of x in magnitude is positive).  ``support`` = indices j ∈ J with ``x_j > 0``.

Certificate (:func:`certify_pair`), row by row: each row i of ``w`` (recomputed from A and
B, with ``‖x‖₂ = 1``) is measured against its own scale ``s_i = max_j|A_ij| + |λ|·max_j|B_ij|``,

    residual = max( max_{i ∈ F ∪ S} |w_i| / s_i,  max(0, −min x_J),  max_{j ∈ J} max(0, −w_j) / s_j,
                    max_{j ∈ J} |x_j w_j| / s_j )

(``w`` on the free set and on the support must vanish: that is the eigen-residual).  The
pair is then an exact solution of a problem whose every row of A and B is perturbed by at
most ``residual`` relative to that row's largest entry: the certificate means the same at
any scale of the data and of each row.  One global scale ``max|A| + |λ|·max|B|`` does not:
with one layer's density 1e-16 the rows of that layer were not checked at all, and seven
spurious "modes" passed.  A pair whose residual exceeds ``tol`` is never reported as a
solution.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from ..core import limits
from ..core.errors import ProblemError
from ..core.matrix import is_petsc_mat, matrix_shape, matvec, max_abs_entry, row_max_abs, to_dense
from ..core.results import Result, brief, brief_text
from ..core.validation import as_index_set, as_int, as_matrix, as_real, check_tol

#: default relative certificate tolerance
DEFAULT_TOL = 1e-10
#: x_j above this (relative to ‖x‖∞) counts as in the support
SUPPORT_TOL = 1e-9
#: rounding allowance of a λ lower bound, in units of eps·(|lam_min| + max|A|/max|B|)
LAM_ROUNDING = 1e3


def lam_floor(lam_min: float, scales: tuple[float, float]) -> float:
    """The smallest λ that counts as ``λ ≥ lam_min``: ``lam_min`` less rounding only.  An
    exact λ = lam_min (e.g. σ = 0 for a block free to slide as a whole) may be computed a few
    ulps below it and must not be lost; a λ below by more (σ = −5e-11 just below μ_c) is no
    solution in the window — the certificate tolerance is not a λ tolerance."""
    if not np.isfinite(lam_min):
        return lam_min
    a, b = scales
    return lam_min - LAM_ROUNDING * np.finfo(float).eps * (abs(lam_min) + (a / b if b > 0 else a))


@dataclass(frozen=True)
class EiCPProblem:
    """Validated data: ``A``, ``B`` (ndarray or CSR, or PETSc Mat), ``J`` sorted indices."""

    A: object
    B: object
    J: np.ndarray

    @classmethod
    def from_data(cls, A, B, J=None) -> "EiCPProblem":
        if is_petsc_mat(A) or is_petsc_mat(B):
            if not (is_petsc_mat(A) and is_petsc_mat(B)):
                raise ProblemError("A and B must both be PETSc Mats or both NumPy/SciPy")
            n = matrix_shape(A)[0]
            if matrix_shape(A) != (n, n) or matrix_shape(B) != (n, n):
                raise ProblemError(f"A and B must be square of one size, got {matrix_shape(A)} and "
                                   f"{matrix_shape(B)}")
            return cls(A, B, as_index_set(J, n, "J"))
        A = as_matrix(A, "A")
        B = as_matrix(B, "B")
        if A.shape != B.shape:
            raise ProblemError(f"A and B must have the same shape, got {A.shape} and {B.shape}")
        if max_abs_entry(B) == 0:
            raise ProblemError("B is zero: λ does not enter (λB − A)x = w, there is no eigenvalue problem")
        return cls(A, B, as_index_set(J, A.shape[0], "J"))

    @property
    def n(self) -> int:
        return matrix_shape(self.A)[0]

    @property
    def distributed(self) -> bool:
        return is_petsc_mat(self.A)

    @property
    def F(self) -> np.ndarray:
        """The free indices (complement of J)."""
        mask = np.ones(self.n, dtype=bool)
        mask[self.J] = False
        return np.flatnonzero(mask)

    def scales(self) -> tuple[float, float]:
        """``(max|A|, max|B|)``."""
        return max_abs_entry(self.A), max_abs_entry(self.B)

    @cached_property
    def row_scales(self) -> tuple[np.ndarray, np.ndarray]:
        """``(max_j|A_ij|, max_j|B_ij|)`` per row i (collective once for PETSc Mats, then cached)."""
        return row_max_abs(self.A), row_max_abs(self.B)

    def dense(self) -> tuple[np.ndarray, np.ndarray]:
        return to_dense(self.A), to_dense(self.B)

    def residual_vector(self, lam: float, x: np.ndarray) -> np.ndarray:
        """``w = (λB − A)x`` (gathered on every rank when distributed)."""
        return lam * matvec(self.B, x) - matvec(self.A, x)


@dataclass
class EiCPSolution:
    """One certified solution: λ, x (‖x‖₂ = 1), w = (λB − A)x, support ⊆ J, residual."""

    lam: float
    x: np.ndarray
    w: np.ndarray
    support: np.ndarray
    residual: float

    @property
    def sigma(self) -> float:  # the instability problem's name for λ (σ = growth rate²)
        return self.lam

    def __repr__(self) -> str:
        return f"EiCPSolution(λ={self.lam:.10g}, support {brief(self.support)}, residual {self.residual:.1e})"


@dataclass
class EiCPResult(Result):
    """Result of :func:`meicp.solve_eicp`.

    solutions: certified :class:`EiCPSolution` s, largest λ first.  status ``solved`` when at
    least one was found; ``no_solution`` when the method proves there is none (enumeration)
    in the requested λ window; other statuses are failures (``max_iterations``,
    ``cycling``, ``not_converged``...), with what was reached in ``candidates``.
    method: the method that produced the result; coverage: what was searched (supports
    visited, eigen-solves), the evidence behind a ``no_solution``.
    attempts: for ``auto``, the (method, status, message) of every method run, in order.
    """

    solutions: list = field(default_factory=list)
    method: str = ""
    candidates: list = field(default_factory=list)
    coverage: dict = field(default_factory=dict)
    attempts: list = field(default_factory=list)

    @property
    def lam(self) -> float | None:
        return self.solutions[0].lam if self.solutions else None

    def __repr__(self) -> str:
        n = len(self.solutions)
        if n:
            lams = brief([s.lam for s in self.solutions], 4)
            return (f"EiCPResult({self.status} by {self.method}: {n} solution{'s' if n != 1 else ''}, λ={lams}, "
                    f"max residual {max(s.residual for s in self.solutions):.1e})")
        return f"EiCPResult({self.status} ({self.method or 'no method'}): {brief_text(self.message)})"

    def summary(self) -> str:
        head = f"{self.method}: {self.status}, {len(self.solutions)} solution(s)"
        if self.solutions:
            lams = ", ".join(f"{s.lam:.10g}" for s in self.solutions[:6])
            head += f" λ = {lams}{' ...' if len(self.solutions) > 6 else ''}; max residual " \
                    f"{max(s.residual for s in self.solutions):.2e}"
        return head + (f" — {self.message}" if self.message else "")


def certificate_parts(problem: EiCPProblem, lams: np.ndarray, X: np.ndarray):
    """Normalise the rows of X (m × n), recompute ``W = (λB − A)X`` and the certificate's
    parts, each row-wise relative (module docstring).

    Returns ``(X, W, in_support, parts)`` with ``in_support`` an (m × |J|) mask and
    ``parts`` a dict of length-m arrays: ``eigen`` (w on F ∪ S), ``sign`` (−min x_J),
    ``dual`` (−min w_J / s_J), ``complementarity``.  The sign convention is the module
    docstring's; one vectorised implementation serves single pairs and the enumeration's
    stacks.
    """
    J = problem.J
    lams = np.asarray(lams, dtype=np.float64)
    X = np.array(X, dtype=np.float64, ndmin=2)
    with np.errstate(invalid="ignore", divide="ignore"):
        X /= np.linalg.norm(X, axis=1, keepdims=True)
    xmax = np.abs(X).max(axis=1)
    sJ = X[:, J].sum(axis=1) if J.size else np.zeros(len(X))
    biggest = X[np.arange(len(X)), np.argmax(np.abs(X), axis=1)]
    flip = np.where(np.abs(sJ) > SUPPORT_TOL * xmax, sJ < 0, biggest < 0)
    X[flip] *= -1
    with np.errstate(over="ignore", invalid="ignore"):
        if problem.distributed:
            W = np.array([problem.residual_vector(l, x) for l, x in zip(lams, X)])
        else:
            W = lams[:, None] * np.asarray(problem.B @ X.T).T - np.asarray(problem.A @ X.T).T
    in_support = X[:, J] > SUPPORT_TOL * xmax[:, None]
    if J.size:
        # x_J = 0 leaves the sign free: it is the one that makes w_J ≥ 0
        empty = ~in_support.any(axis=1)
        refl = empty & (W[:, J].min(axis=1) < -W[:, J].max(axis=1))
        X[refl] *= -1
        W[refl] *= -1
    a, b = problem.row_scales
    with np.errstate(over="ignore", invalid="ignore"):
        S = a[None, :] + np.abs(lams)[:, None] * b[None, :]
        S = np.where(S > 0, S, 1.0)  # an all-zero row of A and B has w_i = 0 exactly
        R = W / S
    must_vanish = np.ones(X.shape, dtype=bool)
    must_vanish[:, J] = in_support
    zero = np.zeros(len(X))
    parts = {"eigen": np.where(must_vanish, np.abs(R), 0.0).max(axis=1), "sign": zero, "dual": zero,
             "complementarity": zero}
    if J.size:
        xJ, RJ = X[:, J], R[:, J]
        parts.update(sign=np.maximum(0.0, -xJ.min(axis=1)), dual=np.maximum(0.0, -RJ.min(axis=1)),
                     complementarity=np.abs(xJ * RJ).max(axis=1))
    for key, value in parts.items():  # a NaN anywhere (overflow) never passes
        parts[key] = np.where(np.isnan(value) | ~np.isfinite(lams), np.inf, value)
    return X, W, in_support, parts


def certify_batch(problem: EiCPProblem, lams: np.ndarray, X: np.ndarray,
                  scales: tuple[float, float] | None = None):
    """:func:`certificate_parts` with the parts combined: ``(X, W, in_support, residuals)``.
    ``scales`` is accepted for callers of the former global certificate and not used."""
    X, W, in_support, parts = certificate_parts(problem, lams, X)
    return X, W, in_support, np.maximum.reduce(list(parts.values()))


def certify_pair(problem: EiCPProblem, lam: float, x: np.ndarray,
                 scales: tuple[float, float] | None = None) -> EiCPSolution:
    """Normalise x, recompute w and the certificate residual (see module docstring)."""
    X, W, in_support, res = certify_batch(problem, np.array([lam]), np.asarray(x)[None, :], scales)
    return EiCPSolution(float(lam), X[0], W[0], problem.J[in_support[0]], float(res[0]))


def check_options(*, tol, lam_min=None, **kwargs) -> None:
    """The numeric arguments of :func:`~meicp.eicp.solve.solve_eicp` and its methods:
    ProblemError naming the one that is wrong (tol outside (0, 1e-2], a NaN or infinite λ bound
    or target, a non-integer count).  ``lam_min = nan`` used to turn every answer into
    "no solution"."""
    check_tol(tol)
    for name in ("lam_min", "lam_max", "target", "lam0"):
        value = lam_min if name == "lam_min" else kwargs.get(name)
        if value is not None:
            as_real(value, name)
    if lam_min is not None and kwargs.get("lam_max") is not None and kwargs["lam_max"] < lam_min:
        raise ProblemError(f"lam_max = {kwargs['lam_max']!r} is below lam_min = {lam_min!r}")
    for name, minimum, maximum in (("nev", 1, None), ("max_iter", 1, None), ("give_up_after", 1, None),
                                   ("converging_after", 1, None),
                                   ("max_j", 0, limits.MAX_ENUMERATED),
                                   ("n_starts", 1, None), ("memory", 1, None)):
        if kwargs.get(name) is not None:
            as_int(kwargs[name], name, minimum=minimum, maximum=maximum)
    for name in ("spg_tol",):
        if kwargs.get(name) is not None:
            check_tol(kwargs[name], name)
