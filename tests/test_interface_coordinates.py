"""Frictional interfaces in centre-of-mass / relative coordinates (meicp.contact.maps): B is
diagonal and positive, and the MEiCP — its solutions, supports and mode shapes in natural
numbering — is the one of any other coordinates whose relative rows are ``e_uᵀ − e_lᵀ``
(here the plain ``u_upper = u_lower + d`` of every pair, by a dense inverse)."""

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import meicp
import meicp.contact.maps as maps
from meicp.contact.lines import contact_lines
from meicp.contact.problem import pencil
from meicp.eicp import solve_eicp
from meicp.examples import two_layer_scene
from meicp.io.scene import scene_from_dict
from meicp.lattice.model import LatticeModel

from .helpers import interface_chain_scene

MIXED = ["slip+", "stick", "slip-", "separated", "slip+", "slip-"]
GRAZING = ["grazing", "slip+", "slip-", "stick", "slip+", "slip+"]


def _interface(states, *, sides="free", rows=(2, 3), stiffness=(6.0, 1.0), mu=1.7, nx=6):
    return two_layer_scene(nx, rows, bottom="fixed", sides=sides, stiffness=stiffness, density=(1.0, 2.0),
                           interface={"kind": "frictional", "friction": mu, "states": states})


def _relative_only(model, lines, keep):
    """Reference coordinates: ``u' = S u`` with ``S`` the identity but ``e_uᵀ − e_lᵀ`` in each
    pair's upper rows; ``T = S⁻¹`` dense (valid wherever no upper node alone is held)."""
    S = np.eye(model.n_dofs)
    for line in lines:
        if line.lower is not None:
            for u, lo in zip(line.upper, line.lower):
                S[2 * u, 2 * lo] = S[2 * u + 1, 2 * lo + 1] = -1.0
    return sp.csr_matrix(np.linalg.inv(S)), keep


def _solutions(scene):
    """Every MEiCP solution over every grazing case: (σ, support, unit mode shape)."""
    model = LatticeModel(scene)
    out = []
    for case in maps.grazing_cases(list(contact_lines(scene, model))):
        with pencil(scene, grazing_case=case) as pen:
            r = solve_eicp(pen.A.toarray(), pen.B.toarray(), J=pen.J, method="enumerate", all_solutions=True)
            for s in r.solutions:
                u = pen.maps.Q @ s.x
                u = u / np.linalg.norm(u)
                out.append((s.lam, tuple(s.support), u))
    return sorted(out, key=lambda t: (round(t[0], 7), t[1]))


@pytest.mark.parametrize("states", ["slip+", "slip-", MIXED])
@pytest.mark.parametrize("sides", ["free", "fixed", "fixed_x"])
def test_b_is_diagonal_and_positive_on_an_interface(states, sides):
    with pencil(_interface(states, sides=sides)) as pen:
        B = pen.B.toarray()
        assert np.count_nonzero(B - np.diag(np.diag(B))) == 0  # exactly, not to rounding
        assert np.diag(B).min() > 0 and pen.J.size > 0


def test_a_grazing_interface_couples_only_through_friction():
    """Grazing keeps v_n (a base contact's B has the same μ·e_n entries): the mass part
    Q̃ᵀMQ̃ is still diagonal, and the only off-diagonal entries of B are the slip rows' μ·m."""
    scene = _interface(GRAZING)
    K, M = meicp.assemble(scene)
    for case in maps.grazing_cases(list(contact_lines(scene, LatticeModel(scene)))):
        red = maps.reduced_system(LatticeModel(scene), contact_lines(scene, LatticeModel(scene)), case)
        mass = (red.Q.T @ M @ red.Q).toarray()
        assert np.count_nonzero(mass - np.diag(np.diag(mass))) == 0
        B = (red.P @ M @ red.Q).toarray()
        off = B - np.diag(np.diag(B))
        assert np.allclose(off, (red.friction_rows() @ M @ red.Q).toarray() - np.diag(
            np.diag((red.friction_rows() @ M @ red.Q).toarray())))


@pytest.mark.parametrize("scene", [
    _interface("slip+"), _interface("slip-", sides="fixed"), _interface(MIXED), _interface(GRAZING),
    _interface(["slip-", "slip+", "slip-", "slip+", "slip-"], rows=(3, 2), stiffness=(2.0, 1.0), mu=8.0, nx=5),
    interface_chain_scene(4, 0.8, sides="free"),
], ids=["slip+", "slip-fixed-sides", "mixed", "grazing", "mu8", "chain"])
def test_the_solution_set_is_the_one_of_relative_coordinates(scene, monkeypatch):
    """Same σ, same supports, same mode shapes in natural numbering as with ``u_upper =
    u_lower + d`` (a one-row layer between two interfaces falls back to those coordinates)."""
    new = _solutions(scene)
    monkeypatch.setattr(maps, "interface_transform", _relative_only)
    ref = _solutions(scene)
    assert len(new) == len(ref) > 0
    for (s1, sup1, u1), (s2, sup2, u2) in zip(new, ref):
        assert abs(s1 - s2) <= 1e-9 * max(1.0, abs(s2)) and sup1 == sup2
        assert min(np.linalg.norm(u1 - u2), np.linalg.norm(u1 + u2)) <= 1e-7


def test_the_chain_fallback_keeps_b_non_diagonal():
    with pencil(interface_chain_scene(5, 0.8)) as pen:
        B = pen.B.toarray()
        assert np.count_nonzero(B - np.diag(np.diag(B))) > 0


@pytest.mark.parametrize("state, mirrored", [("slip+", "slip-"), ("slip-", "slip+")])
def test_an_interface_under_a_held_row_is_the_mirrored_base(state, mirrored):
    """A one-row upper layer held at the top: d = −u_lower, the lower layer slides on a rigid
    body — the same σ ≥ 0 as that layer upside down on the rigid base, slip reversed (the
    previous coordinates moved the held row with the lower one)."""
    layer = {"name": "A", "rows": 3, "stiffness": 3.0, "density": 1.0}
    held = scene_from_dict({"lattice": {"nx": 5}, "layers": [layer, {"name": "B", "rows": 1, "stiffness": 1.0,
                                                                     "density": 2.0}],
                            "boundary": {"top": "fixed", "bottom": "fixed", "left": "free", "right": "free"},
                            "interfaces": [{"below": "A", "kind": "frictional", "friction": 2.5, "states": state}]})
    base = scene_from_dict({"lattice": {"nx": 5}, "layers": [layer],
                            "boundary": {"top": "fixed", "bottom": "contact", "left": "free", "right": "free"},
                            "contact": {"friction": 2.5, "states": mirrored}})
    got = [(s, u) for s, _, u in _solutions(held) if s >= -1e-12]
    want = [s for s, _, _ in _solutions(base) if s >= -1e-12]
    assert len(got) == len(want) > 0
    assert np.allclose([s for s, _ in got], want, rtol=1e-9)
    for _, u in got:
        assert np.all(u[-2 * 5:] == 0)  # the held row stays


def test_the_300_pair_interface_at_mu_20_has_its_mode():
    """Issue 33: 300 pairs at μ = 20 were undecided while 20–100 pairs certify σ = 0.30265;
    with a diagonal B the search from the top of the window finds it."""
    from meicp.io.scene import loads_scene
    from .conftest import ROOT

    text = (ROOT / "data" / "scenes" / "frictional_interface.toml").read_text()
    r = meicp.analyze(loads_scene(text.replace("nx = 10", "nx = 300").replace("friction = 0.5", "friction = 20")),
                      flutter=False)
    assert r.divergence is True and r.proofs[0].test == "certified-mode"
    assert abs(r.modes[0].sigma - 0.30265) < 1e-5 and r.modes[0].residual < 1e-8


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(nx=st.integers(3, 10), lower=st.integers(1, 3), upper=st.integers(1, 3),
       state=st.sampled_from(["slip+", "slip-"]), contrast=st.sampled_from([(6.0, 1.0), (2.0, 1.0)]),
       sides=st.sampled_from(["free", "fixed"]), mu=st.floats(0.05, 20.0))
def test_the_window_procedure_never_contradicts_enumeration_on_interfaces(nx, lower, upper, state, contrast,
                                                                         sides, mu):
    """The large-problem path (``method="active-set"``: Rayleigh bound, σ-window, search,
    condensed proof) on a frictional interface agrees with the enumeration of every support
    whenever it decides: no mode missed, no false mode."""
    scene = two_layer_scene(nx, (lower, upper), bottom="fixed", sides=sides, stiffness=contrast,
                            density=(1.0, 2.0), interface={"kind": "frictional", "friction": mu, "states": state})
    truth = meicp.analyze(scene, method="enumerate", flutter=False)
    window = meicp.analyze(scene, method="active-set", flutter=False)
    assert truth.divergence is not None
    if window.divergence is True:
        assert truth.divergence is True
        assert any(np.isclose(window.modes[0].sigma, m.sigma, rtol=1e-8, atol=1e-12) for m in truth.modes)
    elif window.divergence is False:
        assert truth.divergence is False, window.evidence
