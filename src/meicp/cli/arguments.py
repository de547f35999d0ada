"""The parser every subcommand shares (:class:`Parser`) and the argument types of their
flags: argparse reports a bad value as a one-line usage error naming the flag (exit code 2),
before any work is done.

Each numeric type wraps the check of :mod:`meicp.core.validation` that the API applies to the
same argument, so the command line and the Python API refuse the same values with the same
words.
"""

from __future__ import annotations

import argparse
import re

from ..core.errors import ProblemError
from ..core.log import world_rank
from ..core.validation import as_int, as_real, check_tol

#: an argument that starts like a negative number: a value, never an option (no meicp option
#: starts with a digit, "inf" or "nan").  argparse 3.11 knows only -1 and -0.5, so ``--target
#: -1e6`` failed with "expected one argument" (Python 3.13 widened its own pattern alike to
#: "-digit"); ``-inf``, ``-nan`` and a typo such as ``-1e6x`` reach the type's check and its message
NEGATIVE_NUMBER = re.compile(r"^-(\.?\d|inf|nan)", re.IGNORECASE)


class Parser(argparse.ArgumentParser):
    """``argparse.ArgumentParser`` (its subcommands' parsers too) with negative numbers in any
    spelling as option values (:data:`NEGATIVE_NUMBER`), and its usage, errors, ``--help``
    and ``--version`` printed on rank 0 only: every rank parses the same command line, so a
    usage error is the same on all of them and is said once, not once per rank."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = NEGATIVE_NUMBER  # argparse's own attribute, read by its parser

    def _print_message(self, message, file=None):  # every print of argparse goes through here
        if world_rank() == 0:
            super()._print_message(message, file)


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


#: a keyword hint of the Python API inside a message: method='enumerate', nev=8
_API_HINT = re.compile(r"\b(method|target|nev)=(['\"]?)([\w.+-]+)\2")


def cli_spelling(text: str) -> str:
    """A solver's message with the Python API's keyword hints spelt as this command line's
    flags: "use method='enumerate'" becomes "use --method enumerate"."""
    return _API_HINT.sub(lambda m: f"--{m.group(1)} {m.group(3)}", text or "")


def output_directory(text: str) -> str:
    """A directory path, not empty: ``-o ""`` (an unset shell variable, say) named no
    directory and fell back to the default silently."""
    if not text:
        raise argparse.ArgumentTypeError("an empty path names no directory (leave the option out for the default)")
    return text


def verbosity(parser: argparse.ArgumentParser) -> None:
    """``-v``/``-q`` after the subcommand as well as before it (``meicp solve s.toml -v``): the
    counts are added to the top-level ones by :func:`meicp.cli.main.main`."""
    parser.add_argument("-v", "--verbose", dest="verbose_after", action="count", default=argparse.SUPPRESS,
                        help="-v progress, -vv debug (also before the subcommand)")
    parser.add_argument("-q", "--quiet", action="store_true", default=argparse.SUPPRESS,
                        help="warnings and errors only, no progress lines")


def verbosity_of(args) -> tuple[int, bool]:
    """(verbosity, quiet) of parsed arguments, wherever -v/-q were given."""
    return getattr(args, "verbose", 0) + getattr(args, "verbose_after", 0), bool(getattr(args, "quiet", False))


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
