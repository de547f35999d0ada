"""``solve_lcp``: one entry point, solvers dispatched by name (as in qpsolvers).

Methods:
- ``lemke``: complementary pivoting, dense, any M (ray termination reported).
- ``enumerate``: every solution, n ≤ 18; proves infeasibility.
- ``pgs``: projected Gauss–Seidel/SOR, sparse symmetric M with positive diagonal.
- ``newton``: PETSc SNES VI, reduced-space (``vinewtonrsls``); ``snes_type="vinewtonssls"``
  for the semismooth variant.  Any M, sparse or distributed; local convergence.
- ``tao``: PETSc TAO bound-constrained QP (TRON), symmetric M, sparse or distributed.
- ``auto``: picks by size, sparsity and symmetry and falls back when a method fails;
  every attempt is recorded in ``result.attempts``.

The methods are a registry (:data:`SOLVERS`, filled by :func:`register`): the NumPy/SciPy
ones are registered here, ``newton`` and ``tao`` by :mod:`meicp.petsc.lcp`, which builds on
this package; it imports nothing of PETSc.
"""

from __future__ import annotations

import time

from ..core.comm import check_comm
from ..core.errors import ProblemError, SolverNotFound
from ..core.matrix import is_symmetric
from ..core.registry import SolverRegistry
from ..core.validation import as_int, as_real, check_tol, checked_keywords
from .enumeration import enumerate_lcp
from .lemke import lemke
from .pgs import pgs
from .problem import DEFAULT_TOL, LCPProblem, LCPResult

#: largest n for which auto uses dense pivoting on a dense matrix
DENSE_LIMIT = 3000
#: sparse matrices up to this size are treated as dense by auto
SMALL = 500

#: method name → ``solver(problem, *, tol, comm, **options) -> LCPResult``
SOLVERS = SolverRegistry(
    lemke=lemke,
    enumerate=enumerate_lcp,
    pgs=pgs,
)
#: ``@register(name)`` makes a function method ``name`` of :func:`solve_lcp` (how ``meicp.petsc``
#: adds the methods that need PETSc)
register = SOLVERS.register
available_methods = SOLVERS.available


def auto_order(problem: LCPProblem) -> list[str]:
    """The methods ``auto`` tries, in order, for this problem."""
    n = problem.n
    if problem.distributed:
        return ["tao", "newton"] if _symmetric(problem) else ["newton"]
    order = []
    if n <= DENSE_LIMIT and (not problem.sparse or n <= SMALL):
        order = ["lemke", "newton"]
    elif _symmetric(problem):
        order = ["tao", "newton", "pgs"]
    else:
        order = ["newton"]
    if n <= DENSE_LIMIT and "lemke" not in order:
        order.append("lemke")
    if n <= 12:
        order.append("enumerate")
    return order


def _symmetric(problem: LCPProblem) -> bool:
    return is_symmetric(problem.M, 1e-12)


@checked_keywords(more=lambda: SOLVERS.keywords())
def solve_lcp(M, q, *, method: str = "auto", tol: float = DEFAULT_TOL, comm=None, **method_options) -> LCPResult:
    """Solve LCP(q, M): ``x ≥ 0``, ``w = Mx + q ≥ 0``, ``xᵀw = 0``.

    Parameters
    ----------
    M : ndarray, SciPy sparse matrix or PETSc Mat, shape (n, n)
        A PETSc Mat makes the call collective on its communicator, and only ``newton``,
        ``tao`` and ``auto`` apply.
    q : array_like of n numbers
        Text is refused, not parsed.
    method : str
        ``lemke`` (complementary pivoting, dense), ``enumerate`` (every solution, n ≤ ``max_n``: 18, at most 26),
        ``pgs`` (projected Gauss–Seidel / SOR, sparse symmetric M with positive diagonal),
        ``newton`` (PETSc SNES VI), ``tao`` (PETSc TAO, symmetric M), or ``auto`` (by size,
        sparsity and symmetry, falling back when a method fails; ``result.attempts``).
    tol : float
        Relative certificate tolerance in (0, 1e-2] (:mod:`meicp.lcp.problem`).
    comm : None, mpi4py or PETSc communicator
        Where ``newton`` and ``tao`` distribute a NumPy/SciPy M.  None: M's own
        communicator for a PETSc Mat, this process for NumPy/SciPy data.
    **method_options
        Handed to the method, each checked by name (a misspelt one is a TypeError naming
        the nearest): ``max_iter`` (every iterative method), ``pivot_tol`` (lemke),
        ``max_n`` (enumerate), ``omega``, ``x0``, ``check_every`` (pgs), ``options`` (PETSc
        options), ``snes_type`` (newton), ``tao_type`` (tao).

    Returns
    -------
    LCPResult
        ``x``, ``w``, ``status``, ``success`` (only with a passing certificate),
        ``method``, ``iterations``, ``residual``, ``attempts``.

    Raises
    ------
    ProblemError
        Bad input, naming the argument (non-square or non-numeric M, q of another length,
        tol outside (0, 1e-2], a non-integer ``max_iter``, a comm that is none of the above).
    SolverNotFound
        An unknown method name.
    """
    tol = check_tol(tol)
    check_comm(comm)
    if not isinstance(method, str):
        raise ProblemError(f"method must be a method name (a string), got {method!r}")
    kwargs = check_options(method_options)
    problem = LCPProblem.from_data(M, q)
    if method == "auto":
        return _solve_auto(problem, tol=tol, comm=comm, **kwargs)
    if method not in SOLVERS:
        raise SolverNotFound(method, available_methods())
    if problem.distributed and method not in ("newton", "tao"):
        raise ProblemError(f"method {method!r} needs M as NumPy/SciPy; a PETSc Mat takes newton or tao")
    t0 = time.perf_counter()
    result = SOLVERS[method](problem, tol=tol, comm=comm, **kwargs)
    result.timings["total"] = time.perf_counter() - t0
    return result


def check_options(kwargs: dict) -> dict:
    """The numeric method options checked (ProblemError naming the one that is wrong)."""
    out = dict(kwargs)
    if out.get("max_iter") is not None:
        out["max_iter"] = as_int(out["max_iter"], "max_iter", minimum=1)
    if out.get("max_n") is not None:  # enumerate: 2^n supports, 2^26 already take hours
        out["max_n"] = as_int(out["max_n"], "max_n", minimum=0, maximum=26)
    for name in ("omega", "pivot_tol"):
        if out.get(name) is not None:
            out[name] = as_real(out[name], name)
    return out


def _solve_auto(problem: LCPProblem, *, tol: float, comm=None, **kwargs) -> LCPResult:
    t0 = time.perf_counter()
    attempts, result = [], None
    for name in auto_order(problem):
        try:
            result = SOLVERS[name](problem, tol=tol, comm=comm, **kwargs)
        except ProblemError as exc:  # this method does not apply; the next may
            attempts.append((name, "not_applicable", str(exc)))
            continue
        attempts.append((name, result.status, result.message))
        if result.success or result.status == "infeasible":  # solved, or proved unsolvable
            break
    if result is None:
        result = LCPResult(method="auto", status="no_method",
                           message="no method applies: " + "; ".join(f"{a[0]}: {a[2]}" for a in attempts))
    result.attempts = attempts
    result.timings["total"] = time.perf_counter() - t0
    return result
