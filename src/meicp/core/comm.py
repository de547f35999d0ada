"""Communicators: the one place where a caller's ``comm`` is made canonical.

Every collective function of meicp takes ``comm`` as ``None`` (this process alone), an
mpi4py communicator or a PETSc one.  :func:`mpi_comm` turns any of them into the one form
the rest of the code tests and passes on: an mpi4py communicator when it spans several
ranks, else ``None`` (serial: nothing to distribute, gather or broadcast).  Plain mpi4py
and the operating system only; the PETSc form objects are created on is
:func:`meicp.petsc.comm.to_petsc_comm`.
"""

from __future__ import annotations

from .machine import available_memory


def mpi_comm(comm):
    """The mpi4py communicator of ``comm`` (None, mpi4py or PETSc) when it has several
    ranks, else None."""
    if comm is None:
        return None
    if hasattr(comm, "tompi4py"):  # a PETSc communicator, recognised without importing PETSc
        comm = comm.tompi4py()
    return comm if comm.Get_size() > 1 else None


def comm_size(comm) -> int:
    """Ranks of ``comm`` (None, mpi4py or PETSc); 1 for None."""
    mcomm = mpi_comm(comm)
    return 1 if mcomm is None else mcomm.Get_size()


def available_memory_on(comm, need: int | None = None) -> tuple[int | None, str]:
    """``(bytes, where)``: the memory the ranks of ``comm`` can allocate together, the
    available memory of each host counted once (None when a host does not say), and a
    phrase naming the hosts for messages.  With ``need`` (bytes): when less is available,
    every rank hands its free heap back (:func:`~meicp.core.machine.release_free_heap`) and
    it is measured again.  Collective."""
    mcomm = mpi_comm(comm)

    def measure(reclaim):
        if mcomm is None:
            return available_memory(reclaim), 1
        from mpi4py import MPI

        hosts = dict(mcomm.allgather((MPI.Get_processor_name(), available_memory(reclaim))))
        return None if any(v is None for v in hosts.values()) else sum(hosts.values()), len(hosts)

    memory, count = measure(False)
    if need is not None and memory is not None and memory < need:  # the same decision on every rank
        memory, count = measure(True)
    if memory is None:
        return None, "this machine" if mcomm is None else f"{count} host(s)"
    return memory, "this machine" if count == 1 else f"the {count} hosts together"
