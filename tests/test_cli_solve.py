"""`meicp solve` as a user runs it: real scenes, 1 and 2 ranks, bad input, exit codes."""

import time

import h5py
import pytest

from .conftest import ROOT, meicp_cmd, mpirun, run

SCENES = ROOT / "data" / "scenes"


def test_solve_two_layers_end_to_end(tmp_path):
    out = run(meicp_cmd() + ["solve", str(SCENES / "two_layers.toml"), "-o", str(tmp_path / "o"), "-q"])
    assert out.returncode == 0, out.stderr
    assert "UNSTABLE" in out.stdout and "0.32905494" in out.stdout
    with h5py.File(tmp_path / "o" / "results.h5") as f:
        assert f["modes/sigma"][0] == pytest.approx(0.3290549424, rel=1e-9)
    assert {p.name for p in (tmp_path / "o").iterdir()} >= {"results.h5", "lattice.xdmf", "mode.png"}


def test_solve_on_two_ranks_prints_once_and_matches(tmp_path):
    out = run(mpirun(2) + meicp_cmd() + ["solve", str(SCENES / "sheared_slip_minus.toml"), "--no-output",
                                          "-q"], timeout=180)
    assert out.returncode == 0, out.stderr
    # one table, from rank 0 (its row, not the word: the scene path printed may contain it)
    assert sum(line.lstrip().startswith("verdict") for line in out.stdout.splitlines()) == 1
    assert "UNSTABLE" in out.stdout and "0.1115197" in out.stdout


@pytest.mark.parametrize("text, words", [
    ("[lattice]\nnx = 4\nbogus = 1\n[[layers]]\nname='A'\nrows=2\nstiffness=1.0\ndensity=1.0\n", "bogus"),
    ("[lattice]\nnx = 4\n[[layers]]\nname='A'\nrows=2\nstiffness=1.0\ndensity=1.0\n"
     "[boundary]\nbottom='contact'\ntop='fixed'\n[contact]\nfriction=-1.0\n", "friction"),
    ("[lattice]\nnxx = 4\n[[layers]]\nname='A'\nrows=2\nstiffness=1.0\ndensity=1.0\n[boundary]\ntop='fixed'\n",
     "unknown key lattice.nxx (did you mean nx?"),
])
def test_bad_scene_on_two_ranks_exits_promptly_once_and_writes_nothing(tmp_path, text, words):
    scene = tmp_path / "bad.toml"
    scene.write_text(text)
    t0 = time.monotonic()
    out = run(mpirun(2) + meicp_cmd() + ["solve", str(scene), "-o", str(tmp_path / "o")], timeout=120)
    assert out.returncode == 2, out.stderr
    assert time.monotonic() - t0 < 60  # a liveness bound: a hang would sit at the 120 s timeout
    assert out.stderr.count("meicp: error:") == 1 and words in out.stderr
    assert not (tmp_path / "o").exists()



@pytest.mark.parametrize("nx, args, words", [
    (5, ["-o", ""], "meicp solve: error: argument -o/--output: an empty path names no directory"),
    (22, ["--method", "enumerate"], "meicp: error: method 'enumerate' visits all 2^|J| supports: |J| = 22"),
    (5, ["--target", "-1e6x"], "meicp solve: error: argument --target: not a number: '-1e6x'"),
    (5, ["--no-output", "-o", "somewhere"], "meicp: error: --no-output and -o somewhere ask for opposite things"),
], ids=["output-empty", "enumerate-22-pairs", "target-garbage", "no-output-with-o"])
def test_bad_flags_on_two_ranks_say_so_once_and_write_nothing(tmp_path, nx, args, words):
    """A usage error was printed by every rank (argparse runs on each), and the enumeration
    of 2^22 supports started (hours).  Now one message from rank 0, exit 2, nothing made."""
    scene = tmp_path / "wide.toml"
    scene.write_text((SCENES / "two_layers.toml").read_text().replace("nx = 5", f"nx = {nx}"))
    output = [] if "-o" in args else ["-o", str(tmp_path / "o")]
    out = run(mpirun(2) + meicp_cmd() + ["solve", str(scene), "-q"] + args + output, timeout=120)
    assert out.returncode == 2, out.stderr
    assert out.stderr.count("error:") == 1 and words in out.stderr, out.stderr
    assert out.stderr.count("usage:") <= 1 and "Traceback" not in out.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["wide.toml"]
