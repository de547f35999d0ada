"""The flutter onset on 2 ranks: the dense bracket (rank 0's, broadcast) and the search's upper
end (collective) are the ones of 1 rank, on every rank."""

from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

import meicp
from meicp.contact.critical_friction import critical_friction
from meicp.core import limits

pytestmark = pytest.mark.mpi(min_size=2)

SCENES = Path(__file__).resolve().parents[1] / "data" / "scenes"


def test_the_dense_flutter_bracket_on_two_ranks_is_the_serial_one():
    comm = MPI.COMM_WORLD
    scene = meicp.load_scene(SCENES / "sheared_slip_minus.toml")
    par = critical_friction(scene, comm=comm, bisection=False)
    ser = critical_friction(scene, bisection=False)
    ends = comm.allgather((par.flutter.lower, par.flutter.upper, par.first, float(par)))
    assert ends[0] == ends[1] == (ser.flutter.lower, ser.flutter.upper, ser.first, float(ser))
    assert par.flutter.exact and par.first == "flutter"


def test_the_searched_upper_end_on_two_ranks_is_the_serial_one(monkeypatch):
    monkeypatch.setattr(limits, "FLUTTER_DENSE_MAX", 10)
    comm = MPI.COMM_WORLD
    scene = meicp.load_scene(SCENES / "two_layers.toml")
    par = critical_friction(scene, comm=comm, bisection=False).flutter
    ser = critical_friction(scene, bisection=False).flutter
    uppers = comm.allgather(par.upper)
    assert uppers[0] == uppers[1] == pytest.approx(ser.upper) and np.isfinite(ser.upper)
    assert par.lower == 0 and not par.exact
