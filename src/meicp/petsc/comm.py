"""The communicator forms that need PETSc: the one PETSc objects are created on, and the
index range of this PETSc build.  The canonical ``comm`` (:func:`~meicp.core.comm.mpi_comm`)
and the memory of the ranks are plain mpi4py, in :mod:`meicp.core.comm`.
"""

from __future__ import annotations

import numpy as np

from ..core.comm import mpi_comm
from . import import_petsc


def to_petsc_comm(comm):
    """The PETSc communicator to create objects on: ``COMM_SELF`` when serial."""
    PETSc = import_petsc()
    mcomm = mpi_comm(comm)
    return PETSc.COMM_SELF if mcomm is None else PETSc.Comm(mcomm)


def index_max() -> int:
    """The largest index of this PETSc build (2³¹ − 1 with Debian's 32-bit ``PetscInt``)."""
    return int(np.iinfo(import_petsc().IntType).max)
