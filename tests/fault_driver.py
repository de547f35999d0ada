"""Run ``meicp`` with a fault injected, for tests/test_hostile_mpi.py (not a test itself).

    python tests/fault_driver.py FAULT -- MEICP ARGUMENTS...

FAULT: ``slow-write`` (the results are staged, then rank 0 pauses before moving them into
place: a window in which the hidden staging directory exists), ``rank0-busy`` (rank 0 pauses
before the analysis while the other ranks wait for it in a collective), ``internal-error``
(the analysis raises a RuntimeError, a stand-in for a bug).  When the window opens the
driver writes ``fault-driver: ready`` to stderr.
"""

from __future__ import annotations

import sys
import time

from meicp.cli import main as cli_main
from meicp.cli import solve
from meicp.io import results

PAUSE = 60.0


def ready() -> None:
    print("fault-driver: ready", file=sys.stderr, flush=True)


def slow_write() -> None:
    write_all = results._write_all

    def staged_then_pause(*args, **kwargs):
        written = write_all(*args, **kwargs)
        ready()
        time.sleep(PAUSE)
        return written

    results._write_all = staged_then_pause


def rank0_busy() -> None:
    analyze = solve.analyze

    def pause_on_rank0(scene, comm=None, **kwargs):
        if comm.Get_rank() == 0:
            ready()
            time.sleep(PAUSE)
        return analyze(scene, comm=comm, **kwargs)

    solve.analyze = pause_on_rank0


def internal_error() -> None:
    def bug(*args, **kwargs):
        raise RuntimeError("injected bug")

    solve.analyze = bug


FAULTS = {"slow-write": slow_write, "rank0-busy": rank0_busy, "internal-error": internal_error}

if __name__ == "__main__":
    FAULTS[sys.argv[1]]()
    sys.exit(cli_main.main(sys.argv[sys.argv.index("--") + 1:]))
