"""PETSc options with a prefix, in the order every meicp solver uses them.

Precedence, lowest first: code defaults, then the scene's ``[petsc]`` table, then the
command line (options after ``--``, already in the database when PETSc starts).  A value
already in the database is never overwritten, so the command line wins.  What a scope
inserted is deleted on exit (the 3.18 database holds at most 512 entries), and options
under the prefix that no PETSc object read are reported (PETSc's ``PetscOptionsUsed``);
:func:`report_unused_options` reports, at the end of a run, every option left in the
database that nothing read, whatever its prefix (``-eps_tol`` without one included).

A value PETSc cannot use (``-meicp_as_eps_tol abc``, ``-meicp_ghep_st_type foo``) surfaces as
a :class:`PetscOptionError` naming the prefix and the options given under it
(:func:`set_from_options`), not as a PETSc traceback.

Every prefix meicp reads is a constant here, listed with what reads it in :data:`PREFIXES`
(``meicp --help`` prints that table): the solvers take their prefix from this module.
"""

from __future__ import annotations

import ctypes
import logging
import re
import sys
import time
from contextlib import contextmanager

from ..core.errors import PetscOptionError, PetscSolveError
from . import given_options, import_petsc
from .monitor import watch

log = logging.getLogger("meicp.petsc")

#: the SLEPc eigen-solves of the active-set MEiCP search (``eps_*``, ``st_*``)
ACTIVE_SET = "meicp_as_"
#: the SLEPc eigen-solve of a symmetric-definite pencil: a scene's modal analysis
GHEP = "meicp_ghep_"
#: the MUMPS LDLᵀ factorisation whose inertia proves a symmetric pencil stable
INERTIA = "meicp_inertia_"
#: SNES VI of the static frictional equilibrium (the sparse mixed LCP)
STATIC = "meicp_static_"
#: MUMPS LU that polishes the static equilibrium's answer
STATIC_POLISH = STATIC + "polish_"
#: MUMPS LDLᵀ of the static equilibrium's bordered stiffness and its Schur complement onto
#: the contact unknowns (``formulation="schur"``): ``mat_mumps_icntl_<k>`` / ``mat_mumps_cntl_<k>``
STATIC_SCHUR = STATIC + "schur_"
#: SNES VI (``newton``) and TAO (``tao``) of ``solve_lcp``
LCP = "meicp_lcp_"
#: MUMPS LU solves of :func:`meicp.petsc.lcp.lu_solve`
LU = "meicp_lu_"
#: SNES VI of the semismooth EiCP method
EICP_VI = "meicp_eicp_vi_"
#: ``meicp info --check``'s distributed eigen-solve
SELFCHECK = "meicp_selfcheck_"
#: the complex shift-and-invert solves of the flutter search on a large sliding pencil
FLUTTER = "meicp_flutter_"
#: MUMPS factorisations of the condensation onto the contact DOFs (Schur complements, solves)
SCHUR = "meicp_schur_"
#: the Lanczos estimate of λ_max(sym A, sym B) that places the divergence search's σ-window
WINDOW = "meicp_window_"

#: prefix → what reads options under it (``meicp --help`` lists these)
PREFIXES = {
    ACTIVE_SET: "SLEPc EPS/ST of the active-set search (meicp solve, meicp eicp)",
    GHEP: "SLEPc EPS/ST of the modal analysis of a scene without contact",
    INERTIA: "MUMPS LDLᵀ (KSP/PC) whose inertia proves a symmetric pencil stable",
    STATIC: "SNES VI of the static frictional equilibrium (states = \"solve\")",
    STATIC_POLISH: "MUMPS LU polishing the static equilibrium",
    STATIC_SCHUR: ("MUMPS LDLᵀ + Schur complement of the static equilibrium condensed onto its contacts "
                   "(formulation schur): mat_mumps_icntl_<k> / mat_mumps_cntl_<k>"),
    LCP: "SNES VI / TAO of meicp lcp --method newton | tao",
    LU: "MUMPS LU solves (KSP/PC)",
    EICP_VI: "SNES VI of the semismooth EiCP method",
    SELFCHECK: "SLEPc EPS of meicp info --check",
    FLUTTER: ("SLEPc EPS (complex shift-and-invert) of the flutter search on a large pencil; its complex MUMPS "
              "factor: st_mat_mumps_icntl_<k> / st_mat_mumps_cntl_<k>; real_form: the real 2n LU instead"),
    SCHUR: "MUMPS Schur complements and solves condensing a pencil onto its contact DOFs",
    WINDOW: "SLEPc EPS (Lanczos, no factorisation) estimating the top of the divergence σ-window",
}
#: options PETSc reads only in PetscFinalize, after the end-of-run report
_READ_AT_FINALIZE = {"options_left", "options_view", "malloc_dump", "malloc_view", "memory_view",
                     "objects_dump"}
#: PETSc error codes of a wrong argument or option value (PETSC_ERR_SUP, _ARG_SIZ, _ARG_IDN,
#: _ARG_WRONG, _ARG_OUTOFRANGE, _ARG_INCOMP, _ARG_UNKNOWN_TYPE)
ARGUMENT_ERRORS = (56, 60, 61, 62, 63, 75, 86)
_RANK_TAG = re.compile(r"^\[\d+\]\s*")  # PETSc's "[0] " before each line of its error text


def petsc_error_line(exc) -> str:
    """The last line of a PETSc error's text, without the rank tag (what went wrong)."""
    text = str(exc).strip()
    return _RANK_TAG.sub("", text.splitlines()[-1].strip()) if text else ""


@contextmanager
def petsc_errors(what: str):
    """PETSc's own errors inside the block (or the decorated function) raised as
    :class:`~meicp.core.errors.PetscSolveError` ("PETSc error <ierr> in <what>: <its last
    line>"), so that callers outside ``meicp.petsc`` catch meicp's exceptions; a
    :class:`PetscOptionError` and every other error pass untouched."""
    PETSc = import_petsc()
    try:
        yield
    except PETSc.Error as exc:
        line = petsc_error_line(exc)
        raise PetscSolveError(f"PETSc error {exc.ierr} in {what}" + (f": {line}" if line else ""),
                              exc.ierr, line) from exc


def set_from_options(obj, prefix: str, defaults=()) -> None:
    """``obj.setOptionsPrefix(prefix); obj.setFromOptions()``, with a value PETSc rejects
    reported as a :class:`PetscOptionError` naming the prefix and the options given under it
    (the command line's and the scene's; ``defaults``: names to leave out, the code's own)."""
    PETSc = import_petsc()
    obj.setOptionsPrefix(prefix)
    try:
        obj.setFromOptions()
    except PETSc.Error as exc:
        if getattr(exc, "ierr", None) not in ARGUMENT_ERRORS:
            raise
        given = " ".join(f"-{name}" + (f" {value}" if value else "")
                         for name, value in sorted(PETSc.Options().getAll().items())
                         if name.startswith(prefix) and name not in defaults)
        raise PetscOptionError(f"PETSc cannot use an option value under -{prefix}: {petsc_error_line(exc)}"
                               f"; check the -{prefix}* options and the scene's [petsc] table"
                               + (f" (given: {given})" if given else ""), exc.ierr) from None


def require_mumps_factor(ksp, prefix: str, kinds: tuple[str, ...], purpose: str) -> None:
    """After :func:`set_from_options`: a :class:`PetscOptionError` naming the options unless
    the KSP's preconditioner is a MUMPS factorisation of one of ``kinds`` (``"cholesky"``,
    ``"lu"``).  ``purpose``: what needs it (a proof reads the factor itself — its inertia, its
    Schur complement — so ``-<prefix>pc_type jacobi`` would end in a PETSc error deep inside;
    a value PETSc accepts is not always one the proof can use).  The same on every rank."""
    pc = ksp.getPC()
    kind, solver = pc.getType(), pc.getFactorSolverType() if pc.getType() in kinds else None
    if kind in kinds and solver == "mumps":
        return
    given = f"-{prefix}pc_type {kind}" if kind not in kinds else f"-{prefix}pc_factor_mat_solver_type {solver}"
    raise PetscOptionError(f"{given}: {purpose} reads a MUMPS factorisation (pc_type {' or '.join(kinds)}, "
                           f"pc_factor_mat_solver_type mumps); leave -{prefix}pc_type and "
                           f"-{prefix}pc_factor_mat_solver_type at their defaults")


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

        with OptionsScope(GHEP, {"eps_tol": 1e-10}, scene.petsc) as opts:
            opts.configure(eps)
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
                if level > 0:
                    _OFFERED.add(str(key).lstrip("-"))
                if db.hasName(name):
                    continue
                db.setValue(name, _format(value))
                self.inserted.append(name)
                if level == 0:
                    self._defaults_only.add(name)
        return self

    def configure(self, obj) -> None:
        """Give a PETSc/SLEPc object this scope's prefix and its options
        (:func:`set_from_options`: a rejected value names the options the user gave), and an
        EPS or SNES its progress lines (:func:`meicp.petsc.monitor.watch`)."""
        set_from_options(obj, self.prefix, self._defaults_only)
        watch(obj, self.prefix)

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


_REPORTED: set = set()
#: keys of a scene's ``[petsc]`` table (and other non-default layers) that some scope put
#: in the database for a solver to read
_OFFERED: set = set()


def report_not_offered(keys) -> None:
    """Warn about ``[petsc]`` table entries that reached no solver at all: the run needed
    none that reads them (e.g. a small scene enumerated densely), so their values were
    neither used nor checked — the table's counterpart of :func:`report_unused_options`."""
    left = sorted(k for k in (str(key).lstrip("-") for key in keys) if k not in _OFFERED)
    if left:
        log.warning("the scene's [petsc] entries reached no PETSc solver (this run used none that reads them; "
                    "their values were not checked): %s", ", ".join(left))


def report_unused(names) -> None:
    """Warn about options that no PETSc object read (each name once per process)."""
    names = [n for n in names if n not in _REPORTED]
    if names:
        _REPORTED.update(names)
        log.warning("PETSc options not used by any solver: %s", ", ".join("-" + n for n in names))


def unused_options() -> list[str]:
    """Options in PETSc's database that no PETSc object has read (``PetscOptionsUsed``),
    whatever their prefix; every option given to :func:`~meicp.petsc.init` when PETSc was
    never started.  Local (no communication)."""
    if "petsc4py.PETSc" not in sys.modules:
        return sorted(given_options())
    db = import_petsc().Options()
    return sorted(n for n in db.getAll() if n not in _READ_AT_FINALIZE and not options_used(n))


def report_unused_options() -> None:
    """Warn (through the ``meicp`` logger, rank 0) about every option no solver read: the
    end-of-run counterpart of PETSc's ``-options_left``."""
    report_unused(unused_options())


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


def st_low_rank(low_rank: float | None) -> dict:
    """Code defaults (spectral-transform prefix) for a block-low-rank MUMPS factor and solves
    (ICNTL(35) = 2) at the dropping tolerance ``low_rank`` (CNTL(7)); none for None."""
    return {"st_mat_mumps_icntl_35": 2, "st_mat_mumps_cntl_7": low_rank} if low_rank else {}


def st_node_pairs(n: int) -> dict:
    """Code defaults (spectral-transform prefix) making MUMPS analyse the graph of DOF pairs,
    a lattice node (ICNTL(15) = −2), for a matrix of even order ``n``; none (0) for an odd one,
    whose order the block does not divide (MUMPS 5.5 refuses it, INFOG(1) = −57)."""
    return {"st_mat_mumps_icntl_15": -2 if n % 2 == 0 else 0}


def mumps_controls(head: str) -> tuple[dict, dict]:
    """``(icntl, cntl)``: the ``-<head>icntl_<k>`` / ``-<head>cntl_<k>`` values in the options
    database (e.g. head ``meicp_schur_mat_mumps_``), by MUMPS number, for the MUMPS instances
    meicp drives itself (:mod:`meicp.petsc.mumps_c`); read, so never reported unused.  A value
    of the wrong kind is a :class:`PetscOptionError` naming it."""
    PETSc = import_petsc()
    db = PETSc.Options()
    icntl, cntl = {}, {}
    for name in db.getAll():
        for key, out, get in (("icntl_", icntl, db.getInt), ("cntl_", cntl, db.getReal)):
            if name.startswith(head + key) and name[len(head + key):].isdigit():
                try:
                    out[int(name[len(head + key):])] = get(name)
                except PETSc.Error:
                    raise PetscOptionError(f"-{name} {db.getString(name)!r} is not "
                                           f"{'an integer' if key == 'icntl_' else 'a number'}") from None
    return icntl, cntl


def configure_and_solve(solver, prefix: str, defaults: dict, options: dict | None, solve) -> tuple:
    """Give a SNES, TAO or KSP its options (code defaults < ``options`` < command line) under
    ``prefix``, call ``solve()`` and return ``(seconds, reason_name, iterations)``."""
    t0 = time.perf_counter()
    with OptionsScope(prefix, defaults, options) as scope:
        scope.configure(solver)
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
