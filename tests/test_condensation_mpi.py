"""The condensation and the condensed proofs on 2 ranks: the same answers as serially."""

import numpy as np
import pytest
from mpi4py import MPI

from meicp.contact.condensation import condense, from_bordered_schur, pieces_of
from meicp.contact.divergence.condensed import prove_no_divergence
from meicp.contact.lines import contact_lines
from meicp.contact.maps import reduced_system
from meicp.contact.problem import pencil
from meicp.lattice.assembly import assemble_scipy
from meicp.lattice.model import LatticeModel
from meicp.petsc.schur import dense_schur, mumps_factor

from meicp.examples import two_layer_scene

pytestmark = pytest.mark.mpi(min_size=2)


def test_schur_and_solves_match_dense_on_two_ranks():
    comm = MPI.COMM_WORLD
    scene = two_layer_scene(9, (2, 2), mu=1.3, states="slip-", shear=0.5)
    model = LatticeModel(scene)
    K, M = assemble_scipy(model)
    p = pieces_of(K, M, reduced_system(model, contact_lines(scene, model), ()))
    H = p.H(0.4).toarray()
    J, F = p.J, p.F
    G = H[np.ix_(J, J)] - H[np.ix_(J, F)] @ np.linalg.solve(H[np.ix_(F, F)], H[np.ix_(F, J)])
    Hb, rows = p.bordered(0.4)
    s = from_bordered_schur(p, 0.4, dense_schur(comm, Hb, rows, symmetric=True), 0.0)
    assert np.allclose(s.G(), G, atol=1e-12 * np.abs(G).max())
    c = condense(p, 0.4, mumps_factor(comm), tau=0.05, xi=True)
    assert np.linalg.norm(c.G() - G, 2) <= c.error() < 1e-7


@pytest.mark.parametrize("method", ["schur", "solves"])
def test_proofs_agree_with_serial(method):
    comm = MPI.COMM_WORLD
    for states, mu, proved in [("slip+", 1.0, True), ("slip-", 3.0, False)]:
        scene = two_layer_scene(30, (2, 2), mu=mu, states=states, shear=0.5)
        with pencil(scene, comm=comm) as pen:
            par = prove_no_divergence(comm, pen, 1.0, method=method)
        ser = prove_no_divergence(None, pencil(scene), 1.0, method=method)
        assert par.proved is ser.proved is proved
        assert par.test == ser.test and par.window == ser.window
        assert par.margin == pytest.approx(ser.margin, rel=1e-6, abs=1e-9)
        # the same windows and τ
        assert par.statement.split(";")[0] == ser.statement.split(";")[0]


def test_critical_friction_bracket_on_two_ranks_matches_serial():
    from meicp.contact.critical_friction import critical_friction

    scene = two_layer_scene(30, (2, 2), mu=1.0, states="slip-", shear=0.5)
    par = critical_friction(scene, comm=MPI.COMM_WORLD, flutter=False)
    ser = critical_friction(scene, flutter=False)
    assert par.exact and ser.exact
    assert float(par) == pytest.approx(float(ser), rel=1e-9) and par.lower == pytest.approx(ser.lower, rel=1e-6)


def test_an_error_inside_a_served_condensation_leaves_both_ranks_in_step(monkeypatch):
    """A condensation that raises (on every rank, as a bad input does) ends the proof with
    that error on both ranks, and the next collective call is answered normally — it once
    left rank 0's broadcasts unmatched and the next call hung."""
    from meicp.contact import condenser
    from meicp.contact.critical_friction import critical_friction

    comm = MPI.COMM_WORLD
    scene = two_layer_scene(30, (2, 2), mu=1.0, states="slip+", shear=0.5)
    real_at = condenser.Condenser.at

    def failing_at(self, sigma, **kw):
        if sigma > 0:
            raise ValueError("a condensation that fails")
        return real_at(self, sigma, **kw)

    monkeypatch.setattr(condenser.Condenser, "at", failing_at)
    with pytest.raises(ValueError, match="a condensation that fails"):
        with pencil(scene, comm=comm) as pen:
            prove_no_divergence(comm, pen, 1.0, method="schur")
    monkeypatch.undo()
    cf = critical_friction(two_layer_scene(30, (2, 2), mu=1.0, states="slip-", shear=0.5), comm=comm, flutter=False)
    assert cf.exact and comm.allgather(float(cf))[0] == comm.allgather(float(cf))[1]


@pytest.mark.parametrize("need_tau", [True, False])
def test_a_lattice_not_held_is_refused_on_both_ranks_and_they_stay_in_step(need_tau):
    from meicp.contact.condenser import Condenser

    comm = MPI.COMM_WORLD
    scene = two_layer_scene(6, (2, 2), mu=1.0, states=["slip+"] + ["separated"] * 5, top="free")
    model = LatticeModel(scene)
    with Condenser(comm, reduced_system(model, contact_lines(scene, model), ()), *assemble_scipy(model),
                   method="schur") as cond:
        assert not cond.prepare(need_tau=need_tau) and "not held" in cond.why
    assert comm.allreduce(1) == comm.Get_size()
    held = two_layer_scene(20, (2, 2), mu=1.0, states="slip+", shear=0.5)
    model = LatticeModel(held)
    with Condenser(comm, reduced_system(model, contact_lines(held, model), ()), *assemble_scipy(model),
                   method="schur") as cond:
        assert cond.prepare(need_tau=need_tau) and cond.tau > 0
        assert comm.allreduce(cond.tau, op=MPI.MAX) == comm.allreduce(cond.tau, op=MPI.MIN)
