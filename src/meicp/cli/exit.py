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
