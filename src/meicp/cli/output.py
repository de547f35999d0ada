"""What ``--json`` promises: stdout carries one JSON document and nothing else.

Every subcommand's document starts with :func:`json_header` (``format``, ``format_version``,
``meicp_version``) and writes its numbers as :mod:`meicp.core.json_values` says (never a
string where a number belongs; ±∞ as ``null`` with a ``<key>_infinite`` flag).

**Nothing else on stdout.**  PETSc's viewers (``-log_view``, ``-meicp_as_eps_view``), MUMPS'
own prints (``-meicp_schur_mat_mumps_icntl_4 3``) and any other C or Fortran library write to
file descriptor 1 directly, beyond the reach of ``sys.stdout``.  :func:`stdout_for_json`
therefore moves descriptor 1 onto descriptor 2 (stderr) for the rest of the run, on every
rank, keeping a duplicate of the original stdout for the document alone; PETSc prints
``-log_view`` while it finalizes, after :func:`meicp.cli.main.main` has returned, so the
move is not undone for the program itself.

**A reader that goes away** (``meicp solve s.toml --json | head -c 10``): PETSc's signal
handler turned the SIGPIPE into an ``MPI_Abort`` (exit 59); :mod:`meicp.petsc` gives SIGPIPE
back to Python, so the write fails with EPIPE instead, and :func:`print_json` drops the rest
of the document quietly.  The run goes on to its end (files written, every rank leaving
together) and exits with its verdict's code.
"""

from __future__ import annotations

import json
import os
import sys
from contextlib import contextmanager

from .._version import __version__
from ..core.json_values import FORMAT_VERSION, json_ready
from ..core.log import stdout_closed, world_rank

_saved_stdout: int | None = None


def json_header(command: str) -> dict:
    """The keys every ``--json`` document starts with: ``format`` (``meicp-<command>``),
    ``format_version`` (:data:`FORMAT_VERSION`) and ``meicp_version``."""
    return {"format": f"meicp-{command}", "format_version": FORMAT_VERSION, "meicp_version": __version__}


def _real_stdout() -> bool:
    """Whether ``sys.stdout`` writes to descriptor 1 (not a capture of it, as in pytest)."""
    try:
        return sys.stdout.fileno() == 1
    except (AttributeError, OSError, ValueError):
        return False


@contextmanager
def stdout_for_json(enabled: bool, *, restore: bool = False):
    """Inside the block, descriptor 1 goes to stderr and :func:`print_json` writes to the
    original stdout (see the module docstring).  ``restore``: move descriptor 1 back on
    leaving (a caller of :func:`~meicp.cli.main.main` from Python); the program itself
    leaves it on stderr, so that what PETSc prints at its finalization stays off stdout.
    Nothing happens when ``enabled`` is false or ``sys.stdout`` is not descriptor 1."""
    global _saved_stdout
    if not enabled or not _real_stdout() or _saved_stdout is not None:
        yield
        return
    sys.stdout.flush()
    _saved_stdout = os.dup(1)
    os.dup2(2, 1)
    try:
        yield
    finally:
        saved, _saved_stdout = _saved_stdout, None
        sys.stdout.flush()
        if restore:
            os.dup2(saved, 1)
        os.close(saved)


def print_json(doc: dict) -> None:
    """Write ``doc`` (numbers made JSON-ready) as the run's one JSON document on rank 0; call
    it on every rank.  A reader that has gone away loses the rest of it, quietly."""
    if world_rank() != 0:
        return
    text = json.dumps(json_ready(doc), indent=2, ensure_ascii=False, allow_nan=False) + "\n"
    if _saved_stdout is None:
        try:
            sys.stdout.write(text)
            sys.stdout.flush()
        except BrokenPipeError:
            stdout_closed()
        return
    data = memoryview(text.encode("utf-8"))
    try:
        while data:
            data = data[os.write(_saved_stdout, data):]
    except BrokenPipeError:
        pass
