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



def decided_on_root(comm, decide, serve):
    """``decide(request)`` run on rank 0, where ``request(r)`` has every rank run ``serve(r)``
    (collective work: a factorisation the dense decision asks for) and returns rank 0's result;
    the other ranks serve rank 0's requests until it is done.  ``r`` must not be None (it ends
    the service).  Returns ``decide``'s result on every rank, an exception raised on rank 0
    raised on every rank (:func:`on_root`).  Collective."""
    if comm is None or comm.Get_size() == 1:
        return on_root(comm, lambda: decide(serve))

    def decide_on_root():
        def served(request):
            comm.bcast(request, root=0)
            return serve(request)
        try:
            return decide(served)
        finally:
            comm.bcast(None, root=0)

    if comm.Get_rank() != 0:
        while (request := comm.bcast(None, root=0)) is not None:
            try:
                serve(request)
            except Exception:  # noqa: BLE001 — rank 0 meets it too and raises it on every rank
                # (on_root); leaving the loop here would leave rank 0's broadcasts unmatched
                # and the next collective call out of step (a hang in a later call)
                continue
    return on_root(comm, decide_on_root)
