"""Argument types for the subcommands' numeric flags: argparse reports a bad value as a
one-line usage error naming the flag (exit code 2), before any work is done.

Each wraps the check of :mod:`meicp.core.validation` that the API applies to the same
argument, so the command line and the Python API refuse the same values with the same words.
"""

from __future__ import annotations

import argparse

from ..core.errors import ProblemError
from ..core.validation import as_int, as_real, check_tol


def _number(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None


def tolerance(text: str) -> float:
    """A relative certificate tolerance in (0, MAX_TOL]."""
    try:
        return check_tol(_number(text), "the tolerance")
    except ProblemError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def finite(text: str) -> float:
    """A finite real number (no nan, no inf)."""
    try:
        return as_real(_number(text), "the value")
    except ProblemError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def integer(minimum: int | None = None, maximum: int | None = None):
    """An integer in [minimum, maximum]."""
    def parse(text: str) -> int:
        try:
            return as_int(int(text), "the value", minimum=minimum, maximum=maximum)
        except ValueError as exc:  # int('1.5') and ProblemError alike
            message = str(exc) if isinstance(exc, ProblemError) else f"not an integer: {text!r}"
            raise argparse.ArgumentTypeError(message) from None
    parse.__name__ = "integer"
    return parse
