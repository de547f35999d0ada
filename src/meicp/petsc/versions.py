"""The PETSc, SLEPc and MPI half of ``meicp info``: versions and solver packages, asked of
the libraries themselves."""

from __future__ import annotations

from ..core.comm import comm_size
from . import import_petsc, import_slepc

#: external solver packages worth reporting (PETSc's own names, case-insensitive)
EXTERNAL_PACKAGES = ("MUMPS", "SuperLU_dist", "SuperLU", "SuiteSparse", "hypre")


def petsc_report(comm=None) -> dict:
    """Versions of PETSc, SLEPc, MPI and mpi4py, PETSc's scalar and index types, which
    external packages this PETSc build has, and the ranks of ``comm`` (default: every rank
    of the job).  Initialises PETSc (collective on the job's ranks)."""
    PETSc = import_petsc()
    SLEPc = import_slepc()
    import mpi4py
    from mpi4py import MPI

    report = {
        "petsc": "%d.%d.%d" % PETSc.Sys.getVersion(),
        "slepc": "%d.%d.%d" % SLEPc.Sys.getVersion(),
        "petsc scalar": PETSc.ScalarType.__name__,
        "petsc int bytes": PETSc.IntType().itemsize,
        "mpi": MPI.Get_library_version().replace("\x00", "").splitlines()[0].strip(),
        "mpi4py": mpi4py.__version__,
        "ranks": comm_size(comm or MPI.COMM_WORLD),
    }
    report.update({f"petsc has {name}": PETSc.Sys.hasExternalPackage(name.lower()) for name in EXTERNAL_PACKAGES})
    return report
