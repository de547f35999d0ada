"""``solve_eicp``: one entry point for the EiCP and MEiCP, methods dispatched by name.

- ``enumerate``: every solution (support enumeration, |J| ≤ 24), split across ranks.
- ``active-set``: one certified solution of a large sparse or distributed pencil (SLEPc).
- ``rayleigh``: symmetric A, B with B SPD — stationary points of the Rayleigh quotient.
- ``semismooth``: the MEiCP as a complementarity system in (x, λ) on PETSc SNES VI.
- ``auto``: a portfolio (:func:`auto_order`): ``enumerate`` when small; ``rayleigh`` when
  A and B are symmetric (B SPD) and serial; ``active-set``; ``semismooth`` from the best
  candidate the others reached.  It stops at the first certified answer (or the
  enumeration's proof that there is none) and records every method it ran, with the
  status and message that ended it, in ``result.attempts``.

The methods are a registry (:data:`SOLVERS`, filled by :func:`register`, as in qpsolvers):
the NumPy/SciPy ones are registered here, ``active-set`` and ``semismooth`` by the modules
of ``meicp.petsc`` that implement them (``eicp_active_set.py``, ``eicp_semismooth.py``):
they build on this package, which imports nothing of PETSc.
"""

from __future__ import annotations

import logging
import time

import numpy as np

from ..core import limits
from ..core.comm import check_comm, mpi_comm
from ..core.errors import PetscOptionError, ProblemError, SolverNotFound
from ..core.matrix import is_symmetric, matrix_comm
from ..core.registry import SolverRegistry
from ..core.validation import as_flag, checked_keywords
from .budget import check_enumeration_work
from .enumeration import enumerate_eicp
from .problem import DEFAULT_TOL, EiCPProblem, EiCPResult, check_options
from .rayleigh import rayleigh

#: above this certificate tolerance a certified λ can be far from any solution: at tol
#: 1e-2 the speed-against-accuracy benchmark found certified λ off by up to 37 %
LOOSE_TOL = 1e-6

log = logging.getLogger("meicp")


#: method name → ``solver(problem, **options) -> EiCPResult``
SOLVERS = SolverRegistry(
    enumerate=enumerate_eicp,
    rayleigh=rayleigh,
)
#: ``@register(name)`` makes a function method ``name`` of :func:`solve_eicp` (how ``meicp.petsc``
#: adds the methods that need PETSc)
register = SOLVERS.register
available_methods = SOLVERS.available


@checked_keywords(more=lambda: SOLVERS.keywords())
def solve_eicp(A, B, *, J=None, method: str = "auto", all_solutions: bool = False, lam_min=None,
               tol: float = DEFAULT_TOL, comm=None, **method_options) -> EiCPResult:
    """Solve the (M)EiCP ``w = (λB − A)x, x_J ≥ 0, w_J ≥ 0, x_Jᵀw_J = 0, w_F = 0``.

    Parameters
    ----------
    A, B : ndarray, SciPy sparse matrix or PETSc Mat, shape (n, n)
        PETSc Mats make the call collective on their communicator.
    J : array_like of int, or None
        The complementarity indices (a boolean mask of length n too); None: all, the EiCP.
    method : str
        ``enumerate`` (every solution, support by support), ``active-set`` (one certified
        solution, SLEPc, large sparse or distributed pencils), ``rayleigh`` (symmetric A, B
        with B SPD), ``semismooth`` (PETSc SNES VI), or ``auto``: the portfolio of
        :func:`auto_order`, which records each method's outcome in ``result.attempts``
        (``result.method`` names the one that answered).
    all_solutions : bool
        Enumerate every solution (small |J| only); with ``auto`` it means ``enumerate``.
    lam_min : float or None
        Only solutions with λ ≥ lam_min (finite).
    tol : float
        Relative certificate tolerance in (0, 1e-2]; looser than 1e-6 is warned about.
    comm : None, mpi4py or PETSc communicator
        Splits the enumeration across its ranks (and carries the active-set search).
        None: the matrices' own communicator for PETSc Mats, this process for NumPy/SciPy.
    **method_options
        Handed to the method, each checked by name (a misspelt one is a TypeError naming
        the nearest): ``lam_max``, ``max_j`` (enumerate: raises its limit of pairs, and
        accepts the cost: without it an enumeration past ``limits.ENUMERATE_MAX_FLOPS``,
        about an hour, is refused before any work); ``target``, ``nev``, ``max_iter``,
        ``give_up_after``, ``converging_after``, ``support0``, ``options`` (PETSc options), ``prefix``, ``follow``
        (active-set); ``starts``, ``n_starts``, ``seed``, ``sense``, ``spg_tol``,
        ``memory`` (rayleigh); ``x0``, ``lam0``, ``snes_type`` (semismooth).  ``auto``
        hands them to every method it runs.

    Returns
    -------
    EiCPResult
        ``solutions`` (each ``lam``, ``x``, ``w``, ``support``, ``residual``: every one
        passed its certificate), ``status`` (``solved``, ``no_solution`` when proved,
        else a failure), ``method``, ``candidates``, ``coverage``, ``attempts``.

    Raises
    ------
    ProblemError
        Bad input, naming the argument (shapes, NaN, complex or text data, J out of range,
        tol, a NaN λ bound, a comm that is none of the above).
    SolverNotFound
        An unknown method name.
    """
    kwargs = method_options
    check_comm(comm)
    as_flag(all_solutions, "all_solutions")
    if not isinstance(method, str):
        raise ProblemError(f"method must be a method name (a string), got {method!r}")
    check_options(tol=tol, lam_min=lam_min, **kwargs)
    if not 0.0 < tol < 1.0:
        raise ProblemError(f"tol must lie in (0, 1), got {tol!r}")
    if tol > LOOSE_TOL:
        log.warning("solve_eicp: tol = %.1e is looser than %.0e; a certificate this loose does not "
                    "pin λ (certified λ up to 37 %% off were measured at 1e-2)", tol, LOOSE_TOL)
    problem = EiCPProblem.from_data(A, B, J)
    if all_solutions and method == "auto":
        method = "enumerate"
    if method != "auto" and method not in SOLVERS:
        raise SolverNotFound(method, available_methods())
    if method == "enumerate" and "max_j" not in kwargs:
        # before any work: by name (or all_solutions) it may not start a days-long run; an
        # explicit max_j is the caller's own bound and accepts the cost
        check_enumeration_work(int(problem.J.size), int(problem.n),
                               f"solve_eicp(..., max_j={max(int(problem.J.size), 1)}) from Python")
    comm = matrix_comm(problem.A) if comm is None else mpi_comm(comm)
    t0 = time.perf_counter()
    kw = dict(kwargs, tol=tol, lam_min=lam_min, comm=comm)
    result = _solve_auto(problem, kw) if method == "auto" else _run(method, problem, kw)
    result.timings["total"] = time.perf_counter() - t0
    return result


def _run(method: str, problem: EiCPProblem, kw: dict) -> EiCPResult:
    if method not in ("enumerate", "active-set"):  # serial methods: no communicator
        kw = {k: v for k, v in kw.items() if k != "comm"}
    return SOLVERS[method](problem, **kw)


def auto_order(problem: EiCPProblem) -> list[str]:
    """The methods ``auto`` tries, in order, for this problem.

    ``enumerate`` when |J| ≤ limits.AUTO_ENUMERATE_J and n ≤ limits.AUTO_ENUMERATE_N (its answer, solutions
    or a proof that there are none, is final); ``rayleigh`` when the pencil is serial,
    n ≤ limits.AUTO_RAYLEIGH_N and A, B are symmetric (it checks B SPD itself: a ProblemError is
    recorded as ``not_applicable``); ``active-set``; ``semismooth`` unless the pencil is
    distributed over several ranks (it is serial).
    """
    order = []
    if problem.J.size <= limits.AUTO_ENUMERATE_J and problem.n <= limits.AUTO_ENUMERATE_N and not problem.distributed:
        order.append("enumerate")
    serial = matrix_comm(problem.A) is None
    if serial and problem.n <= limits.AUTO_RAYLEIGH_N and _symmetric_pair(problem):
        order.append("rayleigh")
    order.append("active-set")
    if serial:
        order.append("semismooth")
    return order


def _symmetric_pair(problem: EiCPProblem) -> bool:
    return is_symmetric(problem.A, 1e-12) and is_symmetric(problem.B, 1e-12)


def _solve_auto(problem: EiCPProblem, kw: dict) -> EiCPResult:
    """Run :func:`auto_order` until a method certifies a solution or the enumeration proves
    there is none; the result is that method's, with ``attempts`` = every method run as
    ``(method, status, message)``.  When none succeeds, the last result is returned with
    every attempt's candidates, best residual first."""
    attempts, candidates, result = [], [], None
    for name in auto_order(problem):
        run_kw = dict(kw)
        if name == "semismooth" and "x0" not in kw:
            run_kw.update(_best_start(problem, candidates, kw.get("lam_min")))
        try:
            result = _run(name, problem, run_kw)
        except PetscOptionError:  # a value the user gave PETSc: bad input, whichever method reads it
            raise
        except ProblemError as exc:  # this method does not apply here; the next may
            attempts.append((name, "not_applicable", str(exc)))
            continue
        attempts.append((name, result.status, result.message))
        if result.success or result.status == "no_solution":  # solved, or proved unsolvable
            break
        candidates.extend(result.candidates)
    else:
        if result is None:
            result = EiCPResult(method="auto", status="no_method",
                                message="no method applies: " + "; ".join(f"{a[0]}: {a[2]}" for a in attempts))
        result.candidates = sorted(candidates, key=lambda c: c.residual)
    result.attempts = attempts
    return result


def _best_start(problem: EiCPProblem, candidates: list, lam_min) -> dict:
    """Semismooth's start: the candidate with the smallest certificate residual among those
    it can start from (λ in the window, a positive entry on J); none: its default start."""
    usable = [c for c in candidates
              if np.all(np.isfinite(c.x)) and (lam_min is None or c.lam >= lam_min)
              and (problem.J.size == 0 or np.maximum(c.x[problem.J], 0.0).sum() > 0)]
    if not usable:
        return {}
    best = min(usable, key=lambda c: c.residual)
    return {"x0": best.x, "lam0": best.lam}
