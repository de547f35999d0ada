"""``solve_eicp``: one entry point for the EiCP and MEiCP, methods dispatched by name.

- ``enumerate``: every solution (support enumeration, |J| ≤ 24), split across ranks.
- ``active-set``: one certified solution of a large sparse or distributed pencil (SLEPc).
- ``rayleigh``: symmetric A, B with B SPD — stationary points of the Rayleigh quotient.
- ``semismooth``: the MEiCP as a complementarity system in (x, λ) on PETSc SNES VI.
- ``auto``: ``enumerate`` when |J| ≤ 16 and the pencil is small, ``active-set`` otherwise.
"""

from __future__ import annotations

import logging
import time

from ..core.errors import ProblemError, SolverNotFound
from .active_set import active_set
from .enumeration import enumerate_eicp
from .problem import DEFAULT_TOL, EiCPProblem, EiCPResult, check_options

#: auto enumerates up to this |J| (2^16 supports: seconds) when the pencil is this small
AUTO_ENUMERATE_J = 16
AUTO_ENUMERATE_N = 400
#: above this certificate tolerance a certified λ can be far from any solution: at tol
#: 1e-2 the speed-against-accuracy benchmark found certified λ off by up to 37 %
LOOSE_TOL = 1e-6

log = logging.getLogger("meicp")


def _lazy(module: str, name: str):
    def run(problem, **kwargs):
        import importlib

        return getattr(importlib.import_module(f"{__package__}.{module}"), name)(problem, **kwargs)
    run.__name__ = name
    return run


SOLVERS = {
    "enumerate": enumerate_eicp,
    "active-set": active_set,
    "rayleigh": _lazy("rayleigh", "rayleigh"),
    "semismooth": _lazy("semismooth", "semismooth"),
}


def available_methods() -> list[str]:
    return sorted(SOLVERS) + ["auto"]


def solve_eicp(A, B, *, J=None, method: str = "auto", all_solutions: bool = False, lam_min=None,
               tol: float = DEFAULT_TOL, comm=None, **kwargs) -> EiCPResult:
    """Solve the (M)EiCP ``w = (λB − A)x, x_J ≥ 0, w_J ≥ 0, x_Jᵀw_J = 0, w_F = 0``.

    A, B: NumPy, SciPy sparse, or PETSc Mat (collective on its communicator).  J: the
    complementarity indices (default all: the EiCP).  all_solutions: enumerate every
    solution (small |J| only).  lam_min: only solutions with λ ≥ lam_min.  tol: relative
    certificate tolerance.  comm: split the enumeration across its ranks.  Other keywords
    go to the method (``target``, ``nev``, ``max_iter``, ``options``...).  Every returned
    solution passed its certificate; see :class:`EiCPResult` for the statuses.
    """
    check_options(tol=tol, lam_min=lam_min, **kwargs)
    if not 0.0 < tol < 1.0:
        raise ProblemError(f"tol must lie in (0, 1), got {tol!r}")
    if tol > LOOSE_TOL:
        log.warning("solve_eicp: tol = %.1e is looser than %.0e; a certificate this loose does not "
                    "pin λ (certified λ up to 37 %% off were measured at 1e-2)", tol, LOOSE_TOL)
    problem = EiCPProblem.from_data(A, B, J)
    if all_solutions and method == "auto":
        method = "enumerate"
    if method == "auto":
        small = problem.J.size <= AUTO_ENUMERATE_J and problem.n <= AUTO_ENUMERATE_N and not problem.distributed
        method = "enumerate" if small else "active-set"
    if method not in SOLVERS:
        raise SolverNotFound(method, available_methods())
    if problem.distributed and comm is None:
        comm = problem.A.getComm()
    if comm is not None and hasattr(comm, "tompi4py"):
        comm = comm.tompi4py()
    t0 = time.perf_counter()
    kw = dict(kwargs, tol=tol, lam_min=lam_min)
    if method in ("enumerate", "active-set"):
        kw["comm"] = comm
    result = SOLVERS[method](problem, **kw)
    result.timings["total"] = time.perf_counter() - t0
    return result
