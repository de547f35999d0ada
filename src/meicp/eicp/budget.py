"""The work budget of an enumeration asked for by name.

An enumeration visits 2^|J| supports, each a dense eigen-solve of the reduced pencil of
order at most r = |F| + |J|: about 2^|J|·r³ flops.  A pair count alone does not bound that:
16 pairs on 2,000 retained DOFs are 65,536 eigen-solves of order 2,000 (days).  So the
work itself is checked before anything is solved, in ``analyze(method="enumerate")`` and in
``solve_eicp(method="enumerate")`` (``meicp solve`` / ``meicp eicp --method enumerate``).
``auto`` never reaches this: it enumerates only what it judges small itself.
"""

from __future__ import annotations

from ..core import limits
from ..core.errors import ProblemError



def enumeration_work(n_j: int, r: int) -> float:
    """2^|J|·r³: the flops of 2^|J| dense eigen-solves of order r (an upper estimate: a
    support of size k solves order |F| + k ≤ r)."""
    return 2.0 ** n_j * float(r) ** 3


def duration(t: float) -> str:
    """A rough duration for an estimate: seconds, minutes, hours or days."""
    for unit, size in (("days", 86400.0), ("h", 3600.0), ("min", 60.0)):
        if t >= size:
            return f"{t / size:.3g} {unit}"
    return f"{t:.2g} s"


def check_enumeration_work(n_j: int, r: int, override: str) -> None:
    """ProblemError before any work when 2^n_j eigen-solves of order r exceed
    limits.ENUMERATE_MAX_FLOPS; ``override`` names how the caller may accept the cost."""
    work = enumeration_work(n_j, r)
    if work <= limits.ENUMERATE_MAX_FLOPS:
        return
    raise ProblemError(
        f"method 'enumerate' solves 2^|J| dense eigen-problems of order up to r: |J| = {n_j}, r = {r} is about "
        f"{work:.1e} flops (2^|J|·r³, ~{duration(work * limits.SECONDS_PER_FLOP)} on one core), past the limit of "
        f"{limits.ENUMERATE_MAX_FLOPS:.0e} (~{duration(limits.ENUMERATE_MAX_FLOPS * limits.SECONDS_PER_FLOP)}, "
        f"meicp.core.limits.ENUMERATE_MAX_FLOPS); use method='auto' or method='active-set', which decide "
        f"without visiting every support, or accept the cost with {override}")
