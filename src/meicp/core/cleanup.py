"""Cleanups that must run even when the process is ended from outside (SIGINT, SIGTERM).

The code that creates something temporary — the hidden staging directory of the results
(:mod:`meicp.io.results`) — registers how to remove it with :func:`on_interrupt` for as long
as it exists, and marks the few steps that must not be cut in half (moving the finished
files into place) with :func:`uninterrupted`.  The command line's signal watchdog
(:mod:`meicp.cli.signals`) calls :func:`run_cleanups` from its own thread before it ends the
run: it waits for an uninterrupted section to finish, then runs every registered action,
newest first.  Plain Python, no signals here.
"""

from __future__ import annotations

import itertools
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager

_lock = threading.RLock()
_actions: dict[int, Callable[[], object]] = {}
_keys = itertools.count()


@contextmanager
def on_interrupt(action: Callable[[], object]) -> Iterator[None]:
    """Run ``action()`` (no arguments, must not raise) if the process is interrupted while
    inside the block; nothing otherwise."""
    with _lock:
        key = next(_keys)
        _actions[key] = action
    try:
        yield
    finally:
        with _lock:
            _actions.pop(key, None)


@contextmanager
def uninterrupted() -> Iterator[None]:
    """A short section that :func:`run_cleanups` waits for (a few renames, not a computation)."""
    with _lock:
        yield


def run_cleanups(timeout: float = 2.0) -> int:
    """Run the registered actions, newest first, once no uninterrupted section is running
    (waiting at most ``timeout`` seconds); returns how many ran.  Errors are ignored: this
    runs on the way out."""
    acquired = _lock.acquire(timeout=timeout)
    try:
        actions = list(_actions.values())[::-1]
        for action in actions:
            try:
                action()
            except Exception:  # noqa: BLE001 - best effort while the process ends
                pass
        return len(actions)
    finally:
        if acquired:
            _lock.release()
