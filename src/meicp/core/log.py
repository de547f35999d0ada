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
    """``print`` on rank 0 only, flushed (mpirun interleaves buffered output).  When the
    reader of stdout has gone away (``meicp solve s.toml | head -1``) the rest of the output
    is dropped quietly (:func:`stdout_closed`): the run itself goes on to its end."""
    if world_rank() == 0:
        out = file or sys.stdout
        try:
            print(*args, file=out, flush=True, **kwargs)
        except BrokenPipeError:
            if out is not sys.stdout:
                raise
            stdout_closed()


def stdout_closed() -> None:
    """Send what is still to be printed to stdout to /dev/null: its reader has closed the
    pipe.  Without this every later print, and Python's own flush at exit, would fail
    again ("Exception ignored ... BrokenPipeError", exit status 120)."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (AttributeError, OSError, ValueError):  # not a descriptor (a capture): nothing to redirect
        pass


class _Rank0Filter(logging.Filter):
    def filter(self, record: logging.LogRecord) -> bool:
        return world_rank() == 0


class _StderrHandler(logging.StreamHandler):
    """A handler on whatever ``sys.stderr`` is when a record is emitted, not the stream of its
    set-up: one replaced since (a test harness's capture, closed after its test) made every
    later record a "Logging error" and its line lost."""

    def __init__(self):
        super().__init__(sys.stderr)

    @property
    def stream(self):
        return sys.stderr

    @stream.setter
    def stream(self, value) -> None:
        pass


def configure_logging(verbosity: int = 0) -> None:
    """Send ``meicp`` log records to stderr on rank 0: WARNING by default, INFO with -v, DEBUG with -vv."""
    logger = logging.getLogger("meicp")
    level = logging.WARNING if verbosity <= 0 else logging.INFO if verbosity == 1 else logging.DEBUG
    logger.setLevel(level)
    if not any(getattr(h, "_meicp", False) for h in logger.handlers):
        handler = _StderrHandler()
        handler.setFormatter(logging.Formatter("meicp: %(message)s"))
        handler.addFilter(_Rank0Filter())
        handler._meicp = True
        logger.addHandler(handler)
