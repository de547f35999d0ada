"""The frictional-interface path (centre-of-mass coordinates, diagonal B) on 2 ranks: the
same verdict, proof and σ as on one (``MPI.COMM_SELF``)."""

import numpy as np
import pytest
import scipy.sparse as sp

from .conftest import ROOT

pytestmark = pytest.mark.mpi(min_size=2)


@pytest.mark.parametrize("mu, test", [(3.0, "condensed-windows"), (20.0, "certified-mode")])
def test_an_interface_is_decided_alike_on_one_and_two_ranks(comm, mu, test):
    from mpi4py import MPI

    from meicp import analyze
    from meicp.io.scene import loads_scene

    text = (ROOT / "data" / "scenes" / "frictional_interface.toml").read_text()
    scene = loads_scene(text.replace("nx = 10", "nx = 80").replace("friction = 0.5", f"friction = {mu}"))
    par = analyze(scene, comm=comm, method="active-set", flutter=False)
    ser = analyze(scene, comm=MPI.COMM_SELF, method="active-set", flutter=False)
    assert par.divergence == ser.divergence == (mu == 20.0)
    assert par.proofs[0].test == ser.proofs[0].test == test
    assert len(par.modes) == len(ser.modes)
    for a, b in zip(par.modes, ser.modes):
        assert abs(a.sigma - b.sigma) <= 1e-8 * abs(b.sigma)
        assert np.allclose(a.x, b.x, atol=1e-8) and np.array_equal(a.support, b.support)
    assert par.interface_states == ser.interface_states
    sig = comm.allgather([m.sigma for m in par.modes])
    assert all(s == sig[0] for s in sig)


def test_the_interface_pencil_is_the_same_on_two_ranks(comm):
    """B diagonal on both layouts (the reduced DOFs of a pair may sit on two ranks' bands)."""
    import meicp
    from meicp.contact import pencil
    from meicp.petsc.mat import mat_to_scipy

    scene = meicp.load_scene(ROOT / "data" / "scenes" / "frictional_interface.toml")
    serial = pencil(scene)
    with pencil(scene, comm=comm) as par:
        B = sp.csr_matrix(mat_to_scipy(par.B))
        assert abs(B - serial.B).max() == 0
        assert abs(mat_to_scipy(par.A) - serial.A).max() <= 1e-14 * abs(serial.A).max()
        assert (B - sp.diags(B.diagonal())).count_nonzero() == 0 and B.diagonal().min() > 0
