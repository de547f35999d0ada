"""The exception family of meicp.

Every error meicp raises on purpose is a :class:`MeicpError`, so a caller can catch
the whole family with one clause, or one kind precisely:

- :class:`ProblemError`: the input is wrong (shape, NaN, non-SPD where SPD is required,
  unknown scene key, index out of range).  Raised before any work is done.
- :class:`ConvergenceError`: a solver ran but could not certify a solution; carries the
  partial result in ``.result`` so nothing computed is lost.
- :class:`SolverNotFound`: a method name that is not registered; lists the known ones.
"""

from __future__ import annotations


class MeicpError(Exception):
    """Base class of every error meicp raises on purpose."""


class ProblemError(MeicpError, ValueError):
    """Bad input: the message names the argument or key and what is wrong with it."""


class ConvergenceError(MeicpError, RuntimeError):
    """A solver stopped without a certified solution; ``result`` holds what it reached."""

    def __init__(self, message: str, result=None):
        super().__init__(message)
        self.result = result


class SolverNotFound(MeicpError, KeyError):
    """Unknown method name; ``available`` lists the registered ones."""

    def __init__(self, name: str, available):
        self.name = name
        self.available = sorted(available)
        super().__init__(name)

    def __str__(self) -> str:
        return f"unknown method {self.name!r}; available: {', '.join(self.available)}"
