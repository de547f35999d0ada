"""Logging and printing that happen once, on rank 0.

The rank is read from the MPI launcher's environment (or mpi4py if it is already
imported), so plain NumPy modules can log without initialising MPI.
"""

from __future__ import annotations

import logging
import os
import sys


def world_rank() -> int:
    mpi = sys.modules.get("mpi4py.MPI")
    if mpi is not None and mpi.Is_initialized() and not mpi.Is_finalized():
        return mpi.COMM_WORLD.Get_rank()
    for var in ("OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK"):
        if var in os.environ:
            return int(os.environ[var])
    return 0


def rank0_print(*args, file=None, **kwargs) -> None:
    """``print`` on rank 0 only, flushed (mpirun interleaves buffered output)."""
    if world_rank() == 0:
        print(*args, file=file or sys.stdout, flush=True, **kwargs)


class _Rank0Filter(logging.Filter):
    def filter(self, record: logging.LogRecord) -> bool:
        return world_rank() == 0


def configure_logging(verbosity: int = 0) -> None:
    """Send ``meicp`` log records to stderr on rank 0: WARNING by default, INFO with -v, DEBUG with -vv."""
    logger = logging.getLogger("meicp")
    level = logging.WARNING if verbosity <= 0 else logging.INFO if verbosity == 1 else logging.DEBUG
    logger.setLevel(level)
    if not any(getattr(h, "_meicp", False) for h in logger.handlers):
        handler = logging.StreamHandler(sys.stderr)
        handler.setFormatter(logging.Formatter("meicp: %(message)s"))
        handler.addFilter(_Rank0Filter())
        handler._meicp = True
        logger.addHandler(handler)
