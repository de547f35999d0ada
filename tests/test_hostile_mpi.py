"""Faults of a running ``meicp solve`` (issue 11, part 2), each as its own ``mpirun`` (or
plain) process with a fault injected by tests/fault_driver.py: SIGINT/SIGTERM to one rank
or to ``mpirun`` while the results are staged or while a rank waits in a collective ends
every rank within seconds and leaves no staging file or directory; an internal error on two
ranks prints one message, once, with the traceback only under ``-v``.  docs/hostile-input.md
lists the cases.  Serial tests: each starts its own ``mpirun`` (as tests/test_cli_solve.py)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from .conftest import ROOT, clean_env, mpirun

DRIVER = ROOT / "tests" / "fault_driver.py"
SCENE = ROOT / "data" / "scenes" / "two_layers.toml"
#: a liveness bound: every case ends within about 2 s of the signal; a hang sits until the
#: driver's 60 s pause is over (and its outcome is then wrong as well)
ENDS_WITHIN = 15.0


def _children(pid: int) -> list[int]:
    out = []
    for status in Path("/proc").glob("[0-9]*/status"):
        try:
            fields = dict(line.split(":\t", 1) for line in status.read_text().splitlines() if ":\t" in line)
        except OSError:
            continue
        if int(fields.get("PPid", "0")) == pid:
            out.append(int(status.parent.name))
    return out


def _rank_pid(launcher: int, rank: int) -> int:
    for pid in _children(launcher):
        try:
            env = Path(f"/proc/{pid}/environ").read_bytes().split(b"\0")
        except OSError:
            continue
        if f"OMPI_COMM_WORLD_RANK={rank}".encode() in env:
            return pid
    raise AssertionError(f"rank {rank} of mpirun {launcher} not found")


def _interrupt(tmp: Path, fault: str, target: str, sig: int, ranks: int = 2, out: Path | None = None) -> dict:
    """Start ``meicp solve`` with ``fault``, wait for its window, send ``sig`` to ``target``
    (``mpirun``, ``rank0``, ``rank1``, or ``process`` for a run without mpirun) and return
    exit code, seconds from the signal to the end, stderr and the output directory."""
    out = out or tmp / "out"
    stderr = tmp / "stderr.txt"
    launcher = mpirun(ranks) if target != "process" else []
    cmd = launcher + [sys.executable, str(DRIVER), fault, "--", "solve", str(SCENE), "-o", str(out), "-q"]
    with open(stderr, "w") as err:
        proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=err, env=clean_env(), cwd=ROOT)
    try:
        deadline = time.monotonic() + 90
        while "fault-driver: ready" not in stderr.read_text():
            assert proc.poll() is None and time.monotonic() < deadline, stderr.read_text()
            time.sleep(0.05)
        time.sleep(0.3)  # the other ranks reach their collective
        pid = proc.pid if target in ("mpirun", "process") else _rank_pid(proc.pid, int(target[-1]))
        t0 = time.monotonic()
        os.kill(pid, sig)
        try:
            code = proc.wait(timeout=ENDS_WITHIN)
        except subprocess.TimeoutExpired:
            code = None
        elapsed = time.monotonic() - t0
    finally:
        if proc.poll() is None:
            for pid in _children(proc.pid):
                try:
                    os.kill(pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
            proc.kill()
            proc.wait()
    return {"code": code, "elapsed": elapsed, "stderr": stderr.read_text(), "out": out}


def _leftovers(out: Path) -> list[str]:
    return sorted(p.name for p in out.parent.rglob(".*")) if out.parent.exists() else []


#: (id, fault, target, signal, exit code (mpirun reports 1 when it was signalled itself))
SIGNAL_CASES = [
    ("sigint-rank1-during-write", "slow-write", "rank1", signal.SIGINT, 130),
    ("sigterm-mpirun-during-write", "slow-write", "mpirun", signal.SIGTERM, 1),
    ("ctrl-c-mpirun-during-write", "slow-write", "mpirun", signal.SIGINT, 1),
    ("sigint-rank1-in-a-collective", "rank0-busy", "rank1", signal.SIGINT, 130),
    ("sigterm-rank0-in-a-collective", "rank0-busy", "rank0", signal.SIGTERM, 143),
    ("sigint-serial-during-write", "slow-write", "process", signal.SIGINT, 130),
]


def _internal_error(verbose: bool) -> subprocess.CompletedProcess:
    args = (["-v"] if verbose else []) + ["solve", str(SCENE), "--no-output", "-q"]
    return subprocess.run(mpirun(2) + [sys.executable, str(DRIVER), "internal-error", "--"] + args,
                          capture_output=True, text=True, timeout=120, env=clean_env(), cwd=ROOT)


@pytest.fixture(scope="module")
def outcomes(tmp_path_factory):
    """Every case of this file, four processes at a time (most of their time is spent
    starting up or in the driver's pause)."""
    def one(case):
        if case in (False, True):
            return f"internal-error-{case}", _internal_error(case)
        tmp = tmp_path_factory.mktemp(case[0])
        if case[0] == "sigterm-mpirun-during-write":  # an earlier run's outputs must survive
            (tmp / "out").mkdir()
            (tmp / "out" / "results.h5").write_bytes(b"earlier run")
        return case[0], _interrupt(tmp, *case[1:4])

    with ThreadPoolExecutor(max_workers=4) as pool:
        return dict(pool.map(one, SIGNAL_CASES + [False, True]))


@pytest.mark.parametrize("name, target, sig, code", [(c[0], c[2], c[3], c[4]) for c in SIGNAL_CASES],
                         ids=[c[0] for c in SIGNAL_CASES])
def test_a_signal_ends_every_rank_promptly_and_leaves_no_staging(outcomes, name, target, sig, code):
    """Before: SIGINT to one rank hung both ranks until killed; SIGTERM or Ctrl-C to mpirun
    during the write left ``.meicp-results.PID.tmp`` behind."""
    r = outcomes[name]
    assert r["code"] is not None, f"still running {ENDS_WITHIN} s after the signal:\n{r['stderr']}"
    assert r["code"] == code and r["elapsed"] < ENDS_WITHIN, r
    assert _leftovers(r["out"]) == [], r
    assert "Traceback" not in r["stderr"] and "interrupted by SIG" in r["stderr"], r["stderr"]
    if name == "sigterm-mpirun-during-write":
        assert (r["out"] / "results.h5").read_bytes() == b"earlier run"
        assert sorted(p.name for p in r["out"].iterdir()) == ["results.h5"]
    else:  # the output directory was created by the run: removed with the staging
        assert not r["out"].exists(), sorted(r["out"].iterdir())


@pytest.mark.parametrize("verbose", [False, True], ids=["quiet", "verbose"])
def test_an_internal_error_on_two_ranks_prints_one_message_once(outcomes, verbose):
    """Before: the traceback was printed by both ranks, always."""
    out = outcomes[f"internal-error-{verbose}"]
    assert out.returncode == 3, out.stderr
    assert out.stderr.count("meicp: internal error: RuntimeError: injected bug") == 1, out.stderr
    assert out.stderr.count("Traceback") == (1 if verbose else 0), out.stderr
    assert ("run with -v for the traceback" in out.stderr) is not verbose
