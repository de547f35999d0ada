"""``meicp sweep SCENE.toml --mu A:B:N | --param KEY --values A:B:N|a,b,c [--out DIR] [--json]
[--no-flutter] [--no-resume] [--per-point-comm auto|split|world] [--method M] [-q]``.

The verdicts of a scene over a range of one parameter (:func:`meicp.study.sweep`): one
``analyze`` per value, shared out over the ranks of ``mpirun``; a line per finished value
on stderr (rank 0; none under ``-q``); a table of the rows and the onsets the grid brackets
on stdout (or, with ``--json``, one JSON document and nothing else).  Writes into DIR
(default ``out/<scene stem>-sweep/``): ``sweep.csv`` (a row per value, written as each
finishes), ``sweep.json`` (the summary) and ``stability_map.png``.  Run again into the same
DIR, it skips the values sweep.csv has for the same scene and options (``--no-resume``
starts over).

Exit codes: 0 every value answered (stable, unstable or undecided with what was proved), 1
some value's analysis failed (its row says why; the others are written), 2 bad input — a
bad key, range or value is refused before any analysis.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ..contact.result import seconds
from ..core import limits
from ..core.errors import ProblemError
from ..core.log import rank0_print
from ..io.scene import load_scene
from ..study.parameters import PARAMETER_HELP, parse_values
from ..study.driver import PER_POINT, sweep
from .arguments import cli_spelling, output_directory, verbosity, verbosity_of
from .output import json_header, print_json
from .exit import Exit
from .solve import METHODS


def values_argument(text: str) -> str:
    """A grid ``A:B:N`` or a comma-separated list, checked here so that a bad one is a usage
    error naming the flag (exit 2) before the scene is read."""
    try:
        parse_values(text)
    except ProblemError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return text


def register(sub) -> None:
    p = sub.add_parser(
        "sweep", help="verdicts over a range of μ (or another parameter): CSV, JSON and a stability map",
        description="Analyse a scene at every value of a parameter (friction by default), the values shared out\n"
                    "over the ranks of mpirun, and write sweep.csv (a row per value, as each finishes), sweep.json\n"
                    "(the summary) and stability_map.png (divergence and flutter growth against the parameter,\n"
                    "their onsets bracketed by the grid: not proofs between grid points).  A run into the same\n"
                    "directory skips the values done for the same scene and options.",
        epilog="parameters (--param):\n" + PARAMETER_HELP, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene", help="scene file (TOML)")
    grid = p.add_mutually_exclusive_group(required=True)
    grid.add_argument("--mu", metavar="A:B:N", type=values_argument,
                      help="friction values (every frictional contact): N from A to B, or a list a,b,c")
    grid.add_argument("--values", metavar="A:B:N", type=values_argument,
                      help="values of --param: N from A to B, or a comma-separated list a,b,c")
    p.add_argument("--param", metavar="KEY", default="friction",
                   help="the parameter --values sets (default friction; the keys are listed below)")
    p.add_argument("-o", "--out", metavar="DIR", type=output_directory,
                   help="output directory, created if missing (default: out/<scene stem>-sweep)")
    p.add_argument("--json", action="store_true",
                   help="print one JSON document (sweep.json with every row) instead of the table")
    p.add_argument("--no-flutter", action="store_true",
                   help="divergence only: flutter stays undecided, so no value can be STABLE")
    p.add_argument("--no-resume", action="store_true", help="start over even if DIR holds this sweep's rows")
    p.add_argument("--per-point-comm", choices=PER_POINT, default="auto",
                   help="split: each rank analyses its own values alone; world: every value on all ranks; "
                        f"auto (default): split below {limits.SWEEP_SPLIT_DOFS:,} DOFs")
    p.add_argument("--method", choices=METHODS, help="MEiCP method (default: the scene's [solver] method)")
    verbosity(p)
    p.set_defaults(run=run)


def run(args) -> int:
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    if args.mu is not None and args.param != "friction":
        raise ProblemError("--mu sets the friction: use --param KEY --values A:B:N for another parameter")
    scene = load_scene(args.scene)  # ProblemError (exit 2) on every rank alike, before any work
    out = Path(args.out) if args.out else Path("out") / f"{Path(args.scene).stem}-sweep"
    _, quiet = verbosity_of(args)
    options = {"method": args.method} if args.method else {}
    if args.no_flutter:
        options["flutter"] = False
    try:
        result = sweep(scene, args.param, args.mu or args.values, out=out, comm=comm, resume=not args.no_resume,
                       progress=not quiet, per_point_comm=args.per_point_comm, **options)
    except ProblemError as exc:
        raise ProblemError(cli_spelling(str(exc))) from None
    if args.json:
        print_json({**json_header("sweep"), **result.to_dict()})
    else:
        rank0_print(table(result))
    comm.Barrier()
    return Exit.FAILED if result.counts["failed"] else Exit.OK


def table(result) -> str:
    """The rows and onsets of a sweep for a person."""
    key = result.parameter
    width = max(len(key), 8)
    lines = [f"{result.scene_name}: {key} — {result.description}; {len(result.rows)} value(s)"
             + (f", {result.resumed} from an earlier run" if result.resumed else ""),
             f"  {key:>{width}}  {'verdict':<9} {'divergence σ':>13} {'flutter growth':>22}  {'time':>9}  status"]
    for r in result.rows:
        div = {True: f"{r.sigma:.6g}" if r.sigma is not None else "yes", False: "no"}.get(r.divergence, "undecided")
        flu = {True: "yes", False: "no"}.get(r.flutter, "undecided")
        if r.flutter and r.flutter_growth is not None:  # "≥": the fastest found, not proved the fastest
            flu = ("≥ " if r.flutter_growth_bound is None else "") + f"{r.flutter_growth:.6g}"
        lines.append(f"  {r.value:>{width}.6g}  {r.verdict:<9} {div:>13} {flu:>22}  {seconds(r.seconds):>9}  "
                     f"{r.status}")
    if any(r.flutter and r.flutter_growth_bound is None for r in result.rows):
        lines.append("  ≥: the fastest flutter mode found, a lower bound (a search sees part of the spectrum)")
    lines += ["  " + result.divergence_onset.describe(), "  " + result.flutter_onset.describe()]
    if result.files:
        lines.append("outputs: " + ", ".join(str(p) for p in result.files.values()))
    return "\n".join(lines)
