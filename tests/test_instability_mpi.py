"""The instability analysis on 2 ranks gives the same modes as on 1 (to 1e-8).  The serial
reference is ``comm=MPI.COMM_SELF``: ``meicp.analyze``'s ``comm=None`` is ``MPI.COMM_WORLD``."""

import numpy as np
import pytest

from .conftest import ROOT

pytestmark = pytest.mark.mpi(min_size=2)
SCENES = ROOT / "data" / "scenes"


@pytest.mark.parametrize("name, method", [("two_layers.toml", "enumerate"),
                                          ("sheared_slip_minus.toml", "active-set"),
                                          ("two_layers_below_mu_c.toml", "auto")])
def test_same_modes_on_one_and_two_ranks(comm, name, method):
    from meicp import analyze

    from mpi4py import MPI

    par = analyze(SCENES / name, comm=comm, method=method)
    ser = analyze(SCENES / name, comm=MPI.COMM_SELF, method=method)
    assert par.stable == ser.stable
    assert len(par.modes) == len(ser.modes)
    for a, b in zip(par.modes, ser.modes):
        assert abs(a.sigma - b.sigma) <= 1e-8 * abs(b.sigma)
        assert np.allclose(a.x, b.x, atol=1e-8)
        assert np.array_equal(a.support, b.support)
    # every rank holds the same answer
    sig = comm.allgather([m.sigma for m in par.modes])
    assert all(s == sig[0] for s in sig)


def test_symmetric_pencil_stability_is_proved_by_inertia_on_two_ranks(comm):
    """All contacts sticking: no complementarity, a symmetric pencil; the active-set finds no
    σ ≥ 0 and the LDLᵀ inertia (MUMPS, in parallel) proves that none exists."""
    from meicp import analyze
    from meicp.io.scene import loads_scene

    text = (SCENES / "two_layers.toml").read_text().replace('states = "slip+"', 'states = "stick"')
    from mpi4py import MPI

    for c in (comm, None, MPI.COMM_SELF):
        r = analyze(loads_scene(text), comm=c, method="active-set")
        assert r.stable is True and r.proofs[0].test == "rayleigh-inertia", r.evidence


def test_public_pencil_is_the_same_on_two_ranks(comm):
    """meicp.contact.pencil: PETSc Mats on the lattice's row bands, equal to the SciPy pencil."""
    import meicp
    from meicp.contact import pencil
    from meicp.petsc.mat import mat_to_scipy

    scene = meicp.load_scene(SCENES / "frictional_interface.toml")
    serial = pencil(scene)
    with pencil(scene, comm=comm) as par:
        assert par.distributed and not serial.distributed
        assert (par.J == serial.J).all()
        for a, b in ((par.A, serial.A), (par.B, serial.B)):
            assert abs(mat_to_scipy(a) - b).max() <= 1e-14 * abs(b).max()


@pytest.mark.parametrize("name, stable", [("embedded_layer.toml", True), ("four_node_cell.toml", None)])
def test_modal_analysis_on_two_ranks(comm, name, stable):
    """A scene without contact: the same vibration modes, the same verdict, on 1 and 2 ranks
    (shapes up to sign: an antisymmetric mode's largest entries tie in magnitude; the free
    4-node cell's zero modes span a 3-dimensional space: compared by σ only)."""
    from meicp import analyze

    from mpi4py import MPI

    par, ser = analyze(SCENES / name, comm=comm), analyze(SCENES / name, comm=MPI.COMM_SELF)
    assert par.analysis == ser.analysis == "modal" and par.stable is ser.stable is stable
    assert [m.sigma for m in par.modes] == pytest.approx([m.sigma for m in ser.modes], rel=1e-9, abs=1e-12)
    if stable:
        for a, b in zip(par.modes, ser.modes):
            assert abs(a.x @ b.x) == pytest.approx(1.0, abs=1e-10)


@pytest.mark.parametrize("state, mu, test", [("slip-", 3.0, "certified-mode"),
                                             ("slip-", 1.2, "condensed-windows"),
                                             ("slip+", 1.0, "rayleigh-inertia")])
def test_the_verdict_at_scale_is_the_same_on_one_and_two_ranks(comm, state, mu, test):
    """Past the enumeration budget (60 sliding contacts): the Rayleigh bound, the σ-window
    and its condensed proof, and the search from the window's top give the same verdict,
    proof and σ on 2 ranks as on 1."""
    from meicp import analyze
    from meicp.examples import two_layer_scene

    scene = two_layer_scene(60, (2, 2), mu=mu, states=state, shear=0.5)
    from mpi4py import MPI

    par = analyze(scene, comm=comm, flutter=False)
    ser = analyze(scene, comm=MPI.COMM_SELF, flutter=False)
    assert par.divergence == ser.divergence is not None
    assert par.proofs[0].test == ser.proofs[0].test == test
    assert [m.sigma for m in par.modes] == pytest.approx([m.sigma for m in ser.modes], rel=1e-8)
    if ser.modes:
        assert np.array_equal(par.modes[0].support, ser.modes[0].support)
