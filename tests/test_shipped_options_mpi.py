"""The shipped 10⁶-DOF scene's ``[solver]`` table on 2 ranks (issue 33, deliverable 4): its mode
found by the first search, as on one rank, the same σ — a stopping test that ended the
solve on one rank only would hang the other."""

import dataclasses

import numpy as np
import pytest

from .conftest import ROOT

pytestmark = pytest.mark.mpi(min_size=2)


def test_the_shipped_table_finds_the_same_mode_on_two_ranks(comm):
    import meicp
    from mpi4py import MPI

    scene = meicp.load_scene(ROOT / "data" / "scenes" / "extensive_contact.toml")
    layers = tuple(dataclasses.replace(layer, rows=25) for layer in scene.layers)
    scene = dataclasses.replace(scene, lattice=dataclasses.replace(scene.lattice, nx=100), layers=layers)
    par = meicp.analyze(scene, comm=comm, flutter=False)
    ser = meicp.analyze(scene, comm=MPI.COMM_SELF, flutter=False)
    assert par.divergence is ser.divergence is True
    assert par.proofs[0].sigma_window is None  # the first search found it: no proof, no window spent
    assert abs(par.modes[0].sigma - ser.modes[0].sigma) <= 1e-8 * ser.modes[0].sigma
    sig = comm.allgather(par.modes[0].sigma)
    assert all(np.isclose(s, sig[0], rtol=0, atol=0) for s in sig)
