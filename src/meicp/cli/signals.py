"""SIGINT and SIGTERM end the whole ``meicp`` run within seconds and leave nothing behind.

Why a watchdog thread.  A Python signal handler runs in the main thread between two
bytecodes only: a rank blocked in an MPI collective (waiting for a rank that was stopped)
or inside MUMPS never gets there, so Ctrl-C used to leave both ranks of a 2-rank run
hanging.  Python's C-level handler, though, writes the signal number to the file descriptor
given to :func:`signal.set_wakeup_fd` at once, from whichever thread received the signal.
A daemon thread blocked on that pipe wakes up, runs the registered cleanups
(:func:`meicp.core.cleanup.run_cleanups`: the hidden staging directory of the results),
prints one line and ends the run: ``MPI_Abort`` when several ranks run (the others may be
blocked waiting for this one; mpi4py initialises MPI with ``MPI_THREAD_MULTIPLE``, so the
call from this thread is allowed), ``os._exit`` otherwise.  Exit status 128 + the signal
number (130 for SIGINT, 143 for SIGTERM), as a shell reports it.

How the signals arrive.  Ctrl-C in a terminal goes to ``mpirun`` only (OpenMPI 4.1 starts
each rank in its own process group); on SIGINT or SIGTERM ``mpirun`` sends SIGCONT and
SIGTERM to every rank, and SIGKILL about a second later — the cleanup takes milliseconds.
A signal sent to one rank (``kill -INT <pid>``) ends that rank, and ``MPI_Abort`` makes
``mpirun`` send SIGTERM to the others, which clean up the same way.
"""

from __future__ import annotations

import os
import signal
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager

from ..core.cleanup import run_cleanups
from ..core.log import world_rank

#: the signals that end a run (SIGHUP and the others keep their default action)
SIGNALS = (signal.SIGINT, signal.SIGTERM)
#: seconds the cleanups may wait for a rename in progress before the run ends anyway
CLEANUP_WAIT = 2.0

_interrupted = threading.Event()


def interrupted() -> bool:
    """Whether a signal is ending this run (the main thread then keeps quiet and waits)."""
    return _interrupted.is_set()


def wait_for_the_end(seconds: float = 30.0) -> None:
    """Called by the main thread when it notices :func:`interrupted`: the watchdog is ending
    the process; do nothing that could print or hang meanwhile."""
    time.sleep(seconds)


@contextmanager
def interrupts_end_the_run() -> Iterator[None]:
    """Inside the block, SIGINT and SIGTERM end the run as the module docstring says; the
    previous handlers are restored afterwards.  Outside the main thread (where Python cannot
    install handlers) the block runs unchanged."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    read_end, write_end = os.pipe()
    os.set_blocking(write_end, False)  # set_wakeup_fd requires it
    previous_fd = signal.set_wakeup_fd(write_end, warn_on_full_buffer=False)
    # a Python-level handler must be installed for the C handler to write to the pipe; it
    # does nothing itself (the watchdog acts, whatever the main thread is doing)
    previous = {s: signal.signal(s, _noted) for s in SIGNALS}
    watchdog = threading.Thread(target=_watch, args=(read_end,), name="meicp-signals", daemon=True)
    watchdog.start()
    try:
        yield
    finally:
        if _interrupted.is_set():  # the watchdog is ending the process: let it
            watchdog.join(timeout=30.0)
        for s, handler in previous.items():
            signal.signal(s, handler)
        signal.set_wakeup_fd(previous_fd)
        os.close(write_end)  # the watchdog reads end-of-file and returns
        watchdog.join(timeout=5.0)
        os.close(read_end)


def _noted(signum, frame) -> None:
    """The main thread's part: none (the watchdog has already been woken by the pipe)."""


def _watch(read_end: int) -> None:
    while True:  # other signals with a Python handler write to the pipe as well: skip them
        try:
            data = os.read(read_end, 1)
        except OSError:
            return
        if not data:
            return
        if data[0] in {int(s) for s in SIGNALS}:
            break
    signum = data[0]
    _interrupted.set()
    run_cleanups(CLEANUP_WAIT)
    size = _world_size()
    who = f"[rank {world_rank()}] " if size > 1 else ""
    try:
        print(f"meicp: {who}interrupted by {signal.Signals(signum).name}", file=sys.stderr, flush=True)
    except Exception:  # noqa: BLE001 - stderr may be gone; the run must end all the same
        pass
    code = 128 + signum
    if size > 1:
        sys.modules["mpi4py.MPI"].COMM_WORLD.Abort(code)
    os._exit(code)


def _world_size() -> int:
    mpi = sys.modules.get("mpi4py.MPI")
    if mpi is None or not mpi.Is_initialized() or mpi.Is_finalized():
        return 1
    return mpi.COMM_WORLD.Get_size()
