"""Dense work done once, on rank 0, and its result given to every rank: the condensed
proofs' and the critical friction's |J|×|J| decisions (:mod:`.divergence.condensed`,
:mod:`.critical_friction`)."""
from __future__ import annotations

from ..core.threads import dense_phase


def on_root(comm, fn):
    """``fn()`` run on rank 0 and its result broadcast; an exception raised there is raised on
    every rank (no rank left waiting).  Serial: just ``fn()``.  ``fn`` is a dense phase: its
    BLAS threads are bounded (:mod:`meicp.core.threads`).  Collective."""
    if comm is None or comm.Get_size() == 1:
        with dense_phase():
            return fn()
    outcome = None
    if comm.Get_rank() == 0:
        try:
            with dense_phase():
                outcome = (True, fn())
        except Exception as exc:  # noqa: BLE001 — re-raised below, on every rank
            outcome = (False, exc)
    ok, value = comm.bcast(outcome, root=0)
    if not ok:
        raise value
    return value

