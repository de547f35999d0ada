"""The damped flutter-free proof at any size (issue 31, deliverable 3; docs/damping.md,
"damped flutter-free proof"): Re a ≤ −g by one LDLᵀ inertia, the damping's and the friction's
parts bounded by passes over rows, and the Hurwitz criterion of λ² + dλ − a.  Never against
the dense companion spectrum; stable = True past the dense limit where it holds."""

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

import meicp
from meicp.contact.damped import damping_matrix
from meicp.contact.damped_flutter_free import damped_flutter_free, needed_shift, stiffness_part
from meicp.contact.problem import pencil
from meicp.eicp.quadratic import quadratic_spectrum
from meicp.examples import two_layer_scene
from meicp.lattice.model import LatticeModel

from .test_damping import TWO_LAYERS, damped


def hurwitz(p: complex, q: complex) -> bool:
    return p.real > 0 and p.real * (p.real * q.real + p.imag * q.imag) - q.imag ** 2 > 0


@settings(max_examples=300, deadline=None)
@given(p=st.complex_numbers(max_magnitude=20), q=st.complex_numbers(max_magnitude=20))
def test_the_hurwitz_criterion_is_the_sign_of_the_roots(p, q):
    roots = np.roots([1, p, q])
    if abs(np.max(roots.real)) > 1e-6 * (1 + abs(p) + abs(q)):  # not on the axis itself
        assert hurwitz(p, q) == bool(np.all(roots.real < 0))


@settings(max_examples=200, deadline=None)
@given(beta=st.floats(1e-6, 10), delta=st.floats(0, 10), alpha=st.floats(0, 5), c=st.floats(0, 5),
       nu=st.floats(0, 2))
def test_needed_shift_is_the_smallest_that_holds(beta, delta, alpha, c, nu):
    def d0(g):
        return alpha + c * g - nu

    def h(g):
        return d0(g) > 0 and g * d0(g) ** 2 - d0(g) * delta * beta - beta ** 2 > 0

    g = needed_shift(beta, delta, d0)
    if math.isinf(g):
        assert not h(1e12) and not h(1e100)
        return
    assert h(g) and not h(g * (1 - 1e-5))
    # every a with Re a ≤ −g, |Im a| ≤ β and d with Re d ≥ d₀(g), |Im d| ≤ δ: both roots decay
    rng = np.random.default_rng(int(1e6 * beta) % 2 ** 32)
    for _ in range(50):
        a = complex(-g * (1 + rng.exponential()), beta * rng.uniform(-1, 1))
        d = complex(d0(g) * (1 + rng.exponential()), delta * rng.uniform(-1, 1))
        assert np.all(np.roots([1, d, -a]).real < 1e-12 * (1 + abs(a) + abs(d)))


def test_without_a_skew_part_any_positive_shift_serves():
    assert needed_shift(0.0, 0.0, lambda g: 0.1) == 1e-300
    assert math.isinf(needed_shift(0.0, 0.0, lambda g: -0.1))


def test_the_stiffness_part_is_the_smallest_relaxation_time():
    assert stiffness_part(LatticeModel(damped(TWO_LAYERS, eta=(0.02, 0.02), mass=0.05))) == (pytest.approx(0.004), 0.05)
    assert stiffness_part(LatticeModel(damped(TWO_LAYERS, eta=(0.02, 0.1)))) == (pytest.approx(0.02), 0.0)
    assert stiffness_part(LatticeModel(damped(TWO_LAYERS, eta=(0.0, 0.1), mass=0.1))) == (0.0, 0.1)


def random_lattice(seed: int):
    rng = np.random.default_rng(seed)
    k = float(rng.uniform(1, 6))
    scene = two_layer_scene(int(rng.integers(4, 9)), (int(rng.integers(1, 3)), int(rng.integers(1, 3))),
                            mu=float(rng.choice([0.001, 0.005, 0.01, 0.05, 0.3])),
                            states=str(rng.choice(["slip+", "slip-"])), shear=float(rng.uniform(-0.4, 0.4)),
                            stiffness=(1.0, k), density=(1.0, float(rng.uniform(0.5, 2))))
    return damped(scene, eta=tuple(float(v) for v in rng.choice([0.0, 0.02, 0.2], 2)),
                  mass=float(rng.choice([0.0, 0.05, 0.3])))


def test_the_proof_is_never_against_the_companion_spectrum_and_holds_on_many():
    proved = 0
    for seed in range(60):
        scene = random_lattice(seed)
        if not scene.damped:
            continue
        with pencil(scene) as pen:
            ok, text = damped_flutter_free(pen)
            spec = quadratic_spectrum(pen.A.toarray(), pen.B.toarray(), damping_matrix(pen).toarray())
        if ok:
            proved += 1
            finite = np.isfinite(spec.lam)
            assert np.all(spec.lam.real[finite] < spec.radius[finite]), (seed, text)
            assert "Hurwitz" in text
        else:
            assert "proof" in text
    assert proved >= 10


#: a shallow lattice held on top, 600 columns (5,400 retained DOFs: past the dense limit)
SHALLOW = two_layer_scene(600, (3, 3), mu=0.01, states="slip+")


@pytest.mark.parametrize("eta, mass, test", [(None, 0.1, "proportional-damping"),
                                             ((0.02, 0.02), 0.05, "damped-rayleigh")],
                         ids=["mass damping", "equal viscosities and mass"])
def test_past_the_dense_limit_a_damped_lattice_is_proved_stable(eta, mass, test):
    r = meicp.analyze(damped(SHALLOW, eta=eta, mass=mass))
    assert r.sizes["retained"] > 2500
    assert r.divergence is False and r.flutter is False and r.stable is True
    assert r.proofs[0].test == test and "no eigenvalue grows (a proof)" in r.flutter_evidence
    assert r.flutter_growth.exact and r.flutter_growth.upper == 0.0


def test_where_the_proof_fails_the_verdict_stays_undecided_and_says_why():
    r = meicp.analyze(damped(SHALLOW.with_friction(0.05), mass=0.1))
    assert r.flutter is None and r.stable is None
    assert "damped flutter-free proof failed" in r.flutter_evidence and "no target searched" in r.flutter_evidence


def test_past_the_dense_limit_the_damped_flutter_onset_has_a_proved_lower_end(monkeypatch):
    """The search proves flutter, never its absence; with damping the flutter-free proof
    gives the onset a lower end (two inertias per μ tried), never above the dense onset."""
    from meicp.core import limits

    scene = damped(two_layer_scene(6, (2, 2), mu=0.01, states="slip+"), mass=0.1)
    dense = meicp.critical_friction(scene, mu_max=5.0)
    with monkeypatch.context() as m:
        m.setattr(limits, "FLUTTER_DENSE_MAX", 10)
        r = meicp.critical_friction(scene, mu_max=5.0)
    assert 0 < r.flutter.lower <= dense.flutter.lower
    assert r.flutter.lower <= r.flutter.upper
    assert "no eigenvalue of the damped sliding pencil grows for any μ in [0," in r.flutter.evidence


def test_a_tiny_pencil_past_a_tiny_dense_limit_does_not_end_the_process():
    """The flutter-free proof's inertia of a small pencil: PORD (the long lattices' ordering)
    exits the process on small or dense matrices, so below PORD_FROM rows it is not used (a
    subprocess, so that a regression fails this test, not the whole run)."""
    import subprocess
    import sys

    code = ("import meicp\nfrom meicp.examples import two_layer_scene\n"
            "from meicp.io.scene import scene_from_dict\n"
            "d = two_layer_scene(2, (1, 1), mu=0.3, states='slip+').to_dict(); d['damping'] = {'mass': 0.1}\n"
            "r = meicp.analyze(scene_from_dict(d), flutter_dense_max=1)\nprint('flutter', r.flutter)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stdout + out.stderr
    assert "flutter" in out.stdout
