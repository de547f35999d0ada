"""The critical friction of a damped lattice (issue 31, deliverable 4): the flutter onset μ_f
by an interval cover of the companion form (every eigenvalue real or decaying) and a certified
damped flutter mode, the divergence onset μ_c (λ = 0 modes: the damping drops out), checked
against the dense spectrum on a fine grid of μ, on 1 rank here and on 2 in
tests/test_damping_mpi.py."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

import meicp
from meicp.contact.critical_friction.flutter_onset import sliding_families
from meicp.contact.critical_friction.solve import _friction_states
from meicp.contact import damped_rayleigh
from meicp.contact.damped_cover import QuadraticFamily, damped_cover_step
from meicp.contact.maps import reduced_system
from meicp.core import limits
from meicp.eicp.quadratic import quadratic_spectrum
from meicp.examples import two_layer_scene

from .test_damping import INTERFACE, TWO_LAYERS, damped


def family_of(scene) -> QuadraticFamily:
    lattice, lines = _friction_states(scene)
    (branch,) = sliding_families(lattice, lines)
    assert isinstance(branch.family, QuadraticFamily)
    return branch.family


def growing_non_real(fam: QuadraticFamily, mu: float) -> float:
    """The largest Re λ over the eigenvalues that are clearly non-real, from the dense
    companion spectrum (an independent computation: QZ/QR and no cover)."""
    A, B, D = (M.toarray() for M in fam.at(mu))
    spec = quadratic_spectrum(A, B, D)
    lam, r = spec.lam, spec.radius
    non_real = np.abs(lam.imag) > np.maximum(10 * r, 1e-9 * np.abs(lam))
    return float(np.max(lam.real[non_real], initial=-np.inf))


def lattice(seed: int):
    """A small damped lattice: two layers on a sliding base, or a frictional interface."""
    rng = np.random.default_rng(seed)
    k = tuple(float(v) for v in rng.uniform(0.5, 4.0, 2))
    eta = tuple(float(v) for v in rng.uniform(0.005, 0.2, 2))
    if rng.random() < 0.5:
        scene = two_layer_scene(int(rng.integers(3, 6)), (2, 2), bottom="contact", stiffness=k,
                                density=(1.0, float(rng.uniform(0.5, 2))), shear=float(rng.uniform(-0.4, 0.4)),
                                mu=1.0, states=str(rng.choice(["slip+", "slip-"])))
    else:
        scene = two_layer_scene(int(rng.integers(3, 6)), (2, 2), bottom="fixed", stiffness=k, density=(1.0, 1.0),
                                interface={"kind": "frictional", "friction": 1.0,
                                           "states": str(rng.choice(["slip+", "slip-"]))})
    return damped(scene, eta=eta)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2 ** 32 - 1), mu=st.floats(0.0, 3.0))
def test_no_growing_non_real_eigenvalue_inside_a_proved_interval(seed, mu):
    fam = family_of(lattice(seed))
    step = damped_cover_step(fam, mu)
    if step.radius == 0:
        return
    ends = max(mu - step.radius, 0.0), mu + min(step.radius, 10.0)
    for m in np.linspace(*ends, 9):
        assert growing_non_real(fam, float(m)) < 0, (m, step)


@pytest.mark.parametrize("scene, eta", [(TWO_LAYERS, (0.02, 0.02)), (TWO_LAYERS, (0.1, 0.01)),
                                        (INTERFACE, (0.02, 0.02)), (INTERFACE, (0.1, 0.01))])
def test_the_damped_flutter_onset_is_exact_and_matches_the_dense_spectrum(scene, eta):
    s = damped(scene, eta=eta)
    mu = meicp.critical_friction(s)
    f = mu.flutter
    assert f.exact and f.upper - f.lower <= 1e-6 * f.upper and "companion form" in f.evidence
    fam = family_of(s)
    # the dense spectrum on a grid of [0, lower]: nothing grows; just past the upper end it does
    for m in np.linspace(0.0, f.lower, 40):
        assert growing_non_real(fam, float(m)) < 0, m
    assert growing_non_real(fam, f.upper) > 0
    lam = np.sqrt(complex(f.mode.sigma))
    assert lam.real > 0 and abs(lam.imag) > 0
    assert mu.first == "flutter" and float(mu) == f.upper


def test_damping_raises_the_flutter_onset_of_two_layers_a_proof():
    """The base contact's threshold rises with damping: the damped lower end lies above the
    undamped certified flutter mode (both ends proved, not a grid)."""
    undamped = meicp.critical_friction(TWO_LAYERS)
    for eta in [(0.02, 0.02), (0.1, 0.01)]:
        mu = meicp.critical_friction(damped(TWO_LAYERS, eta=eta))
        assert mu.flutter.lower > undamped.flutter.upper
    assert 1.38 < meicp.critical_friction(damped(TWO_LAYERS, eta=(0.02, 0.02))).flutter.lower < 1.39


def test_the_divergence_onset_is_the_undamped_one_and_says_why():
    undamped = meicp.critical_friction(TWO_LAYERS, flutter=False)
    mu = meicp.critical_friction(damped(TWO_LAYERS, eta=(0.1, 0.01)), flutter=False)
    assert mu.divergence.lower == undamped.divergence.lower and mu.divergence.upper == undamped.divergence.upper
    assert "damping drops out" in mu.divergence.evidence and "η(A) = 0.1" in mu.divergence.evidence
    assert float(mu) == pytest.approx(1.90603249, rel=1e-8)
    # the λ = 0 mode at μ_c is a damped divergence mode too: just above it the damped
    # enumeration finds a mode whose λ goes to 0 with μ − μ_c (here like √(μ − μ_c): the mode at
    # μ_c is nearly a rigid slide, which the dashpots barely resist, ξᵀDx ≈ 0)
    def slowest(rel):
        r = meicp.analyze(damped(TWO_LAYERS, eta=(0.1, 0.01)).with_friction(float(mu) * (1 + rel)), flutter=False)
        assert r.divergence is True
        return min(m.growth_rate for m in r.modes)

    far, near = slowest(1e-3), slowest(1e-5)
    assert near < far / 5 and near < 5e-3


def test_an_undamped_mode_leaves_the_cover_at_zero():
    """D with a null vector that is a mode of the symmetric pencil: that mode's λ = ±i sits on
    the imaginary axis at μ = 0, where the skew coupling may push it right at once — the
    cover proves nothing there, and the onset's lower end stays 0, saying why."""
    import scipy.sparse as sp

    from meicp.contact.critical_friction.flutter_onset import dense_onset

    csr = lambda M: sp.csr_matrix(np.asarray(M, dtype=float))
    fam = QuadraticFamily(csr(-np.diag([1.0, 4.0])), csr([[0, 1], [-1, 0]]), csr(np.eye(2)), csr(np.zeros((2, 2))),
                          D0=csr(np.diag([0.0, 0.1])), D1=csr(np.zeros((2, 2))))
    step = damped_cover_step(fam, 0.0)
    assert step.radius == 0 and "imaginary axis" in step.why
    assert damped_cover_step(fam, 0.5).radius == 0 or growing_non_real(fam, 0.5) < 0
    onset = dense_onset([fam], 1.0, 10.0)
    assert onset.lower == 0 and "a mode the damping does not reach" in onset.evidence
    # with the mode damped too the cover starts: the same coupling, D positive definite
    damped_too = QuadraticFamily(fam.A0, fam.A1, fam.B0, fam.B1, D0=csr(np.diag([0.05, 0.1])), D1=fam.D1)
    assert damped_cover_step(damped_too, 0.0).radius > 0


def test_past_the_dense_limit_the_damped_search_gives_the_upper_end(monkeypatch):
    exact = meicp.critical_friction(damped(INTERFACE, eta=(0.02, 0.02))).flutter
    monkeypatch.setattr(limits, "FLUTTER_DENSE_MAX", 10)
    f = meicp.critical_friction(damped(INTERFACE, eta=(0.02, 0.02))).flutter
    assert not f.exact and "never its absence" in f.evidence
    # the lower end: where the damped flutter-free proof holds (docs/damping.md), never above μ_f
    assert 0 < f.lower <= exact.lower and "no eigenvalue of the damped sliding pencil grows" in f.evidence
    assert exact.lower <= f.upper <= 2 * exact.upper and "damped flutter mode" in f.evidence


def test_the_cli_prints_and_stores_the_damped_onsets(tmp_path):
    import json
    import subprocess
    import sys

    from .conftest import ROOT

    text = (ROOT / "data" / "scenes" / "two_layers.toml").read_text()
    text = text.replace('name = "A"', 'name = "A"\nviscosity = 0.02').replace('name = "B"', 'name = "B"\nviscosity = 0.02')
    path = tmp_path / "damped.toml"
    path.write_text(text)
    out = subprocess.run([sys.executable, "-m", "meicp", "solve", str(path), "--critical-friction", "--json",
                          "-o", str(tmp_path / "run")], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    rec = json.loads(out.stdout)["critical_friction"]
    assert rec["first"] == "flutter" and rec["exact"]
    assert 1.38 < rec["flutter"]["lower"] <= rec["flutter"]["upper"] < 1.39
    assert rec["divergence"]["upper"] == pytest.approx(1.90603249, rel=1e-8)
    back = meicp.load_results(tmp_path / "run" / "results.h5")
    assert back.damping is not None and back.critical_friction.flutter.upper == rec["flutter"]["upper"]


def test_damped_modes_below_the_lambda_zero_onset_make_a_bracket_with_a_proved_floor():
    """The 6 × 4 interface with η 0.1 / 0.01: the λ = 0 mode at μ_c = 6.708 has ξᵀDx < 0, so
    damped divergence modes exist just below it; the onset is then a bracket whose upper end
    is where the enumeration finds them and whose lower end the damped Rayleigh bound (convex in
    μ) and the λ-windows carried over μ prove — [6.7039, 6.7061], far above the flutter onset,
    so flutter is proved to start first."""
    mu = meicp.critical_friction(damped(INTERFACE, eta=(0.1, 0.01)))
    d = mu.divergence
    assert not d.exact and d.upper < 6.7082039 and "born at" in d.evidence and "convex in μ" in d.evidence
    assert 6.69 < d.lower < d.upper and "carried over μ" in d.evidence
    assert mu.first == "flutter" and mu.flutter.upper < d.lower
    # the floor is sound: the enumeration finds no damped divergence mode on a grid below it
    for m in np.linspace(0.05, d.lower, 6):
        assert meicp.analyze(damped(INTERFACE, eta=(0.1, 0.01)).with_friction(float(m)), flutter=False).divergence is False
    # and the upper end is a μ with a certified damped divergence mode
    assert meicp.analyze(damped(INTERFACE, eta=(0.1, 0.01)).with_friction(d.upper), flutter=False).divergence is True


def test_proportional_damping_keeps_the_exact_onset_past_the_enumeration():
    scene = two_layer_scene(22, (2, 2), bottom="fixed", stiffness=(2.0, 1.0), density=(1.0, 1.0),
                            interface={"kind": "frictional", "friction": 1.0, "states": "slip+"})
    d = meicp.critical_friction(damped(scene, eta=(0.2, 0.1)), flutter=False).divergence
    assert d.exact and d.upper == pytest.approx(6.7082039, rel=1e-7) and "proportional" in d.evidence



def test_the_rayleigh_floor_ends_when_nothing_above_0_is_proved(monkeypatch):
    """The Rayleigh bound along μ proved at 0 and nowhere above: the bisection ends with 0 (with
    lo = 0 its stopping rule hi − lo ≤ rel·hi never held: a grazing case looped forever)."""
    scene = damped(two_layer_scene(6, (2, 2), mu=1.0, states="slip+"), eta=[0.02, 0.02])
    lattice, lines = _friction_states(scene)
    tried = []

    def only_at_zero(pen, C=None, M=None, *, comm=None):
        mu = float(np.max(np.abs(pen.maps.friction_rows().data), initial=0.0))
        tried.append(mu)
        return mu == 0.0, ""

    monkeypatch.setattr(damped_rayleigh, "damped_rayleigh_bound", only_at_zero)
    assert damped_rayleigh.divergence_free_up_to(lattice, lines, (), 5.0) == 0.0
    # 0, the upper end, then 5 / 8^k down to 1e-6·5: 7 steps
    assert tried[0] == 0.0 and len(tried) == 2 + 7 and tried[-1] <= 5.0 * damped_rayleigh.SMALLEST


def test_the_damped_flutter_free_bisection_ends_when_nothing_above_0_is_proved(monkeypatch):
    """The twin of the Rayleigh floor's loop: the damped flutter-free proof along μ, proved at
    0 and nowhere above, ends with 0 after the same descent (its plain halving from lo = 0 ran
    until hi underflowed: about a thousand inertias)."""
    from types import SimpleNamespace

    from meicp.contact import damped_flutter_free

    scene = damped(two_layer_scene(6, (2, 2), mu=1.0, states="slip+"), eta=[0.02, 0.02])
    lattice, lines = _friction_states(scene)
    maps = reduced_system(lattice.model, lines, ())
    tried = []

    def only_at_zero(pen, tau, comm=None):
        mu = float(np.max(np.abs(pen.maps.friction_rows().data), initial=0.0))
        tried.append(mu)
        return SimpleNamespace(proved=mu == 0.0)

    monkeypatch.setattr(damped_flutter_free, "pencil_bound", only_at_zero)
    lo, _ = damped_flutter_free.flutter_free_up_to(lattice, lines, maps, 5.0)
    above = [mu for mu in tried if mu > 0]
    # the upper end, then 5 / 8^k down to 1e-6·5: 7 steps
    assert lo == 0.0 and len(above) == 1 + 7 and min(above) <= 5.0 * damped_rayleigh.SMALLEST
