"""Damping on 2 ranks: C distributed as K is, identical to the serial one; the damped
verdict the same on one and two ranks (the dense references run on rank 0, broadcast)."""

import numpy as np
import pytest

import meicp
from meicp.io.scene import load_scene, scene_from_dict
from meicp.lattice.model import LatticeModel
from meicp.petsc.assembly import assemble_damping

from .test_damping import INTERFACE, TWO_LAYERS, damped
from .test_lattice import SCENES

pytestmark = pytest.mark.mpi(min_size=2)


def _damped_embedded():
    d = load_scene(SCENES / "embedded_layer.toml").to_dict()
    for k, layer in enumerate(d["layers"]):
        layer["viscosity"] = 0.01 * (k + 1)
    d["embedded"][0]["viscosity"] = 0.2
    d["damping"] = {"mass": 0.05}
    return scene_from_dict(d)


@pytest.mark.parametrize("name", ["two_layers", "embedded"])
def test_distributed_damping_equals_serial(comm, name):
    from meicp.petsc.mat import mat_to_scipy

    scene = damped(TWO_LAYERS, eta=(0.02, 0.1), mass=0.3) if name == "two_layers" else _damped_embedded()
    model = LatticeModel(scene)
    C = assemble_damping(scene, comm)
    try:
        j0, j1 = model.row_band(comm.rank, comm.size)
        assert C.getOwnershipRange() == model.dof_range(j0, j1)
        Cs = assemble_damping(scene)
        assert abs(mat_to_scipy(C) - Cs).max() == 0
        info = C.getInfo(C.InfoType.LOCAL)
        assert info["mallocs"] == 0
    finally:
        C.destroy()


@pytest.mark.parametrize("scene", [damped(TWO_LAYERS, eta=(0.02, 0.02)), damped(INTERFACE, eta=(0.02, 0.05))],
                         ids=["two_layers", "interface"])
def test_the_damped_verdict_is_the_same_on_one_and_two_ranks(comm, scene):
    from mpi4py import MPI

    two = meicp.analyze(scene, comm=comm)
    one = meicp.analyze(scene, comm=MPI.COMM_SELF)
    assert (two.divergence, two.flutter, two.stable) == (one.divergence, one.flutter, one.stable)
    assert [m.sigma for m in two.modes] == pytest.approx([m.sigma for m in one.modes], rel=1e-12)
    assert [m.sigma for m in two.flutter_modes] == pytest.approx([m.sigma for m in one.flutter_modes], rel=1e-12)
    assert two.flutter_growth.lower == pytest.approx(one.flutter_growth.lower, rel=1e-12)
    assert np.allclose(comm.bcast(two.flutter_growth.lower, root=0), two.flutter_growth.lower)


def test_the_damped_flutter_search_is_the_same_on_one_and_two_ranks(comm):
    """The search past the dense limit (companion shift-and-invert, distributed factor and
    Krylov basis) certifies the same modes on 2 ranks as on one."""
    from mpi4py import MPI

    from .test_damped_search import SCENES

    scene = SCENES["interface"]
    two = meicp.analyze(scene, comm=comm, flutter_dense_max=10)
    one = meicp.analyze(scene, comm=MPI.COMM_SELF, flutter_dense_max=10)
    assert two.flutter is True and one.flutter is True
    assert "companion form" in two.flutter_evidence
    lam_one = np.array([np.sqrt(m.sigma) for m in one.flutter_modes])
    for m in two.flutter_modes:  # the same eigenvalues (a Krylov run may converge a different subset)
        assert np.min(np.abs(lam_one - np.sqrt(m.sigma))) <= 1e-10 * abs(m.sigma) ** 0.5
    assert two.flutter_modes[0].growth_rate == pytest.approx(one.flutter_modes[0].growth_rate, rel=1e-10)
    assert comm.bcast(two.flutter_growth.lower, root=0) == two.flutter_growth.lower


def test_the_damped_critical_friction_is_the_same_on_one_and_two_ranks(comm):
    """Both onsets of a damped interface (the cover on rank 0, broadcast; the condensations
    distributed) on 2 ranks as on one, and every rank holds the same answer."""
    from mpi4py import MPI

    scene = damped(INTERFACE, eta=(0.02, 0.02))
    two = meicp.critical_friction(scene, comm=comm)
    one = meicp.critical_friction(scene, comm=MPI.COMM_SELF)
    assert two.flutter.exact and "companion form" in two.flutter.evidence
    assert (two.flutter.lower, two.flutter.upper) == (one.flutter.lower, one.flutter.upper)
    assert (two.divergence.lower, two.divergence.upper) == (one.divergence.lower, one.divergence.upper)
    assert comm.allgather(float(two)) == [float(two)] * comm.size


def test_followed_damped_divergence_modes_are_the_same_on_one_and_two_ranks(comm, monkeypatch):
    """Past the enumeration (its limit lowered on both ranks) the undamped mode of the
    distributed pencil, followed to the damped problem (a distributed ZMUMPS factor), is the
    same certified mode on 2 ranks as on one."""
    from mpi4py import MPI

    from meicp.core import limits

    monkeypatch.setattr(limits, "ENUMERATE_N", 5)
    scene = damped(TWO_LAYERS, eta=(0.1, 0.01))
    two = meicp.analyze(scene, comm=comm, flutter=False)
    one = meicp.analyze(scene, comm=MPI.COMM_SELF, flutter=False)
    assert two.divergence is True and one.divergence is True
    assert two.proofs[0].test == one.proofs[0].test == "quadratic-followed"
    assert two.modes[0].sigma == pytest.approx(one.modes[0].sigma, rel=1e-10)
    assert comm.allgather(two.modes[0].sigma) == pytest.approx([two.modes[0].sigma] * comm.size, rel=0)


@pytest.mark.parametrize("viscosity, mass, divergence", [((0.02, 0.1), 0.01, True), ((0.05, 0.25), None, False)],
                         ids=["a mode", "stable"])
def test_the_proportional_damped_verdict_is_the_same_on_one_and_two_ranks(comm, viscosity, mass, divergence):
    """Past the enumeration (720 DOFs, 60 sliding contacts) damping proportional to stiffness
    decides the damped divergence by the undamped verdict of the distributed pencil, its mode
    certified on the distributed quadratic pencil: the same on 2 ranks as on one."""
    from mpi4py import MPI

    from meicp.contact.damped_proportional import TEST
    from meicp.examples import two_layer_scene

    base = (two_layer_scene(60, (3, 3), mu=3.0, states="slip+", shear=0.2) if divergence
            else two_layer_scene(40, (3, 3), mu=2.0, states="slip-", shear=-0.3))
    scene = damped(base, eta=viscosity, mass=mass)
    two = meicp.analyze(scene, comm=comm, flutter=False)
    one = meicp.analyze(scene, comm=MPI.COMM_SELF, flutter=False)
    assert two.divergence is divergence and one.divergence is divergence
    assert two.proofs[0].test == one.proofs[0].test == TEST
    assert [m.sigma for m in two.modes] == pytest.approx([m.sigma for m in one.modes], rel=1e-10)
    assert comm.allgather(two.divergence) == [divergence] * comm.size


def test_the_proportional_damped_flutter_search_is_the_same_on_one_and_two_ranks(comm):
    """η ∝ k past the dense limit: the undamped search at σ(λ₀) (distributed factor and basis),
    its modes certified on the distributed quadratic pencil, as on one rank."""
    from mpi4py import MPI

    from .test_damped_proportional import SEARCHED

    scene = SEARCHED["base"]
    two = meicp.analyze(scene, comm=comm, flutter_dense_max=10)
    one = meicp.analyze(scene, comm=MPI.COMM_SELF, flutter_dense_max=10)
    assert two.flutter is True and one.flutter is True and "so the undamped search ran" in two.flutter_evidence
    lam_one = np.array([np.sqrt(m.sigma) for m in one.flutter_modes])
    for m in two.flutter_modes:
        assert np.min(np.abs(lam_one - np.sqrt(m.sigma))) <= 1e-10 * abs(m.sigma) ** 0.5
    assert two.flutter_modes[0].growth_rate == pytest.approx(one.flutter_modes[0].growth_rate, rel=1e-10)
    assert comm.bcast(two.flutter_growth.lower, root=0) == two.flutter_growth.lower


def test_the_damped_flutter_free_proof_is_the_same_on_one_and_two_ranks(comm):
    """Past the dense limit (5,400 retained DOFs) a shallow lattice with mass damping at small
    μ is proved stable: the bounds on every rank alike, the inertia distributed."""
    from mpi4py import MPI

    from .test_damped_flutter_free import SHALLOW

    scene = damped(SHALLOW, mass=0.1)
    two = meicp.analyze(scene, comm=comm)
    one = meicp.analyze(scene, comm=MPI.COMM_SELF)
    assert two.stable is True and one.stable is True
    assert "no eigenvalue grows (a proof)" in two.flutter_evidence
    assert comm.allgather(two.stable) == [True] * comm.size


def test_the_condensed_lambda_windows_on_two_ranks(comm):
    """The damped λ-windows (one MUMPS Schur series over both ranks, the certificates on rank 0)
    prove what they prove on one rank, with the same windows."""
    from mpi4py import MPI

    from meicp.contact.damped_windows import prove_no_damped_divergence
    from meicp.contact.problem import pencil
    from meicp.examples import two_layer_scene

    scene = damped(two_layer_scene(30, (6, 6), bottom="fixed", stiffness=(1.0, 4.0), density=(1.0, 2.0),
                                   interface={"kind": "frictional", "friction": 1.0, "states": "slip+"}),
                   eta=(0.02, 0.02))
    with pencil(scene, comm=comm) as pen:
        two = prove_no_damped_divergence(pen, comm)
    with pencil(scene, comm=MPI.COMM_SELF) as pen:
        one = prove_no_damped_divergence(pen, MPI.COMM_SELF)
    assert two.proved and one.proved
    assert [w[:2] for w in two.windows] == [w[:2] for w in one.windows]


def test_the_lambda_windows_over_mu_on_two_ranks(comm):
    """The λ-windows carried over μ (one MUMPS Schur series over both ranks, the μ intervals on
    rank 0) reach what they reach on one rank, below the first damped mode (6.7053–6.7063,
    tests/test_damped_mu_windows.py), the same on every rank."""
    from mpi4py import MPI

    from meicp.contact.damped_mu_windows import prove_up_to
    from meicp.contact.problem import pencil

    from .test_damped_mu_windows import SIX

    reach = {}
    for name, c in (("two", comm), ("one", MPI.COMM_SELF)):
        with pencil(SIX.with_friction(1.0), comm=c) as unit:
            reach[name] = prove_up_to(unit, 2.357, 6.7082039, c).reach
    assert 6.69 < reach["two"] < 6.7053 and 6.69 < reach["one"] < 6.7053
    assert reach["two"] == pytest.approx(reach["one"], rel=1e-3)
    assert comm.allgather(reach["two"]) == [reach["two"]] * comm.size


@pytest.mark.parametrize("mu, tau", [(3.0, 0.0), (0.5, 0.0)])
def test_a_scipy_pencils_bound_factored_over_two_ranks_is_the_serial_one(comm, mu, tau):
    """The critical friction's SciPy pencils (every rank holding them) get their Rayleigh
    bounds factored over the ranks, node by node: the same proof and the same count as on one
    process, on every rank (at 10⁶ DOFs each rank factored the whole pencil alone)."""
    from mpi4py import MPI

    from meicp.contact.problem import pencil
    from meicp.contact.rayleigh import pencil_bound, rayleigh_bound
    from meicp.examples import two_layer_scene

    with pencil(two_layer_scene(30, (3, 3), mu=mu, states="slip+", shear=0.5), comm=MPI.COMM_SELF) as pen:
        alone = rayleigh_bound(pen.A, pen.B, tau, decisive=False)
        shared = pencil_bound(pen, tau, comm)
    assert (shared.proved, shared.above) == (alone.proved, alone.above)
    assert comm.allgather((shared.proved, shared.above)) == [(alone.proved, alone.above)] * comm.size
