"""PETSc options with a prefix, in the order every meicp solver uses them.

Precedence, lowest first: code defaults, then the scene's ``[petsc]`` table, then the
command line (options after ``--``, already in the database when PETSc starts).  A value
already in the database is never overwritten, so the command line wins.  What a scope
inserted is deleted on exit (the 3.18 database holds at most 512 entries), and options
under the prefix that no PETSc object read are reported (PETSc's ``PetscOptionsUsed``).
"""

from __future__ import annotations

import ctypes
import logging
import time

from . import import_petsc

log = logging.getLogger("meicp.petsc")


def _format(value) -> str | None:
    if value is True or value is None:
        return None  # a flag
    if value is False:
        return "false"
    return str(value)


class OptionsScope:
    """Context manager that puts options under ``prefix`` for the duration of one solve.

    ``layers`` are dicts from lowest to highest precedence (code defaults, then scene);
    keys without the leading dash and without the prefix, values as Python objects
    (``True`` for a flag).  Example::

        with OptionsScope("meicp_eps_", {"eps_tol": 1e-10}, scene.petsc) as opts:
            eps.setOptionsPrefix(opts.prefix); eps.setFromOptions()
        opts.unused  # names under the prefix that nothing read

    The first layer is the code's defaults: those that nothing read (e.g. MUMPS options when
    the user chose another factorisation) are left out of the warning about unused options.
    ``warn=False``: only record them in ``unused`` (a caller that opens one scope per solve
    reports once, for all of them).
    """

    def __init__(self, prefix: str, *layers: dict | None, warn: bool = True):
        self.prefix = prefix
        self.warn = warn
        self.layers = [dict(layer) if layer else {} for layer in layers]
        self.inserted: list[str] = []
        self.unused: list[str] = []
        self._defaults_only: set[str] = set()

    def __enter__(self) -> "OptionsScope":
        PETSc = import_petsc()
        db = PETSc.Options()
        for level in reversed(range(len(self.layers))):  # highest first: lower ones never override
            for key, value in self.layers[level].items():
                name = self.prefix + str(key).lstrip("-")
                if db.hasName(name):
                    continue
                db.setValue(name, _format(value))
                self.inserted.append(name)
                if level == 0:
                    self._defaults_only.add(name)
        return self

    def __exit__(self, *exc) -> None:
        PETSc = import_petsc()
        db = PETSc.Options()
        self.unused = [name for name in self._names_under_prefix(db)
                       if not options_used(name) and name not in self._defaults_only]
        if self.warn:
            report_unused(self.unused)
        for name in self.inserted:
            db.delValue(name)
        self.inserted.clear()
        self._defaults_only.clear()

    def _names_under_prefix(self, db) -> list[str]:
        return sorted(n for n in db.getAll() if n.startswith(self.prefix))


def report_unused(names) -> None:
    """Warn (once per call) about options that no PETSc object read."""
    if names:
        log.warning("PETSc options not used by any solver: %s", ", ".join("-" + n for n in names))


_USED = None


def options_used(name: str) -> bool:
    """Whether a PETSc object has queried ``-name`` (``PetscOptionsUsed`` in the C API,
    which petsc4py 3.18 does not wrap; libpetsc is already loaded by petsc4py)."""
    global _USED
    if _USED is None:
        import_petsc()
        try:
            fn = ctypes.CDLL(None).PetscOptionsUsed
        except AttributeError:
            fn = ctypes.CDLL("libpetsc_real.so.3.18").PetscOptionsUsed
        fn.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.POINTER(ctypes.c_int)]
        fn.restype = ctypes.c_int
        _USED = fn
    flag = ctypes.c_int(0)
    _USED(None, name.lstrip("-").encode(), ctypes.byref(flag))
    return bool(flag.value)


def configure_and_solve(solver, prefix: str, defaults: dict, options: dict | None, solve) -> tuple:
    """Give a SNES, TAO or KSP its options (code defaults < ``options`` < command line) under
    ``prefix``, call ``solve()`` and return ``(seconds, reason_name, iterations)``."""
    t0 = time.perf_counter()
    with OptionsScope(prefix, defaults, options):
        solver.setOptionsPrefix(prefix)
        solver.setFromOptions()
        solve()
    seconds = time.perf_counter() - t0
    return seconds, reason_name(solver), solver.getIterationNumber()


def reason_name(solver) -> str:
    """``NAME (code)`` of a SNES, KSP or TAO converged reason."""
    PETSc = import_petsc()
    enum = (PETSc.SNES.ConvergedReason if isinstance(solver, PETSc.SNES) else
            PETSc.KSP.ConvergedReason if isinstance(solver, PETSc.KSP) else PETSc.TAO.Reason)
    value = solver.getConvergedReason()
    for name in dir(enum):
        if not name.startswith("_") and getattr(enum, name) == value:
            return f"{name} ({value})"
    return str(value)
