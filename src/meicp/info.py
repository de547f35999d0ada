"""``meicp info``: the versions and capabilities a user needs to trust or report an install."""

from __future__ import annotations

import platform
import sys

from . import __version__


def _petsc_external_packages(PETSc) -> dict:
    """Which solver packages this PETSc build has, asked of PETSc itself."""
    return {name: PETSc.Sys.hasExternalPackage(name.lower())
            for name in ("MUMPS", "SuperLU_dist", "SuperLU", "SuiteSparse", "hypre")}


def collect(comm=None) -> dict:
    """Gather the report as a dict (collective when ``comm`` has several ranks)."""
    import numpy
    import scipy

    from .petsc import import_petsc, import_slepc

    PETSc = import_petsc()
    SLEPc = import_slepc()
    from mpi4py import MPI

    comm = comm or MPI.COMM_WORLD
    report = {
        "meicp": __version__,
        "python": f"{platform.python_version()} ({sys.executable})",
        "numpy": numpy.__version__,
        "scipy": scipy.__version__,
        "petsc": "%d.%d.%d" % PETSc.Sys.getVersion(),
        "slepc": "%d.%d.%d" % SLEPc.Sys.getVersion(),
        "petsc scalar": PETSc.ScalarType.__name__,
        "petsc int bytes": PETSc.IntType().itemsize,
        "mpi": MPI.Get_library_version().replace("\x00", "").splitlines()[0].strip(),
        "mpi4py": __import__("mpi4py").__version__,
        "ranks": comm.Get_size(),
    }
    report.update({f"petsc has {k}": v for k, v in _petsc_external_packages(PETSc).items()})
    try:
        import h5py
        report["h5py"] = f"{h5py.__version__} (HDF5 {h5py.version.hdf5_version}, MPI {'yes' if h5py.get_config().mpi else 'no'})"
    except ImportError as exc:  # reported, not fatal: only the I/O needs it
        report["h5py"] = f"missing ({exc})"
    return report


def format_report(report: dict) -> str:
    width = max(map(len, report))
    return "\n".join(f"{k:<{width}}  {v}" for k, v in report.items())
