"""The divergence verdict of a small reduced problem, by enumerating every support; and of
a method asked for by name other than the window procedure.

An enumeration asked for by name is refused past ``limits.ENUMERATE_J`` pairs unless ``max_j``
raises the limit, or past ``limits.ENUMERATE_MAX_FLOPS`` of work (2^|J|·r³, about an hour) unless
``max_j`` is given (:func:`check_enumeration_size`).
"""

from __future__ import annotations

import logging

from ...core import limits
from ...core.errors import ProblemError
from ...core.validation import as_int
from ...eicp.budget import check_enumeration_work
from ...eicp.solve import solve_eicp
from .modes import certified_modes
from .verdict import DivergenceProof, DivergenceVerdict

log = logging.getLogger("meicp")


def enumeration_is_small(r: int, n_j: int) -> bool:
    """Whether 2^|J| dense eigen-solves of size r are within the enumeration budget
    (``analyze``'s ``auto`` choice, and ``critical_friction``'s bisection check)."""
    return r <= limits.ENUMERATE_N and n_j <= limits.ENUMERATE_J and 2.0 ** n_j * r ** 3 <= limits.ENUMERATE_FLOPS


def check_enumeration_size(n_j: int, r: int, options: dict) -> None:
    """ProblemError when an enumeration of 2^n_j supports of order up to r is past the
    limit: limits.ENUMERATE_J pairs, or the ``max_j`` keyword's (at most limits.MAX_ENUMERATED) when the
    caller raised it; and, unless ``max_j`` was given (the caller then accepts the cost),
    limits.ENUMERATE_MAX_FLOPS of work.  The error names the limit and the methods that decide
    past it."""
    given = options.get("max_j")
    limit = limits.ENUMERATE_J if given is None else as_int(given, "max_j", minimum=0, maximum=limits.MAX_ENUMERATED)
    if n_j <= limit:
        if given is None:  # the pair count is not the work (docs/benchmarks-notes.md, "enumeration by name")
            check_enumeration_work(n_j, r, f"analyze(..., max_j={max(n_j, 1)}) from Python")
        return
    name = (f"max_j = {limit}" if given is not None
            else f"the limit of {limit} pairs ({2 ** limit:,} supports, meicp.core.limits.ENUMERATE_J)")
    raise_it = (f", or raise the limit with analyze(..., max_j={n_j}) from Python" if n_j <= limits.MAX_ENUMERATED
                else f"; max_j cannot exceed {limits.MAX_ENUMERATED}")
    raise ProblemError(f"method 'enumerate' visits all 2^|J| supports: |J| = {n_j} complementarity pairs is "
                       f"{2 ** n_j:,} supports, past {name}; each pair more doubles the time; use method='auto' "
                       f"or method='active-set', which decide past it with proofs that scale{raise_it}")


def named_method_verdict(pen, comm, chosen: str, lam_min: float, tol: float, options) -> DivergenceVerdict:
    """The verdict of ``solve_eicp(method=chosen)`` on the whole pencil: the enumeration
    (a proof either way when it completes), or another method by name (modes, never a proof
    of stability).  Collective on ``comm``."""
    red = pen.maps
    if chosen == "enumerate":  # before any work: an enumeration by name may not start a days-long run
        check_enumeration_size(int(red.J.size), int(red.retained.size), options)
    eicp = solve_eicp(pen.A, pen.B, J=red.J, method=chosen, lam_min=0.0, tol=tol, comm=comm, **dict(options))
    got = certified_modes(eicp, pen, lam_min)
    cover = int(eicp.coverage.get("supports", 0))

    def verdict(modes, stable, evidence, test, statement):
        return DivergenceVerdict(modes, stable, evidence, eicp, DivergenceProof(test, statement, cover))

    if chosen == "enumerate":
        if got.found:
            return verdict(got.listed, False, f"enumeration of all {cover} supports: {len(got.found)} divergence "
                           f"mode(s) with σ ≥ 0{got.note}", chosen, "certified mode(s)")
        if eicp.status == "no_solution":
            text = f"enumeration of all {cover} supports: no solution with σ ≥ 0 (a proof)"
            return verdict([], True, text, chosen, text)
        text = (f"enumeration of all {cover} supports found no mode, but this is not a proof "
                f"({eicp.status}): {eicp.message}")
        return verdict([], None, text, "", text)
    if got.found:
        return verdict(got.listed, False, f"{chosen}: {len(got.found)} certified divergence mode(s){got.note}",
                       chosen, "certified mode(s)")
    text = (f"{chosen} found no mode with σ ≥ 0 ({eicp.status}); this is not a proof of stability: "
            f"method {chosen!r} (the [solver] table or the caller) runs no proof, method 'auto' does")
    log.warning("divergence undecided: method %r runs no proof of stability; method 'auto' does", chosen)
    return verdict([], None, text, "", text)
