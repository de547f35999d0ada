"""The exit codes of every ``meicp`` command (listed in ``meicp --help``)."""

from __future__ import annotations

from enum import IntEnum


class Exit(IntEnum):
    """0 the command answered, 1 no certified answer (a solver failed), 2 bad input or
    usage, 3 internal error.  A run ended by SIGINT or SIGTERM exits with 128 + the signal
    number (130, 143; :mod:`meicp.cli.signals`), or 1 from ``mpirun`` when it was signalled."""

    OK = 0
    FAILED = 1
    BAD_INPUT = 2
    INTERNAL = 3


#: what each exit code means, for ``meicp --help``
MEANING = {
    Exit.OK: "the command answered: stable, unstable (also a certified flutter mode while the "
             "divergence search was inconclusive), undecided with what was proved, or the "
             "modal analysis of a scene without contact",
    Exit.FAILED: "no certified answer: a solver stopped without one (the message says why)",
    Exit.BAD_INPUT: "bad input or usage: a scene key, a file, an argument, a PETSc option value",
    Exit.INTERNAL: "internal error: a bug in meicp (run again with -vv and report it)",
}
