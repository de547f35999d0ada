"""Communicators: the one place where a caller's ``comm`` is made canonical.

Every collective function of meicp takes ``comm`` as ``None``, an mpi4py communicator or
a PETSc one; anything else is a ProblemError naming ``comm`` (:func:`check_comm`).
:func:`mpi_comm` turns any of them into the one form the rest of the code tests and passes
on: an mpi4py communicator when it spans several ranks, else ``None`` (serial: nothing to
distribute, gather or broadcast).  Plain mpi4py and the operating system only; the PETSc
form objects are created on is :func:`meicp.petsc.comm.to_petsc_comm`.

What ``comm=None`` means (docs/design.md §10.2): inside the packages, this process alone.
The public functions that take a scene (``meicp.analyze``, ``meicp.critical_friction``)
read it as ``MPI.COMM_WORLD`` (:func:`world_if_none`), as petsc4py and DOLFINx do: under
``mpirun`` every rank calls them and they share the work; run without ``mpirun`` that is
one process, the same as serial.  Those that take matrices (``solve_lcp``, ``solve_eicp``)
read it as the matrices' own communicator, and ``meicp.assemble`` as serial SciPy.
"""

from __future__ import annotations

from .errors import ProblemError
from .machine import available_memory


def check_comm(comm, name: str = "comm"):
    """``comm`` itself when it is None, an mpi4py communicator or a PETSc one (recognised
    without importing PETSc); else a ProblemError naming ``name``."""
    if comm is None or hasattr(comm, "tompi4py") or (hasattr(comm, "Get_size") and hasattr(comm, "Get_rank")):
        return comm
    shown = repr(comm)
    shown = shown if len(shown) <= 80 else shown[:77] + "..."
    raise ProblemError(f"{name} must be None, an mpi4py communicator (e.g. MPI.COMM_WORLD) or a PETSc one, "
                       f"got {type(comm).__name__} {shown}")


def world_if_none(comm, name: str = "comm"):
    """``comm`` checked (:func:`check_comm`), None read as mpi4py's ``MPI.COMM_WORLD``:
    every process of an ``mpirun`` job, one process without it (then serial)."""
    if check_comm(comm, name) is not None:
        return comm
    from mpi4py import MPI

    return MPI.COMM_WORLD


def mpi_comm(comm):
    """The mpi4py communicator of ``comm`` (None, mpi4py or PETSc) when it has several
    ranks, else None.  Anything else: ProblemError naming ``comm``."""
    if check_comm(comm) is None:
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
