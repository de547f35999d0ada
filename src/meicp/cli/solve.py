"""``meicp solve SCENE.toml [-o DIR] [--no-output] [--json] [--method M] [--target T] [--nev N]
[--critical-friction] [--no-flutter] [--flutter-dense-max N] [-v|-q] [-- PETSc options]``.

Loads the scene (a bad scene fails before any work, exit 2), runs
:func:`meicp.contact.instability.analyze` on every rank of ``MPI.COMM_WORLD`` (a scene
without contact gets its modal analysis), prints a summary (stdout, rank 0) and writes
``results.h5``, ``lattice.h5`` + ``lattice.xdmf`` and the PNGs to DIR (default
``out/<scene stem>``; see :mod:`meicp.io.results`).  ``--method`` and ``--nev``
override the scene's ``[solver]`` table, ``--target`` sets the active-set search's shift (all
recorded in results.h5); ``--no-flutter``
skips the flutter analysis of steady sliding (docs/flutter.md): the divergence verdict
alone, and the overall verdict cannot be STABLE.

``--json``: instead of the summary, one JSON document on stdout (:func:`solve_json`): the
verdict, the modes with σ and support, μ_c when asked, the output paths, timings and
versions.  Nothing else goes there, whatever PETSc or MUMPS options print (they go to
stderr: :mod:`meicp.cli.output`).

``--critical-friction`` is an extra: when μ_c cannot be determined (a floating layer, where
it is undefined; a solver that fails) the verdict, its files and its JSON stand, the reason
is a warning on stderr, the ``μ_c`` row of the summary and ``critical_friction.error`` in
the JSON and in results.h5, and the exit code is the verdict's.

Progress goes to stderr through the ``meicp`` logger, each line stamped with the seconds
since the start of the run: an estimate of the run's memory and time from the size model
(:func:`meicp.lattice.size.typical_cost`), then the phases of this command and of the
analysis, shown by default (INFO), and within a long phase a line every few seconds
(:mod:`meicp.core.progress`); ``-q`` shows warnings only, ``-vv`` adds debug output.

Exit codes: 0 the analysis answered (stable, unstable, undecided with ``success``, or a
modal analysis) — unstable also when a certified flutter mode decides it while the
divergence search was inconclusive (the divergence row says so); 1 it failed
(``result.success`` is False: nothing decided the verdict, or a solver raised), 2 bad input,
3 an internal error.
"""

from __future__ import annotations

import dataclasses
import logging
import os
import time
from pathlib import Path

from ..contact.critical_friction import critical_friction
from ..contact.instability import analyze
from ..contact.modal import has_contact
from ..contact.problem import needs_static
from ..contact.result import seconds
from ..core.errors import MeicpError, ProblemError
from ..core.json_values import json_ready
from ..core.log import configure_logging, rank0_print
from ..io.results import critical_friction_record, versions, write_results
from ..io.scene import load_scene, read_scene_text
from ..lattice.size import typical_cost
from ..petsc.options import report_not_offered
from ..petsc.stages import stage
from .arguments import cli_spelling, finite, integer, output_directory, verbosity, verbosity_of
from .exit import Exit
from .output import json_header, print_json

#: what ``--method`` may choose: the MEiCP methods :func:`analyze` decides with
METHODS = ("auto", "enumerate", "active-set")

log = logging.getLogger("meicp")


def register(sub) -> None:
    p = sub.add_parser("solve", help="stability of a scene: contact states, divergence modes, "
                                     "verdict; writes HDF5 + XDMF + PNG",
                       description="Decide whether a scene's lattice is stable in its contact state "
                                   "(MEiCP on PETSc/SLEPc) and write the results.")
    p.add_argument("scene", help="scene file (TOML)")
    p.add_argument("-o", "--output", metavar="DIR", type=output_directory,
                   help="output directory, created if missing (default: out/<scene stem>)")
    p.add_argument("--no-output", action="store_true", help="print the summary only, write no files")
    p.add_argument("--json", action="store_true",
                   help="print one JSON document (verdict, modes, μ_c, outputs, timings, versions) instead "
                        "of the summary; nothing else goes to stdout")
    p.add_argument("--critical-friction", action="store_true",
                   help="also compute the critical friction: the onsets of divergence (μ_c, a σ = 0 mode) and "
                        "of flutter (μ_f, a non-real σ of steady sliding; not with --no-flutter), each a certified "
                        "bracket, and which instability starts first (docs/critical-friction.md)")
    p.add_argument("--method", choices=METHODS,
                   help="MEiCP method (default: the scene's [solver] method; auto = enumerate when small)")
    p.add_argument("--target", type=finite,
                   help="shift of the active-set search's SLEPc solves (default: the certified top of the σ-window, "
                        "or 1.25× the contact-strip proxy's rightmost real σ for the first search)")
    p.add_argument("--nev", type=integer(1),
                   help="eigenpairs per SLEPc solve of the last divergence search, made only when the "
                        "searches following one eigenpair found nothing; the vibration modes of a scene "
                        "without contact (default: the scene's [solver] nev, else 1 / 6)")
    p.add_argument("--flutter-dense-max", type=integer(0), metavar="N",
                   help="retained DOFs up to which flutter takes the dense path: every eigenvalue, the "
                        "fastest growth proved, absence provable (default 2500; O(n³): ~1 min at 3,300)")
    p.add_argument("--no-flutter", action="store_true",
                   help="skip the flutter analysis of steady sliding (complex σ; docs/flutter.md): "
                        "flutter stays undecided, so the verdict cannot be STABLE")
    verbosity(p)
    p.set_defaults(run=run)


class _ElapsedFormatter(logging.Formatter):
    def __init__(self, t0: float):
        super().__init__("meicp [%(elapsed)8.2f s] %(message)s")
        self.t0 = t0

    def format(self, record):
        record.elapsed = time.perf_counter() - self.t0
        return super().format(record)


def _configure_progress(args, t0: float):
    """Show INFO (phases) by default for this command; return a function that undoes it."""
    logger = logging.getLogger("meicp")
    old_level = logger.level
    verbose, quiet = verbosity_of(args)
    if quiet:
        logger.setLevel(logging.DEBUG if verbose >= 2 else logging.WARNING)
    else:
        logger.setLevel(logging.DEBUG if verbose >= 2 else logging.INFO)
    ours = [h for h in logger.handlers if getattr(h, "_meicp", False)]
    if not ours:  # run() called without main(): give it the same rank-0 handler
        configure_logging(0)
        logger.setLevel(logging.DEBUG if verbose >= 2 else logging.WARNING if quiet else logging.INFO)
        ours = [h for h in logger.handlers if getattr(h, "_meicp", False)]
    old = [(h, h.formatter) for h in ours]
    for h in ours:
        h.setFormatter(_ElapsedFormatter(t0))

    def restore():
        logger.setLevel(old_level)
        for h, f in old:
            h.setFormatter(f)

    return restore


def _check_output_dir(out: Path) -> None:
    """Fail before the solve if DIR cannot be created or written (nothing is created here)."""
    probe = out
    while not probe.exists():
        if probe.parent == probe:
            break
        probe = probe.parent
    if probe.exists() and not probe.is_dir():
        raise ProblemError(f"output path {str(probe)!r} exists and is not a directory")
    if not os.access(probe, os.W_OK | os.X_OK):
        raise ProblemError(f"output directory {str(out)!r} cannot be written "
                           f"({str(probe)!r} is not writable)")


def summary_rows(scene, result, *, ranks: int = 1) -> list[tuple[str, str]]:
    """The (key, text) rows of the summary (:meth:`InstabilityResult.summary_rows`), its
    messages' keyword hints spelt as this command's flags (--method enumerate), the scene's
    title on one line of at most 80 characters (results.h5 keeps it whole)."""
    if scene.title != _shortened(scene.title):
        scene = dataclasses.replace(scene, title=_shortened(scene.title))
    return [(key, cli_spelling(text)) for key, text in result.summary_rows(scene, ranks=ranks)]


def overrides(args) -> dict:
    """The solver settings given on the command line (``--method``, ``--target``, ``--nev``,
    ``--no-flutter`` as ``flutter = False``)."""
    given = {name: getattr(args, name) for name in ("method", "target", "nev", "flutter_dense_max")
             if getattr(args, name, None) is not None}
    if getattr(args, "no_flutter", False):
        given["flutter"] = False
    return given


def solve_json(args, scene, result, *, ranks: int, mu_c=None, files=None, wall=None, out=None,
               mu_c_error: str | None = None) -> dict:
    """The document ``meicp solve --json`` prints, JSON-ready: the header
    (:func:`~meicp.cli.output.json_header`), the run (scene, ranks, the command line's
    overrides), the result keyed like its attributes (:meth:`InstabilityResult.to_dict`;
    messages with this command's flags), the critical friction (None when not asked;
    ``{"error": why}`` when it failed; else ``value``, ``found``, ``lower``, ``upper``,
    ``exact``, ``evidence``, an infinite end as ``null`` with ``<key>_infinite: 1`` where
    results.h5 stores the float inf: ``value`` when no σ = 0 mode was found, ``lower`` too
    when none exists at any μ), the output files, the wall-clock timings of this command and
    the versions of the stack."""
    doc = {**json_header("solve"),
           "scene": {"path": str(args.scene), "title": scene.title, "nx": scene.nx, "ny": scene.ny,
                     "dofs": scene.n_dofs},
           "ranks": ranks, "overrides": overrides(args)}
    data = result.to_dict()
    for key in ("message", "evidence", "flutter_evidence"):
        data[key] = cli_spelling(data[key])
    doc.update(data)
    if mu_c is None:
        doc["critical_friction"] = None if mu_c_error is None else {"error": mu_c_error}
    else:  # an infinite end keeps its meaning (no mode found / none at any μ) through its flag
        doc["critical_friction"] = critical_friction_record(mu_c)
    doc["output"] = None if out is None else {"directory": str(out), **{k: str(v) for k, v in (files or {}).items()}}
    doc["wall"] = dict(wall or {})
    doc["versions"] = versions()
    return json_ready(doc)


def critical_friction_rows(mu_c) -> list[tuple[str, str]]:
    """The summary's rows of the critical friction: the first onset, then each onset's bracket
    and evidence (divergence alone with ``--no-flutter``)."""
    if mu_c.flutter is None:
        return [("μ_c", mu_c.describe()), ("", f"  {mu_c.evidence}")]
    return [("μ_c", mu_c.describe()),
            ("  divergence", mu_c.divergence.describe("σ = 0 mode")), ("", f"  {mu_c.divergence.evidence}"),
            ("  flutter", mu_c.flutter.describe("flutter mode")), ("", f"  {mu_c.flutter.evidence}")]


def format_rows(rows) -> str:
    width = max(len(k) for k, _ in rows)
    return "\n".join(f"{k:<{width}}  {v}".rstrip() for k, v in rows)


def run(args) -> int:
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    t0 = time.perf_counter()
    restore = _configure_progress(args, t0)
    try:
        return _run(args, comm, t0)
    finally:
        restore()


def _run(args, comm, t0) -> int:
    wall = {}
    log.info(f"loading scene {args.scene}")
    scene = load_scene(args.scene)  # ProblemError (exit 2) on every rank alike, before any work
    try:
        scene_text = read_scene_text(args.scene)  # bounded, as load_scene read it
    except ProblemError:
        scene_text = None
    out = None
    if args.no_output and args.output:
        raise ProblemError(f"--no-output and -o {args.output} ask for opposite things: give one of them")
    if not args.no_output:
        out = Path(args.output) if args.output else Path("out") / Path(args.scene).stem
        _check_output_dir(out)
    log.info(f"scene: {_shortened(scene.title) or Path(args.scene).stem}, {scene.nx} × {scene.ny} nodes, "
             f"{scene.n_dofs:,} DOFs, {comm.Get_size()} rank(s)")
    log.info(typical_cost(scene, comm.Get_size(), static=needs_static(scene)).describe())
    wall["load"] = time.perf_counter() - t0

    log.info("analysis: started")
    t1 = time.perf_counter()
    try:
        result = analyze(scene, comm=comm, scene_path=args.scene, **overrides(args))
    except ProblemError as exc:  # its hints spelt as this command's flags: --method auto
        raise ProblemError(cli_spelling(str(exc))) from None
    wall["analyze"] = time.perf_counter() - t1
    log.info(f"analysis: done in {seconds(wall['analyze'])} ({result.status})")

    rows = summary_rows(scene, result, ranks=comm.Get_size())
    mu_c, files, mu_c_failed = None, {}, None
    if args.critical_friction and not has_contact(scene):
        rows.append(("μ_c", "not applicable: the scene has no contact, hence no friction"))
    elif args.critical_friction:
        log.info("critical friction: μ as the eigenvalue at σ = 0, condensed onto the contact DOFs "
                 "(enumerated up to 20 pairs, bracketed beyond)")
        t3 = time.perf_counter()
        try:
            with stage("critical_friction"):
                # collective; the enumeration alike on every rank; --no-flutter skips the flutter onset too
                mu_c = critical_friction(scene, comm=comm, flutter=False if args.no_flutter else None)
        except MeicpError as exc:  # an extra: the verdict is done and stands, with its files and exit code
            mu_c_failed = cli_spelling(str(exc))
            log.warning(f"μ_c not determined: {mu_c_failed}")
            rows.append(("μ_c", f"not determined: {mu_c_failed}"))
        else:
            rows += critical_friction_rows(mu_c)
        wall["critical_friction"] = time.perf_counter() - t3
    if out is not None:
        log.info(f"writing results to {out}/")
        t2 = time.perf_counter()
        try:
            record = {"error": mu_c_failed} if mu_c_failed else None if mu_c is None else critical_friction_record(mu_c)
            files = write_results(out, scene, result, comm=comm, scene_text=scene_text, critical_friction=record,
                                  overrides=overrides(args))
        except BaseException:
            if not args.json:
                rank0_print(format_rows(rows + [("outputs", "not written (error below)")]))
            raise
        wall["write"] = time.perf_counter() - t2
        log.info(f"writing: done in {seconds(wall['write'])}")
        rows.append(("outputs", f"{out}/  (open {files['xdmf'].name} in ParaView)"))
        rows += [("", f"  {path.name:<16} {_DESCRIBE.get(key, '')}") for key, path in files.items()]
    report_not_offered(scene.petsc)
    wall["total"] = time.perf_counter() - t0
    rows.append(("wall", ", ".join(f"{k} {seconds(v)}" for k, v in wall.items())))
    if args.json:
        doc = solve_json(args, scene, result, ranks=comm.Get_size(), mu_c=mu_c, files=files, wall=wall, out=out,
                         mu_c_error=mu_c_failed)
        print_json(doc)
    else:
        rank0_print(format_rows(rows))
    # every rank leaves together: mpirun aborts the job as soon as one rank exits non-zero,
    # which could cut rank 0's summary short after a failed (exit 1) analysis
    comm.Barrier()
    return Exit.OK if result.success else Exit.FAILED


def _shortened(text: str, limit: int = 80) -> str:
    """A scene's title on one progress line: a 3 MB title is legal in a scene file."""
    text = " ".join(text.split())
    return text if len(text) <= limit else text[:limit - 1] + "…"


_DESCRIBE = {"results": "scene, versions, states, forces, modes, certificates, timings",
             "lattice": "lattice + mode shapes + contact states (HDF5)",
             "xdmf": "ParaView/meshio entry point for lattice.h5",
             "mode_png": "fastest divergence mode found, on the deformed lattice",
             "flutter_png": "fastest flutter mode (real part of its complex shape; both parts in the XDMF)",
             "contacts_png": "contact states and forces along each contact line"}
