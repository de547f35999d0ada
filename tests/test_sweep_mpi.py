"""``meicp.sweep`` on 2 ranks writes the CSV one rank writes, whether each rank analyses
values of its own or both analyse every value; an error on one rank only ends the sweep on
both (no hang)."""

import csv
import tempfile
from pathlib import Path

import pytest

import meicp
from meicp.study import driver

from .conftest import ROOT

pytestmark = pytest.mark.mpi(min_size=2)
TWO_LAYERS = ROOT / "data" / "scenes" / "two_layers.toml"
#: an odd count: the last round has work for one rank only
MUS = "0.3,1,2,2.5,3"


@pytest.fixture
def shared_dir(comm):
    """One temporary directory for every rank (rank 0's, broadcast)."""
    tmp = tempfile.TemporaryDirectory() if comm.Get_rank() == 0 else None
    path = Path(comm.bcast(tmp.name if tmp else None, root=0))
    yield path
    comm.Barrier()
    if tmp:
        tmp.cleanup()


def _rows(path):
    with open(path, newline="") as f:
        return [{k: v for k, v in row.items() if k != "seconds"} for row in csv.DictReader(f)]


@pytest.mark.parametrize("per_point", ["split", "world"])
def test_two_ranks_write_the_csv_one_rank_writes(comm, shared_dir, per_point):
    par = meicp.sweep(TWO_LAYERS, "friction", MUS, out=shared_dir / per_point, comm=comm, progress=False,
                      per_point_comm=per_point)
    if comm.Get_rank() == 0:
        from mpi4py import MPI

        ser = meicp.sweep(TWO_LAYERS, "friction", MUS, out=shared_dir / "serial", comm=MPI.COMM_SELF, progress=False)
        assert _rows(shared_dir / per_point / "sweep.csv") == _rows(shared_dir / "serial" / "sweep.csv")
        assert ser.rows[0].value == 0.3 and len(ser.rows) == 5
    comm.Barrier()
    assert [r.verdict for r in par.rows] == comm.bcast([r.verdict for r in par.rows], root=0)
    assert par.run["ranks"] == comm.Get_size() and par.run["per_point_comm"] == per_point


def test_split_mode_analyses_each_value_on_its_rank_alone(comm, shared_dir, monkeypatch):
    """Each value's analysis runs on a one-rank communicator: None would be COMM_WORLD (as
    meicp.analyze reads it), every rank in one collective analysis of different scenes — on
    a small scene the answers agree by luck, on a distributed one they mix."""
    real, sizes = driver.analyze, []

    def recording(scene, comm=None, **options):
        sizes.append(None if comm is None else comm.Get_size())
        return real(scene, comm, **options)

    monkeypatch.setattr(driver, "analyze", recording)
    meicp.sweep(TWO_LAYERS, "friction", MUS, out=shared_dir / "split", comm=comm, progress=False,
                per_point_comm="split")
    assert sizes and all(size == 1 for size in sizes)


def test_comm_none_under_mpirun_is_the_world(comm):
    """A sweep on each rank alone would write one directory from every rank."""
    assert meicp.sweep(TWO_LAYERS, "friction", "1", progress=False).run["ranks"] == comm.Get_size()


def test_an_error_on_one_rank_ends_the_sweep_on_every_rank(comm, shared_dir, monkeypatch):
    real = driver.analyze

    def analyze(scene, c=None, **options):
        if comm.Get_rank() == 1 and scene.contact.friction == 1.0:
            raise ValueError("broken on rank 1")
        return real(scene, c, **options)

    monkeypatch.setattr(driver, "analyze", analyze)
    with pytest.raises(RuntimeError, match="friction = 1: ValueError: broken on rank 1"):
        meicp.sweep(TWO_LAYERS, "friction", MUS, out=shared_dir / "e", comm=comm, progress=False)
    if comm.Get_rank() == 0:  # the round before the error is kept: a rerun resumes from it
        assert [r["value"] for r in _rows(shared_dir / "e" / "sweep.csv")] == ["0.3"]
