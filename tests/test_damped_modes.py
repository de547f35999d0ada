"""Damped divergence modes past the enumeration (issue 31, deliverable 2; docs/damping.md
"damped divergence modes at scale"): the undamped modes followed to the damped problem on
their supports by residual inverse iteration, certified on the whole reduced pencil.  Against
the enumeration of the quadratic MEiCP on lattices small enough for both; a way to find
modes, never a proof of absence."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

import meicp
from meicp.core import limits
from meicp.examples import two_layer_scene

from .test_damping import TWO_LAYERS, damped


def followed(scene, monkeypatch):
    """``analyze`` with the enumeration's limits set below the scene: the path at scale."""
    with monkeypatch.context() as m:
        m.setattr(limits, "ENUMERATE_N", 5)
        return meicp.analyze(scene, flutter=False)


def growth(result) -> np.ndarray:
    return np.array(sorted(np.sqrt(m.sigma) for m in result.modes))


def random_lattice(seed: int):
    rng = np.random.default_rng(seed)
    return damped(two_layer_scene(int(rng.integers(4, 8)), (2, int(rng.integers(2, 4))),
                                  mu=float(rng.choice([0.5, 1.0, 2.0, 3.0, 5.0])),
                                  states=str(rng.choice(["slip+", "slip-"])), shear=float(rng.uniform(-0.4, 0.4)),
                                  stiffness=(1.0, float(rng.uniform(1, 6))), density=(1.0, float(rng.uniform(0.5, 2)))),
                  eta=tuple(float(v) for v in rng.uniform(0.005, 0.15, 2)))


@pytest.mark.parametrize("eta", [(0.02, 0.02), (0.1, 0.01)])
def test_the_followed_mode_is_the_enumerated_one(eta, monkeypatch):
    scene = damped(TWO_LAYERS, eta=eta)
    exact = meicp.analyze(scene, flutter=False)
    r = followed(scene, monkeypatch)
    assert exact.divergence is True and r.divergence is True and r.stable is False
    assert growth(r) == pytest.approx(growth(exact), rel=1e-9)
    assert r.proofs[0].test == "quadratic-followed" and "residual inverse iteration" in r.evidence
    assert r.modes[0].residual <= 1e-9
    assert np.array_equal(r.modes[0].support, exact.modes[0].support)


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(seed=st.integers(0, 2 ** 32 - 1))
def test_a_followed_mode_is_always_an_enumerated_mode(seed, monkeypatch):
    """Never a wrong mode: whatever the path at scale certifies, the enumeration of every
    support finds too; where it finds nothing the verdict is undecided, or proved by the
    damped Rayleigh bound or the condensed λ-windows, never "stable" by default."""
    scene = random_lattice(seed)
    exact = meicp.analyze(scene, flutter=False)
    r = followed(scene, monkeypatch)
    if r.divergence is True:
        assert exact.divergence is True
        lam_exact = growth(exact)
        for lam in growth(r):
            assert np.min(np.abs(lam_exact - lam)) <= 1e-8 * max(lam, 1e-3)
    elif r.divergence is False:
        assert r.proofs[0].test in ("damped-rayleigh", "damped-condensed-windows") and exact.divergence is False
    else:
        assert "proves nothing" in r.evidence


def test_without_an_undamped_mode_nothing_is_followed(monkeypatch):
    """Nothing to follow; the condensed λ-windows then prove what the enumeration finds (no mode)."""
    scene = damped(two_layer_scene(8, (2, 3), mu=2.0, states="slip-", shear=-0.3), eta=(0.05, 0.01))
    assert meicp.analyze(scene, flutter=False).divergence is False
    r = followed(scene, monkeypatch)
    assert r.divergence is False and r.proofs[0].test == "damped-condensed-windows"
    assert "no undamped divergence mode to follow" in r.evidence


def test_real_roots_keep_a_double_root_perturbed_by_rounding():
    from meicp.petsc.damped_refine import _real_roots

    assert sorted(_real_roots(1.0, -3.0, 2.0)) == pytest.approx([1.0, 2.0])
    assert _real_roots(1.0, -2.0, 1.0 + 1e-15) == pytest.approx([1.0, 1.0])  # negative discriminant by rounding
    assert _real_roots(1.0, 0.0, 1.0) == []  # a true complex pair
    assert _real_roots(0.0, 2.0, -1.0) == [0.5]
