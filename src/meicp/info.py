"""``meicp info``: the versions and capabilities a user needs to trust or report an install."""

from __future__ import annotations

import platform
import sys

import numpy
import scipy

from ._version import __version__
from .petsc.versions import petsc_report


def collect(comm=None) -> dict:
    """Gather the report as a dict (collective when ``comm`` has several ranks)."""
    report = {
        "meicp": __version__,
        "python": f"{platform.python_version()} ({sys.executable})",
        "numpy": numpy.__version__,
        "scipy": scipy.__version__,
    }
    report.update(petsc_report(comm))
    try:
        import h5py
        report["h5py"] = f"{h5py.__version__} (HDF5 {h5py.version.hdf5_version}, MPI {'yes' if h5py.get_config().mpi else 'no'})"
    except ImportError as exc:  # reported, not fatal: only the I/O needs it
        report["h5py"] = f"missing ({exc})"
    return report


def format_report(report: dict) -> str:
    width = max(map(len, report))
    return "\n".join(f"{k:<{width}}  {v}" for k, v in report.items())
