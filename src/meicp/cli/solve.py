"""``meicp solve SCENE.toml [-o DIR] [--no-output] [-q] [-- PETSc options]``.

Loads the scene (a bad scene fails before any work, exit 2), runs
:func:`meicp.contact.instability.analyze` on every rank of ``MPI.COMM_WORLD``, prints a
summary (stdout, rank 0) and writes ``results.h5``, ``lattice.h5`` + ``lattice.xdmf`` and the
PNGs to DIR (default ``out/<scene stem>``; see :mod:`meicp.io.results`).

Progress goes to stderr through the ``meicp`` logger, each line stamped with the seconds
since the start of the run: the phases of this command and of the analysis are shown by
default (INFO), ``-q`` shows warnings only, ``-vv`` adds debug output.

Exit codes: 0 the analysis answered (stable, unstable or undecided with ``success``), 1 it
failed (``result.success`` is False, or a solver raised), 2 bad input.
"""

from __future__ import annotations

import logging
import os
import time
from collections import Counter
from pathlib import Path

import numpy as np

from ..core.errors import ProblemError
from ..core.log import rank0_print
from .main import EXIT_FAILED, EXIT_OK

log = logging.getLogger("meicp")
#: one character per contact state, for the compact per-column strip of the summary
GLYPHS = {"stick": "|", "slip+": ">", "slip-": "<", "separated": "o", "grazing": "~"}
#: show the per-column strip up to this many columns
STRIP_MAX = 100


def register(sub) -> None:
    p = sub.add_parser("solve", help="stability of a scene: contact states, divergence modes, "
                                     "verdict; writes HDF5 + XDMF + PNG",
                       description="Decide whether a scene's lattice is stable in its contact state "
                                   "(MEiCP on PETSc/SLEPc) and write the results.")
    p.add_argument("scene", help="scene file (TOML)")
    p.add_argument("-o", "--output", metavar="DIR",
                   help="output directory, created if missing (default: out/<scene stem>)")
    p.add_argument("--no-output", action="store_true", help="print the summary only, write no files")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress lines, only the summary")
    p.add_argument("--critical-friction", action="store_true",
                   help="also compute μ_c, the smallest friction with a divergence mode (small scenes: enumeration)")
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
    verbose = getattr(args, "verbose", 0) or 0
    if args.quiet:
        logger.setLevel(logging.DEBUG if verbose >= 2 else logging.WARNING)
    else:
        logger.setLevel(logging.DEBUG if verbose >= 2 else logging.INFO)
    ours = [h for h in logger.handlers if getattr(h, "_meicp", False)]
    if not ours:  # run() called without main(): give it the same rank-0 handler
        from ..core.log import configure_logging

        configure_logging(0)
        logger.setLevel(logging.DEBUG if verbose >= 2 else logging.WARNING if args.quiet else logging.INFO)
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


def states_compact(states) -> str:
    """``slip+ ×12, stick ×3`` (in the order of DESIGN §4's table); "unknown" when empty."""
    if not states:
        return "unknown"
    counts = Counter(states)
    order = list(GLYPHS) + sorted(set(counts) - set(GLYPHS))
    return ", ".join(f"{s} ×{counts[s]}" for s in order if counts[s])


def _strip(states) -> str:
    if not states or len(states) > STRIP_MAX:
        return ""
    return "  [" + "".join(GLYPHS.get(s, "?") for s in states) + "]"


def _seconds(t: float) -> str:
    return f"{t * 1e3:.1f} ms" if t < 1 else f"{t:.2f} s"


def summary_rows(scene, result, *, ranks: int = 1) -> list[tuple[str, str]]:
    """The (key, text) rows of the summary; a mode table row has key ``""``."""
    rows = []

    def row(key, value):
        rows.append((key, value))

    name = scene.title or (Path(scene.source).stem if scene.source else "scene")
    row("scene", name + (f"  ({scene.source})" if scene.source else ""))
    sizes = dict(getattr(result, "sizes", None) or {})
    size_text = ", ".join(f"{k} {v:,}" if isinstance(v, int) else f"{k} {v}" for k, v in sizes.items())
    row("lattice", f"{scene.nx} × {scene.ny} nodes, {scene.n_dofs:,} DOFs"
        + (f" ({size_text})" if size_text else "") + f", {ranks} rank{'s' if ranks != 1 else ''}")
    if scene.boundary.bottom == "contact":
        st = list(getattr(result, "states", None) or [])
        row("base", f"{scene.nx} contact nodes, μ = {scene.contact.friction:g}: {states_compact(st)}{_strip(st)}")
    istates = getattr(result, "interface_states", None) or {}
    for itf in scene.frictional_interfaces():
        st = list(istates.get(itf.below) or [])
        row(f"interface {itf.below}", f"{scene.nx} contact pairs, μ = {itf.friction:g}: "
                                      f"{states_compact(st)}{_strip(st)}")
    stable = getattr(result, "stable", None)
    verdict = {True: "STABLE", False: "UNSTABLE"}.get(stable, "UNDECIDED")
    if not getattr(result, "success", False):
        verdict = f"FAILED ({getattr(result, 'status', '?')})" + \
            ("" if stable is None else f", last verdict {verdict}")
    row("verdict", verdict)
    if getattr(result, "evidence", ""):
        row("evidence", result.evidence)
    if getattr(result, "message", "") and result.message != getattr(result, "evidence", ""):
        row("message", result.message)
    modes = list(getattr(result, "modes", None) or [])
    if modes:
        row("modes", f"{len(modes)} certified divergence mode{'s' if len(modes) != 1 else ''} "
                     f"(σ = λ², fastest first)")
        row("", f"  {'#':>3}  {'σ':>14}  {'growth rate λ':>14}  {'support':>8}  {'residual':>9}")
        for k, m in enumerate(modes[:10]):
            sup = int(np.size(getattr(m, "support", ())))
            sup += sum(int(np.size(v)) for v in (getattr(m, "interface_support", None) or {}).values())
            row("", f"  {k:>3}  {m.sigma:>14.8g}  {m.growth_rate:>14.8g}  {sup:>8d}  {m.residual:>9.1e}")
        if len(modes) > 10:
            row("", f"  ... {len(modes) - 10} more (all in results.h5)")
    else:
        row("modes", "none")
    timings = {k: float(v) for k, v in (getattr(result, "timings", None) or {}).items()}
    if timings:
        row("timings", ", ".join(f"{k} {_seconds(v)}" for k, v in timings.items()))
    return rows


def format_rows(rows) -> str:
    width = max(len(k) for k, _ in rows)
    return "\n".join(f"{k:<{width}}  {v}".rstrip() for k, v in rows)


def summary_text(scene, result, *, ranks: int = 1) -> str:
    """The table ``meicp solve`` prints at the end (also usable from Python)."""
    return format_rows(summary_rows(scene, result, ranks=ranks))


def run(args) -> int:
    from mpi4py import MPI

    from ..io.scene import load_scene

    comm = MPI.COMM_WORLD
    t0 = time.perf_counter()
    restore = _configure_progress(args, t0)
    try:
        return _run(args, comm, t0, load_scene)
    finally:
        restore()


def _run(args, comm, t0, load_scene) -> int:
    wall = {}
    log.info(f"loading scene {args.scene}")
    scene = load_scene(args.scene)  # ProblemError (exit 2) on every rank alike, before any work
    try:
        scene_text = Path(args.scene).read_text(encoding="utf-8")
    except OSError:
        scene_text = None
    out = None
    if not args.no_output:
        out = Path(args.output) if args.output else Path("out") / Path(args.scene).stem
        _check_output_dir(out)
    log.info(f"scene: {scene.title or Path(args.scene).stem}, {scene.nx} × {scene.ny} nodes, "
             f"{scene.n_dofs:,} DOFs, {comm.Get_size()} rank(s)")
    wall["load"] = time.perf_counter() - t0

    from ..contact.instability import analyze

    log.info("analysis: started")
    t1 = time.perf_counter()
    result = analyze(scene, comm=comm, scene_path=args.scene)
    wall["analyze"] = time.perf_counter() - t1
    log.info(f"analysis: done in {_seconds(wall['analyze'])} ({getattr(result, 'status', '?')})")

    rows = summary_rows(scene, result, ranks=comm.Get_size())
    if args.critical_friction:
        from ..contact.instability import critical_friction

        log.info("critical friction: μ as the eigenvalue at σ = 0, condensed onto the contact DOFs and enumerated")
        t3 = time.perf_counter()
        mu_c = critical_friction(scene)  # serial and deterministic: every rank computes it alike
        wall["critical_friction"] = time.perf_counter() - t3
        rows.append(("μ_c", f"{mu_c:.10g}  (smallest μ with a σ = 0 divergence mode for these states; "
                             "every support enumerated, certified)" if mu_c < float("inf") else "none up to μ = 1000"))
    if out is not None:
        from ..io.results import write_results

        log.info(f"writing results to {out}/")
        t2 = time.perf_counter()
        try:
            files = write_results(out, scene, result, comm=comm, scene_text=scene_text)
        except BaseException:
            rank0_print(format_rows(rows + [("outputs", "not written (error below)")]))
            raise
        wall["write"] = time.perf_counter() - t2
        log.info(f"writing: done in {_seconds(wall['write'])}")
        rows.append(("outputs", f"{out}/  (open {files['xdmf'].name} in ParaView)"))
        rows += [("", f"  {path.name:<14} {_DESCRIBE.get(key, '')}") for key, path in files.items()]
    wall["total"] = time.perf_counter() - t0
    rows.append(("wall", ", ".join(f"{k} {_seconds(v)}" for k, v in wall.items())))
    rank0_print(format_rows(rows))
    # every rank leaves together: mpirun aborts the job as soon as one rank exits non-zero,
    # which could cut rank 0's summary short after a failed (exit 1) analysis
    comm.Barrier()
    return EXIT_OK if getattr(result, "success", False) else EXIT_FAILED


_DESCRIBE = {"results": "scene, versions, states, forces, modes, certificates, timings",
             "lattice": "lattice + mode shapes + contact states (HDF5)",
             "xdmf": "ParaView/meshio entry point for lattice.h5",
             "mode_png": "fastest mode on the deformed lattice",
             "contacts_png": "contact states and forces along each contact line"}
