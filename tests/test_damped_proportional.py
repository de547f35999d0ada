"""Damping proportional to stiffness and mass (issue 31, deliverable 2; docs/damping.md,
"Proportional damping"): C = cK + αM makes λ²B + λD − A = (1 + cλ)(σ(λ)B − A), so past the
enumeration the damped divergence is decided by the undamped verdict of the same pencil.
Against the enumeration of the quadratic MEiCP on lattices small enough for both."""

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

import meicp
from meicp.contact.damped_proportional import TEST, ProportionalDamping, growing_root, proportional_damping
from meicp.contact.problem import pencil
from meicp.core import limits
from meicp.examples import two_layer_scene
from meicp.io.scene import load_scene, scene_from_dict
from meicp.lattice.model import LatticeModel

from .test_damping import INTERFACE, SCENES, TWO_LAYERS, damped


def at_scale(scene, monkeypatch, **kw):
    """``analyze`` with the enumeration's limits set below the scene: the path at scale."""
    with monkeypatch.context() as m:
        m.setattr(limits, "ENUMERATE_N", 5)
        return meicp.analyze(scene, flutter=False, **kw)


def growth(result) -> np.ndarray:
    return np.array(sorted(np.sqrt(m.sigma) for m in result.modes))


def embedded(relaxation: float, band_eta: float | None = None):
    """data/scenes/embedded_layer.toml (band k 20 in a matrix k 1, k 2 between) with η = relaxation·k."""
    d = load_scene(SCENES / "embedded_layer.toml").to_dict()
    d["layers"][0]["viscosity"] = relaxation * d["layers"][0]["stiffness"]
    band = d["embedded"][0]
    band["viscosity"] = relaxation * band["stiffness"] if band_eta is None else band_eta
    return scene_from_dict(d)


@pytest.mark.parametrize("scene, c, alpha", [
    (damped(TWO_LAYERS, eta=(0.02, 0.1)), 0.02, 0.0),
    (damped(TWO_LAYERS, eta=(0.02, 0.1), mass=0.05), 0.02, 0.05),
    (damped(TWO_LAYERS, mass=0.1), 0.0, 0.1),
    (damped(INTERFACE, eta=(0.2, 0.1), mass=0.3), 0.1, 0.3),
    (damped(TWO_LAYERS, eta=(0.01, 0.05), interface_eta=0.03), 0.01, 0.0),
], ids=["base", "base+mass", "mass only", "frictional interface", "bonded interface's own η"])
def test_proportional_damping_makes_D_a_combination_of_A_and_B(scene, c, alpha):
    found = proportional_damping(LatticeModel(scene))
    assert found is not None
    assert found.stiffness == pytest.approx(c, rel=1e-15) and found.mass == alpha
    with pencil(scene) as pen:
        A, B, D = pen.A.toarray(), pen.B.toarray(), pen.damping().toarray()
    assert np.abs(D - (-found.stiffness * A + found.mass * B)).max() <= 1e-15 * np.abs(D).max()


def test_the_interface_and_band_viscosities_count_where_bonds_join_them():
    # two_layers.toml's interface has k = mean(1, 5) = 3; its own η 0.05 is not 0.01·3
    assert proportional_damping(LatticeModel(damped(TWO_LAYERS, eta=(0.01, 0.05), interface_eta=0.05))) is None
    # the band's bonds to the matrix have k = 2 (interface_stiffness) and η the mean of the two:
    # 0.5·(0.01 + 0.2) ≠ 0.01·2, so η = 0.01·k on every material is not proportional here
    assert proportional_damping(LatticeModel(embedded(0.01))) is None
    # equal viscosity in layers of different stiffness is not proportional; no damping is none
    assert proportional_damping(LatticeModel(damped(TWO_LAYERS, eta=(0.02, 0.02)))) is None
    assert proportional_damping(LatticeModel(TWO_LAYERS)) is None
    # a frictional interface cuts the bonds between its layers: only each layer's own count
    cut = damped(INTERFACE, eta=(0.2, 0.1))
    assert proportional_damping(LatticeModel(cut)).stiffness == pytest.approx(0.1)


@settings(max_examples=200, deadline=None)
@given(c=st.floats(0, 10), alpha=st.floats(0, 10), lam=st.floats(0, 1e3))
def test_lam_of_inverts_sigma_of(c, alpha, lam):
    damping = ProportionalDamping(c, alpha)
    sigma = damping.sigma_of(lam)
    back = damping.lam_of(sigma)
    assert back >= 0
    # λ(σ) is the root ≥ 0 of λ² + (α − cσ)λ − σ: its residual is rounding of the terms
    assert abs(back * back + (alpha - c * sigma) * back - sigma) <= 1e-13 * (back * back + abs(alpha - c * sigma) * back + sigma) + 1e-300
    assert back == pytest.approx(lam, rel=1e-9, abs=1e-12)


@pytest.mark.parametrize("scene", [damped(TWO_LAYERS, eta=(0.02, 0.1)), damped(TWO_LAYERS, eta=(0.2, 1.0), mass=0.5),
                                   damped(INTERFACE, eta=(0.2, 0.1), mass=0.3),
                                   damped(two_layer_scene(8, (2, 3), mu=2.0, states="slip-", shear=-0.3),
                                          eta=(0.05, 0.25))],
                         ids=["two_layers", "two_layers strongly damped", "interface", "stable"])
def test_the_undamped_verdict_decides_the_damped_one(scene, monkeypatch):
    exact = meicp.analyze(scene, flutter=False)
    r = at_scale(scene, monkeypatch)
    assert exact.proofs[0].test == "quadratic-enumerate" and exact.divergence is not None
    assert r.proofs[0].test == TEST and r.divergence is exact.divergence
    assert growth(r) == pytest.approx(growth(exact), rel=1e-9)
    if r.divergence:
        assert r.modes[0].residual <= 1e-9 and np.array_equal(r.modes[0].support, exact.modes[0].support)
        assert "σ = (λ² + αλ)/(1 + cλ)" in r.evidence and "certified damped divergence mode" in r.evidence


def random_lattice(seed: int):
    """``(undamped, damped)``: a random small lattice and the same with η ∝ k or α·M alone."""
    rng = np.random.default_rng(seed)
    k = float(rng.uniform(1, 6))
    c = float(rng.choice([0.0, 0.01, 0.1, 1.0]))
    base = two_layer_scene(int(rng.integers(4, 8)), (2, int(rng.integers(2, 4))),
                           mu=float(rng.choice([0.5, 1.0, 2.0, 3.0, 5.0])),
                           states=str(rng.choice(["slip+", "slip-"])), shear=float(rng.uniform(-0.4, 0.4)),
                           stiffness=(1.0, k), density=(1.0, float(rng.uniform(0.5, 2))))
    return base, damped(base, eta=(c, c * k), mass=float(rng.choice([0.05, 0.5])) if c == 0 else None)


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                 HealthCheck.function_scoped_fixture])
@given(seed=st.integers(0, 2 ** 32 - 1))
def test_the_proportional_verdict_is_the_enumerated_one(seed, monkeypatch):
    """Decided whenever the undamped verdict is, never against the enumeration of every
    support of the quadratic MEiCP."""
    base, scene = random_lattice(seed)
    exact = meicp.analyze(scene, flutter=False)
    r = at_scale(scene, monkeypatch)
    assert r.divergence is at_scale(base, monkeypatch).divergence
    if r.divergence is not None:
        assert r.divergence is exact.divergence and r.proofs[0].test == TEST
        assert growth(r) == pytest.approx(growth(exact), rel=1e-8, abs=1e-10)


def test_beyond_the_enumeration_without_a_monkeypatch():
    """A lattice past the enumeration (720 DOFs, 60 sliding contacts): the damped divergence
    of an equal viscosity is undecided or found by following; with η ∝ k it is decided
    exactly as the undamped one, and its modes are the undamped ones moved by σ(λ)."""
    base = two_layer_scene(60, (3, 3), mu=3.0, states="slip+", shear=0.2)
    undamped = meicp.analyze(base, flutter=False)
    r = meicp.analyze(damped(base, eta=(0.02, 0.1), mass=0.01), flutter=False)
    assert undamped.divergence is True and r.divergence is True and r.proofs[0].test == TEST
    damping = ProportionalDamping(0.02, 0.01)
    lam = np.array([damping.lam_of(m.sigma) for m in undamped.modes])
    assert growth(r) == pytest.approx(np.sort(lam), rel=1e-9)
    assert math.sqrt(r.modes[0].sigma) < math.sqrt(undamped.modes[0].sigma)


def test_the_divergence_onset_with_proportional_damping_is_the_undamped_one():
    scene = damped(TWO_LAYERS, eta=(0.02, 0.1), mass=0.05)
    r = meicp.critical_friction(scene, flutter=False)
    undamped = meicp.critical_friction(TWO_LAYERS, flutter=False)
    assert (r.divergence.lower, r.divergence.upper) == (undamped.divergence.lower, undamped.divergence.upper)
    assert r.divergence.exact and "proportional to stiffness and mass" in r.divergence.evidence


@settings(max_examples=200, deadline=None)
@given(c=st.floats(0, 5), alpha=st.floats(0, 5), re=st.floats(-50, 5), im=st.floats(1e-6, 20))
def test_the_growing_root_solves_the_scalar_equation_and_grows_the_faster(c, alpha, re, im):
    damping, sigma = ProportionalDamping(c, alpha), complex(re, im)
    lam = growing_root(damping, sigma)
    other = -(alpha - c * sigma) - lam
    scale = abs(lam) ** 2 + abs(alpha - c * sigma) * abs(lam) + abs(sigma)
    assert abs(lam * lam + (alpha - c * sigma) * lam - sigma) <= 1e-13 * scale
    assert lam.real >= other.real - 1e-13 * scale ** 0.5
    if c == alpha == 0:
        assert lam == pytest.approx(np.sqrt(sigma), rel=1e-14)


#: past the dense limit (flutter_dense_max=10) with η ∝ k: a base contact (with and without a
#: mass term) and a frictional interface, 60 columns
SEARCHED = {
    "base": damped(two_layer_scene(60, (3, 3), mu=1.0, states="slip+"), eta=(0.01, 0.05)),
    "base+mass": damped(two_layer_scene(60, (3, 3), mu=1.0, states="slip+"), eta=(0.01, 0.05), mass=0.02),
    "interface": damped(two_layer_scene(60, (3, 3), bottom="fixed", stiffness=(2.0, 1.0), density=(1.0, 1.0),
                                        interface={"kind": "frictional", "friction": 1.0, "states": "slip+"}),
                        eta=(0.04, 0.02)),
}


@pytest.mark.parametrize("name", sorted(SEARCHED))
def test_the_undamped_search_finds_damped_flutter_modes(name):
    """With proportional damping the search at scale is the undamped one at σ(λ₀); every mode
    it certifies is an eigenvalue of the damped pencil's dense companion spectrum, with its
    backward error on λ²B + λD − A itself; on the base contact the fastest is the dense fastest."""
    scene = SEARCHED[name]
    dense = meicp.analyze(scene)
    r = meicp.analyze(scene, flutter_dense_max=10)
    assert dense.flutter is True and dense.flutter_growth.exact
    assert r.flutter is True and r.stable is False
    assert "so the undamped search ran" in r.flutter_evidence and "not a proof" in r.flutter_evidence
    lam_dense = np.array([np.sqrt(m.sigma) for m in dense.flutter_modes])
    for mode in r.flutter_modes:
        lam = np.sqrt(mode.sigma)
        assert np.min(np.abs(lam_dense - lam)) <= 1e-10 * abs(lam) and mode.residual <= 1e-10
    assert r.flutter_growth.lower <= dense.flutter_growth.upper <= r.flutter_growth.upper
    if name.startswith("base"):
        assert r.flutter_modes[0].growth_rate == pytest.approx(dense.flutter_modes[0].growth_rate, rel=1e-10)
