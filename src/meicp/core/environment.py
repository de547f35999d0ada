"""What meicp needs from the Python it runs in, checked up front: a message, not a traceback.

meicp declares no pip dependencies on purpose: NumPy, SciPy, mpi4py, petsc4py, slepc4py and
h5py come from Debian's packages (their PETSc bindings are compiled against Debian's NumPy
1.24), and ``make setup`` makes a ``.venv`` that sees them.  A venv made without
``--system-site-packages``, or one where pip put NumPy 2 over Debian's, fails deep inside
an import; :func:`require_python_stack` (run by ``import meicp``) and
:func:`meicp.petsc.import_petsc` report such a set-up as :class:`MissingDependency`, naming
what is missing and how to set up.  Nothing here imports NumPy before it is known to work.
"""

from __future__ import annotations

import importlib
import importlib.util
import sys

from .errors import MeicpError

#: the Debian package that provides each Python module meicp uses
DEBIAN_PACKAGES = {
    "numpy": "python3-numpy", "scipy": "python3-scipy", "mpi4py": "python3-mpi4py",
    "petsc4py": "python3-petsc4py-real", "slepc4py": "python3-slepc4py-real",
    "h5py": "python3-h5py-mpi", "matplotlib": "python3-matplotlib", "threadpoolctl": "python3-threadpoolctl",
}

SETUP_ADVICE = (
    "meicp uses Debian's packages, not pip builds. Set up with `make setup` in the meicp\n"
    "checkout (it installs them and a .venv that sees them), then run .venv/bin/meicp or\n"
    ".venv/bin/python. A venv of your own needs /usr/bin/python3 -m venv --system-site-packages,\n"
    "and pip must not install numpy into it.")


class MissingDependency(MeicpError, ImportError):
    """A module meicp needs is missing or does not match the others (e.g. NumPy 2 under
    petsc4py built for NumPy 1); the message says which and how to set up."""


def describe(problems: list[str]) -> str:
    """One message for a list of problems (one line each), with the set-up advice."""
    return "\n".join([f"this Python ({sys.executable}) cannot run meicp:"]
                     + [f"  - {p}" for p in problems] + [SETUP_ADVICE])


def missing_line(module: str, exc: BaseException) -> str:
    package = DEBIAN_PACKAGES.get(module, module)
    if isinstance(exc, ModuleNotFoundError) and exc.name == module:
        return f"{module} is missing (Debian package {package})"
    return f"{module} cannot be imported (Debian package {package}): {type(exc).__name__}: {exc}"


def require_python_stack() -> None:
    """Import NumPy and SciPy and find mpi4py (without starting MPI); raise
    :class:`MissingDependency` listing every one that fails.  When it raises, a console
    run (``meicp ...``) prints the message alone instead of a traceback."""
    problems = []
    for module in ("numpy", "scipy"):
        try:
            importlib.import_module(module)
        except Exception as exc:  # noqa: BLE001 - an ABI mismatch raises more than ImportError
            problems.append(missing_line(module, exc))
    if importlib.util.find_spec("mpi4py") is None:
        problems.append(missing_line("mpi4py", ModuleNotFoundError(name="mpi4py")))
    if problems:
        _print_message_instead_of_traceback()
        raise MissingDependency(describe(problems))


def numpy_mismatch(numpy_version: str, petsc4py_path: str | None) -> str | None:
    """Why this NumPy cannot load Debian's petsc4py, or None.  Debian bookworm builds
    petsc4py against NumPy 1.24; a NumPy 2 (from pip) cannot import it."""
    major = int(numpy_version.split(".")[0])
    if major >= 2 and petsc4py_path and petsc4py_path.startswith("/usr/lib/petscdir/"):
        return (f"numpy {numpy_version} is installed, but Debian's petsc4py ({petsc4py_path}) is "
                f"built against numpy 1.x and cannot be imported with it")
    return None


def _print_message_instead_of_traceback() -> None:
    """An import-time :class:`MissingDependency` that nobody catches is printed as
    ``meicp: error: <message>`` (exit status 1): the console script imports the package
    before any of its code can catch anything.  Other exceptions keep the usual hook."""
    previous = sys.excepthook

    def hook(kind, value, tb):
        if isinstance(value, MissingDependency):
            print(f"meicp: error: {value}", file=sys.stderr)
        else:
            previous(kind, value, tb)

    sys.excepthook = hook
