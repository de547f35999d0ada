"""The command line's contract with scripts and people (issue 30): under ``--json`` stdout is
one JSON document whatever PETSc or MUMPS print, every subcommand's document starts with its
format keys; a reader that closes the pipe early ends nothing badly, on one rank or two; and
long phases say where they are on stderr, silent under ``-q``."""

import json
import signal
import subprocess
import sys

import h5py
import numpy as np
import pytest

import meicp
from meicp.cli.output import FORMAT_VERSION
from meicp.core import progress

from .conftest import ROOT, clean_env, meicp_cmd, mpirun, run

SCENES = ROOT / "data" / "scenes"


def _wide(tmp_path, name: str, nx: int = 30):
    """A scene of data/scenes widened to ``nx`` columns: past the enumeration, so that the
    SLEPc search (and, below μ_c, the inertia and the condensed proof) run."""
    path = tmp_path / f"wide_{name}"
    path.write_text((SCENES / name).read_text().replace("nx = 5", f"nx = {nx}"))
    return path


def _seed_lcp(tmp_path):
    """Seed 002's three-node LCP (x = (1, 0, 2)) as an HDF5 problem file."""
    path = tmp_path / "seed.h5"
    with h5py.File(path, "w") as f:
        f["M"], f["q"] = np.array([[2.0, -1, 0], [-1, 2, -1], [0, -1, 2]]), np.array([-2.0, 4, -4])
    return path


def test_json_is_alone_on_stdout_whatever_petsc_and_mumps_print(tmp_path):
    """-log_view, an EPS viewer and MUMPS' own diagnostics printed into the JSON on stdout;
    now they go to stderr (not lost) and stdout parses."""
    out = run(meicp_cmd() + ["solve", str(_wide(tmp_path, "two_layers.toml")), "--json", "--no-output", "-q",
                             "--", "-log_view", "-meicp_as_eps_view", "-meicp_as_st_mat_mumps_icntl_4", "3"])
    assert out.returncode == 0, out.stderr
    doc = json.loads(out.stdout)
    assert doc["format"] == "meicp-solve" and doc["verdict"] == "UNSTABLE"
    for printed in ("Summary of Stages", "EPS Object: (meicp_as_)", "Entering DMUMPS"):
        assert printed in out.stderr, printed


def test_every_subcommands_json_starts_with_its_format_keys(cli, tmp_path):
    """lcp, classify and eicp --json had no format or version keys; info and lattice had no
    --json.  Every document now starts the same way and parses."""
    dat = _seed_lcp(tmp_path)
    pencil = tmp_path / "pencil.h5"
    with h5py.File(pencil, "w") as f:
        f["A"], f["B"] = -np.array([[1.0, 1.0], [1.0, 2.0]]), np.eye(2)
    commands = {"lcp": [dat], "classify": [dat], "eicp": [pencil], "info": [],
                "lattice": [SCENES / "two_layers.toml", "-o", tmp_path / "lattice", "--no-plot"],
                "solve": [SCENES / "two_layers.toml", "--no-output"]}
    for command, args in commands.items():
        code, out, err = cli(command, *args, "--json", "-q")
        assert code == 0, (command, err)
        doc = json.loads(out)
        assert list(doc)[:3] == ["format", "format_version", "meicp_version"], command
        assert (doc["format"], doc["format_version"], doc["meicp_version"]) == \
            (f"meicp-{command}", FORMAT_VERSION, meicp.__version__)
    assert doc["verdict"] == "UNSTABLE"


def _pipe_closed_at_once(cmd) -> tuple[int, str]:
    """Run ``cmd`` with its stdout a pipe whose reader is gone before anything is written
    (``| head -c 10`` at its worst: head has exited): (exit code, stderr)."""
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=clean_env(), cwd=ROOT)
    p.stdout.close()
    try:
        err = p.stderr.read()
        return p.wait(timeout=120), err
    finally:
        p.kill()


@pytest.mark.parametrize("ranks, json_flag", [(1, True), (1, False), (2, True)], ids=["json", "text", "json-2-ranks"])
def test_a_reader_that_closes_the_pipe_ends_the_run_quietly(tmp_path, ranks, json_flag):
    """``meicp solve … --json | head -c 10`` ended in PETSc's SIGPIPE handler, MPI_ABORT and
    exit 59.  Now the rest of the output is dropped, the run ends normally with its verdict's
    code, its files written, and (2 ranks) neither rank hangs."""
    cmd = (mpirun(2) if ranks == 2 else []) + meicp_cmd() + [
        "solve", str(SCENES / "two_layers.toml"), "-o", str(tmp_path / "o"), "-q"] + (["--json"] if json_flag else [])
    code, err = _pipe_closed_at_once(cmd)
    # 2 ranks: mpirun forwards the ranks' stdout, and when it finds the pipe closed it may die
    # of SIGPIPE itself, as any program in a shell pipeline does (status 141 in a shell) —
    # quietly, after the ranks wrote their files (the JSON, which names them, comes last)
    assert code == 0 or (ranks == 2 and code == -signal.SIGPIPE), (code, err)
    for text in ("MPI_ABORT", "Caught signal", "Broken Pipe", "BrokenPipeError", "Traceback"):
        assert text not in err, err
    with h5py.File(tmp_path / "o" / "results.h5") as f:
        assert f.attrs["verdict"] == "unstable"


def test_progress_within_long_phases_on_stderr_and_q_silences_it(cli, monkeypatch, tmp_path):
    """A 10⁶-DOF run printed nothing for 211 s.  With the throttle at 0 every line shows: the
    size estimate, SLEPc's restarts, the condensed proof's windows, the Lemke pivots and SNES
    iterations of an LCP (the static equilibrium's); ``-q`` (``lcp``: no ``-v``) shows none."""
    monkeypatch.setattr(progress, "FIRST", 0.0)
    monkeypatch.setattr(progress, "INTERVAL", 0.0)
    below = _wide(tmp_path, "two_layers_below_mu_c.toml")
    # above μ_c the first search runs (below it the contact-strip proxy has no real σ above 0:
    # no short search is made, docs/benchmarks-notes.md, "no first search without a proxy mode")
    code, out, err = cli("solve", _wide(tmp_path, "two_layers.toml"), "--no-output", "--no-flutter")
    assert code == 0, err
    assert "SLEPc -meicp_as_: restart 1, " in err and "eigenpair(s) converged" in err
    code, out, err = cli("solve", below, "--no-output", "--no-flutter")
    assert code == 0, err
    assert "size: 240 DOFs, a small analysis" in err
    assert "no first search (the contact-strip proxy has no real σ above 0)" in err
    assert "condensed proof: window [0, inf] split; 0 window(s) proved" in err
    assert "condensed proof: window [1, inf] proved" in err
    code, out, err = cli("solve", below, "--no-output", "--no-flutter", "-q")
    assert code == 0 and err == "", err
    # the static equilibrium's LCP: Lemke (condensed) or SNES VI (mixed), as `meicp lcp` runs them
    dat = _seed_lcp(tmp_path)
    for method, line in (("lemke", "Lemke on 3 unknowns: 1 pivots, "), ("newton", "SNES -meicp_lcp_: iteration 1, ")):
        code, out, err = cli("lcp", dat, "--method", method, "-v")
        assert code == 0 and line in err, err
        code, out, err = cli("lcp", dat, "--method", method)
        assert code == 0 and err == "", err


def test_a_size_estimate_scales_the_measured_runs():
    """The up-front estimate: the measured 10⁶-DOF runs at 10⁶ DOFs, more at more DOFs, less
    per rank on more ranks, more with the static equilibrium."""
    from meicp.lattice.size import MEASURED_ANALYSIS, MEASURED_STATIC, typical_cost

    big = meicp.load_scene(SCENES / "extensive_solve.toml")
    assert big.n_dofs == 10 ** 6
    one, two = typical_cost(big, 1), typical_cost(big, 2)
    assert one.seconds == pytest.approx(MEASURED_ANALYSIS[1][0], rel=0.01)
    assert two.bytes == pytest.approx(MEASURED_ANALYSIS[2][1], rel=0.01) and two.seconds < one.seconds
    static = typical_cost(big, 2, static=True)
    assert static.seconds == pytest.approx(sum(x[0] for x in (MEASURED_ANALYSIS[2], MEASURED_STATIC)), rel=0.01)
    assert typical_cost(big, 4).bytes == pytest.approx(two.bytes / 2)
    assert "per rank (at least" in static.describe() and "with the static equilibrium" in static.describe()


def test_the_log_handler_writes_to_the_stderr_of_the_moment(monkeypatch):
    """The handler was bound to sys.stderr at its set-up: a stream replaced and closed since (a
    test's capture) made every later record a "Logging error" on stderr and its line lost, so
    this file's progress test failed when run after tests/test_results.py."""
    import io
    import logging

    from meicp.core.log import configure_logging

    first = io.StringIO()
    monkeypatch.setattr(sys, "stderr", first)
    configure_logging(1)
    first.close()
    now = io.StringIO()
    monkeypatch.setattr(sys, "stderr", now)
    logging.getLogger("meicp").info("written where stderr is now")
    assert "meicp: written where stderr is now" in now.getvalue()
