"""``meicp`` entry point.

Everything after ``--`` goes to the PETSc options database (and wins over code defaults
and the scene's ``[petsc]`` table).  Errors are printed once, on rank 0 when every rank
failed alike (an internal error's traceback only with ``-v``); a failure on some ranks only
ends the whole run with ``MPI_Abort`` after a short grace period, so a 2-rank run never
hangs.  SIGINT and SIGTERM end every rank within seconds, leaving no staging file behind
(:mod:`meicp.cli.signals`).

Exit codes: :class:`~meicp.cli.exit.Exit`.  ``meicp --help`` lists them and the PETSc option
prefixes (:data:`meicp.petsc.options.PREFIXES`); at the end of a run every PETSc option no
solver read is reported (:func:`~meicp.petsc.options.report_unused_options`).
"""

from __future__ import annotations

import argparse
import sys
import time
import traceback

from .._version import __version__
from ..core.errors import ConvergenceError, MeicpError, ProblemError
from ..core.log import configure_logging, rank0_print, world_rank
from ..petsc import init
from ..petsc.options import PREFIXES, report_unused_options
from . import eicp, info, lattice, lcp, solve, sweep
from .arguments import Parser, verbosity_of
from .exit import MEANING, Exit
from .output import stdout_for_json
from .signals import interrupted, interrupts_end_the_run, wait_for_the_end

#: the subcommands, each a module with ``register(subparsers)``, in the order of ``--help``
SUBCOMMANDS = (solve, sweep, info, lcp, eicp, lattice)
#: seconds a failing rank waits for the others to fail alike before aborting the job
GRACE_SECONDS = 3.0


def epilog() -> str:
    """The end of ``meicp --help``: PETSc options, their prefixes, the exit codes."""
    width = max(len(p) for p in PREFIXES) + 1
    lines = ["Options after -- go to the PETSc options database (they win over the scene's [petsc]",
             "table), e.g. meicp solve s.toml -- -meicp_as_eps_view; options that no solver read are",
             "reported at the end of the run.  meicp's solvers read them under these prefixes:", ""]
    lines += [f"  -{prefix:<{width}} {what}" for prefix, what in PREFIXES.items()]
    lines += ["", "exit codes:"] + [f"  {int(code)}  {text}" for code, text in MEANING.items()]
    return "\n".join(lines)


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(
        prog="meicp",
        description="Stability of layered elastic lattices in frictional contact (MEiCP/LCP on PETSc/SLEPc).",
        epilog=epilog(), formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version", version=f"meicp {__version__}")
    parser.add_argument("-v", "--verbose", action="count", default=0, help="-v progress, -vv debug")
    parser.add_argument("-q", "--quiet", action="store_true", help="warnings and errors only, no progress lines")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for module in SUBCOMMANDS:
        module.register(sub)
    return parser


def _split_petsc_args(argv: list[str]) -> tuple[list[str], list[str]]:
    if "--" in argv:
        k = argv.index("--")
        return argv[:k], argv[k + 1:]
    return argv, []


def _all_ranks_failed() -> bool:
    """True when every rank reaches this point within the grace period (a collective error)."""
    mpi = sys.modules.get("mpi4py.MPI")
    if mpi is None or not mpi.Is_initialized() or mpi.COMM_WORLD.Get_size() == 1:
        return True
    request = mpi.COMM_WORLD.Ibarrier()
    deadline = time.monotonic() + GRACE_SECONDS
    while time.monotonic() < deadline:
        if request.Test():
            return True
        time.sleep(0.01)
    return False


def main(argv: list[str] | None = None) -> int:
    """Run ``meicp`` with ``argv`` (default: the command line) and return its exit code.
    Under ``--json`` descriptor 1 stays on stderr after the run when ``argv`` is None (the
    program: PETSc prints ``-log_view`` as it finalizes) and is given back otherwise
    (:func:`meicp.cli.output.stdout_for_json`)."""
    program = argv is None
    argv = list(sys.argv[1:] if argv is None else argv)
    own, petsc_args = _split_petsc_args(argv)
    args = build_parser().parse_args(own)
    args.verbose, args.quiet = verbosity_of(args)  # -v/-q before or after the subcommand
    vars(args).pop("verbose_after", None)
    configure_logging(-1 if args.quiet else args.verbose)
    init(petsc_args)
    with stdout_for_json(getattr(args, "json", False), restore=not program), interrupts_end_the_run():
        return _run(args)


def _run(args) -> int:
    """Run the subcommand; report an error once (see the module docstring)."""
    try:
        code = args.run(args)
        report_unused_options()  # PETSc's own bookkeeping, every prefix (rank 0, via the logger)
        return code
    except ProblemError as exc:
        code, text = Exit.BAD_INPUT, f"meicp: error: {exc}"
    except ConvergenceError as exc:
        code, text = Exit.FAILED, f"meicp: failed: {exc}"
    except MeicpError as exc:
        code, text = Exit.FAILED, f"meicp: {exc}"
    except Exception as exc:  # noqa: BLE001 - last resort: report, never hang the other ranks
        code, text = Exit.INTERNAL, f"meicp: internal error: {type(exc).__name__}: {exc}"
        if getattr(args, "verbose", 0):
            text = traceback.format_exc() + text
        else:
            text += " (run with -v for the traceback)"
    if interrupted():  # a signal is ending the run: the error is its consequence
        wait_for_the_end()
    if _all_ranks_failed():
        rank0_print(text, file=sys.stderr)
        return code
    print(f"[rank {world_rank()}] {text}", file=sys.stderr, flush=True)
    sys.modules["mpi4py.MPI"].COMM_WORLD.Abort(code)
    return code  # not reached
