"""The PETSc/SLEPc layer: the only place that imports petsc4py and slepc4py.

It builds on ``lcp`` and ``eicp`` one way: :mod:`~meicp.petsc.mat` registers the PETSc Mat
with the operations of :mod:`meicp.core.matrix`, and the methods that need PETSc register
themselves by name (``eicp_active_set``, ``eicp_semismooth``, ``lcp``); ``meicp/__init__``
imports those modules, so the registries are whole whatever the caller imported.

Debian installs petsc4py/slepc4py under ``/usr/lib/petscdir/...`` and ``/usr/lib/slepcdir/...``
rather than on the default ``sys.path`` (docs/design.md §11).  :func:`import_petsc` finds them, so
users need no ``PETSC_DIR``; ``make setup`` also writes a ``.pth`` file into the venv
with the same paths so that a bare ``import petsc4py`` works there.

:func:`import_petsc` initialises PETSc with the command-line options given to
:func:`init` (the CLI passes what follows ``--``); call :func:`init` before the first use.
"""

from __future__ import annotations

import glob
import importlib.util
import resource
import signal
import sys

import numpy

from ..core.environment import MissingDependency, describe, missing_line, numpy_mismatch

_ARGV: list[str] = []


def debian_paths() -> list[str]:
    """The site directories of Debian's real-scalar petsc4py and slepc4py, newest first."""
    paths = []
    for pattern in ("/usr/lib/petscdir/petsc3.*/*-real/lib/python3/dist-packages",
                    "/usr/lib/slepcdir/slepc3.*/*-real/lib/python3/dist-packages"):
        found = sorted(glob.glob(pattern), reverse=True)
        if found:
            paths.append(found[0])
    return paths


def _ensure_on_path() -> None:
    try:
        import petsc4py  # noqa: F401
        import slepc4py  # noqa: F401
        return
    except ImportError:
        pass
    for p in debian_paths():
        if p not in sys.path:
            sys.path.append(p)


def init(argv: list[str] | None = None) -> None:
    """Record PETSc command-line options; effective only before PETSc is first imported."""
    global _ARGV
    _ARGV = list(argv or [])
    if "petsc4py.PETSc" in sys.modules and _ARGV:
        # too late for petsc4py.init; insert into the live database instead (same precedence)
        sys.modules["petsc4py.PETSc"].Options().insertString(" ".join(_ARGV))


def given_options() -> list[str]:
    """The names (without the dash) of the options given to :func:`init`."""
    return [a.lstrip("-") for a in _ARGV if a.startswith("-") and not _is_number(a)]


def _is_number(text: str) -> bool:
    try:
        float(text)
        return True
    except ValueError:
        return False


def import_petsc():
    """Return the ``PETSc`` module, initialising PETSc and SLEPc with the options given to
    :func:`init` (SLEPc is initialised with PETSc so that the order of first use is irrelevant).
    Raises :class:`~meicp.core.environment.MissingDependency` when petsc4py or slepc4py is
    missing or cannot be loaded with this NumPy."""
    if "petsc4py.PETSc" not in sys.modules:
        _ensure_on_path()
        _check_bindings()
        try:
            import slepc4py
            slepc4py.init([sys.argv[0] if sys.argv else "meicp"] + _ARGV)
            from petsc4py import PETSc  # noqa: F401
        except Exception as exc:  # noqa: BLE001 - a build mismatch raises more than ImportError
            raise MissingDependency(describe([f"PETSc/SLEPc cannot be loaded: {type(exc).__name__}: "
                                              f"{exc}"])) from exc
        _give_sigpipe_back()
        _raise_stack_limit()
    from petsc4py import PETSc
    return PETSc


def _raise_stack_limit() -> None:
    """Let the main thread's stack grow to the hard limit, as MUMPS' users are told to
    (``ulimit -s unlimited``): its analysis and factorisation recurse over the elimination
    tree, which on a long, shallow lattice is deep — a 6-row, 83,333-column lattice (10⁶ DOFs)
    ended in a segmentation fault under the default 8 MB (docs/benchmarks-notes.md,
    "stack limit").  The main thread's stack grows on demand to the limit in force then; the
    memory is used only where the recursion reaches."""
    soft, hard = resource.getrlimit(resource.RLIMIT_STACK)
    if soft != resource.RLIM_INFINITY and (hard == resource.RLIM_INFINITY or soft < hard):
        try:
            resource.setrlimit(resource.RLIMIT_STACK, (hard, hard))
        except (ValueError, OSError):  # a limit the system refuses: MUMPS keeps the one it had
            pass


def start() -> None:
    """Initialise PETSc and SLEPc on this rank now (their finalisation at exit is collective:
    a rank of a job that never used them while another did makes the job abort at exit)."""
    import_petsc()


def _give_sigpipe_back() -> None:
    """Python ignores SIGPIPE, so that a write to a closed pipe raises BrokenPipeError;
    PETSc's initialisation installs its own handler, which turns ``meicp ... | head`` into an
    ``MPI_Abort`` (exit 59) on the first write after the reader left.  Ignore it again (its
    other handlers, SIGSEGV and SIGFPE, stay: their report is PETSc's).  Only the main
    thread may set a handler; elsewhere PETSc's stays."""
    try:
        signal.signal(signal.SIGPIPE, signal.SIG_IGN)
    except (ValueError, AttributeError):  # not the main thread; no SIGPIPE (not POSIX)
        pass


def _check_bindings() -> None:
    """Name a missing binding, or a NumPy that cannot load Debian's, before importing them
    (NumPy 2 would print its own page of warnings and then fail inside petsc4py)."""
    problems = [missing_line(m, ModuleNotFoundError(name=m))
                for m in ("petsc4py", "slepc4py") if importlib.util.find_spec(m) is None]
    spec = importlib.util.find_spec("petsc4py") if not problems else None
    mismatch = numpy_mismatch(numpy.__version__, spec.origin if spec else None)
    if mismatch:
        problems.append(mismatch)
    if problems:
        raise MissingDependency(describe(problems))


def import_slepc():
    """Return the ``SLEPc`` module (initialised together with PETSc)."""
    import_petsc()
    from slepc4py import SLEPc
    return SLEPc

