"""The exception family of meicp.

Every error meicp raises on purpose is a :class:`MeicpError`, so a caller can catch
the whole family with one clause, or one kind precisely:

- :class:`ProblemError`: the input is wrong (shape, NaN, non-SPD where SPD is required,
  unknown scene key, index out of range).  Raised before any work is done.
- :class:`ConvergenceError`: a solver ran but could not certify a solution; carries the
  partial result in ``.result`` so nothing computed is lost.
- :class:`SolverNotFound`: a method name that is not registered; lists the known ones.
- :class:`PetscSolveError`: PETSc or SLEPc stopped a solve with an error; ``meicp.petsc``
  raises it in place of petsc4py's own, so no caller outside it names PETSc.
- :class:`PetscOptionError`: PETSc refused an option value the user gave (bad input).
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


class PetscSolveError(MeicpError, RuntimeError):
    """PETSc or SLEPc ended a solve with an error: ``ierr`` its error code, ``line`` the last
    line of its text (what went wrong, without the rank tag)."""

    def __init__(self, message: str, ierr: int | None = None, line: str = ""):
        super().__init__(message)
        self.ierr = ierr
        self.line = line


class PetscOptionError(ProblemError):
    """PETSc refused an option value (``ierr``: its error code): bad input, whichever method
    reads it."""

    def __init__(self, message: str, ierr: int | None = None):
        super().__init__(message)
        self.ierr = ierr
