import logging
import os
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import settings

ROOT = Path(__file__).resolve().parents[1]
#: the external reference sets the tests read (provenance and licences: tests/data/README.md)
DATA = ROOT / "tests" / "data"


def clean_env() -> dict:
    """The environment for a child ``mpirun``: no inherited MPI singleton state."""
    env = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_", "PMIX_", "PMI_"))}
    env.update(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OMP_NUM_THREADS="1")
    return env


# property tests draw the same examples on every run (CI must not fail on a new draw);
# HYPOTHESIS_PROFILE=explore draws fresh ones, as a search for counterexamples
settings.register_profile("repeatable", derandomize=True)
settings.register_profile("explore", derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "repeatable"))


def run(args, timeout=120, **kw) -> subprocess.CompletedProcess:
    return subprocess.run(args, capture_output=True, text=True, timeout=timeout, env=clean_env(),
                          cwd=ROOT, **kw)


def meicp_cmd() -> list:
    return [sys.executable, "-m", "meicp"]


def mpirun(n: int = 2) -> list:
    return ["mpirun", "-n", str(n), "--oversubscribe"]


@pytest.fixture
def cli(capsys):
    """``meicp ARGS`` in this process: (exit code, stdout, stderr), the logger restored after.
    Not for PETSc options (after ``--``): they would stay in this process's database."""
    from meicp.cli.main import main

    logger = logging.getLogger("meicp")
    level, handlers = logger.level, list(logger.handlers)

    def call(*args):
        code = main([str(a) for a in args])
        out, err = capsys.readouterr()
        return code, out, err

    yield call
    logger.setLevel(level)
    logger.handlers[:] = handlers


@pytest.fixture
def comm():
    from mpi4py import MPI

    return MPI.COMM_WORLD
