"""The flutter onset μ_f in ``critical_friction`` (issue 29, deliverable 3): the interval
cover proves "smallest", the upper end is a certified flutter mode, and at a collision itself
the answer is undecided, never wrong."""
import math
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sl
import scipy.sparse as sp
from hypothesis import HealthCheck, given, settings, strategies as st
from scipy.optimize import brentq

import meicp
from meicp.contact.critical_friction import CriticalFriction, critical_friction
from meicp.contact.critical_friction.flutter_onset import dense_onset
from meicp.contact.critical_friction import solve
from meicp.contact.critical_friction.result import FLUTTER_EXACT_WIDTH, Onset
from meicp.contact.flutter import dense_flutter
from meicp.contact.flutter_cover import PencilFamily, cover_step
from meicp.contact.problem import pencil
from meicp.core import limits
from meicp.examples import two_layer_scene

SCENES = Path(__file__).resolve().parents[1] / "data" / "scenes"


def family(C0, C1, B0=None, B1=None) -> PencilFamily:
    """(A₀ + μA₁, B₀ + μB₁) from dense arrays (B = I by default)."""
    n = len(C0)
    B0 = np.eye(n) if B0 is None else B0
    B1 = np.zeros((n, n)) if B1 is None else B1
    return PencilFamily(*(sp.csr_matrix(np.asarray(M, dtype=float)) for M in (C0, C1, B0, B1)))


def skew_pair(a, b) -> PencilFamily:
    """C(μ) = [[a, μ], [−μ, b]]: eigenvalues (a+b)/2 ± √(((a−b)/2)² − μ²), real up to the
    collision at μ = |a − b|/2, a non-real pair beyond."""
    return family(np.diag([a, b]), [[0, 1], [-1, 0]])


# -------------------------------------------------------------------------- the cover lemma

@pytest.mark.parametrize("a, b", [(1.0, 3.0), (-2.0, 0.5), (10.0, 10.1), (1e3, 1e3 + 6)])
def test_the_cover_lemma_stops_short_of_the_analytic_collision(a, b):
    c = abs(a - b) / 2
    fam = skew_pair(a, b)
    for mu in (0.0, 0.3 * c, 0.9 * c, 0.999 * c):
        step = cover_step(fam, mu)
        assert step.real and 0.1 * (c - mu) <= step.radius < c - mu, (mu, step)  # sound, and not timid
    assert cover_step(fam, c).radius == 0  # the collision itself: nothing proved
    beyond = cover_step(fam, 1.01 * c)
    assert beyond.radius == 0 and not beyond.real


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), n=st.integers(2, 6), interface=st.booleans())
def test_every_sigma_is_real_inside_a_proved_interval(seed, n, interface):
    """Random families (A₀ symmetric, A₁ arbitrary; B diagonal, or B₀ SPD with μ in B₁ as on
    a frictional interface): wherever cover_step proves an interval, QZ finds only real σ."""
    rng = np.random.default_rng(seed)
    A0 = rng.normal(size=(n, n))
    A0 = A0 + A0.T
    A1 = rng.normal(size=(n, n))
    B0, B1 = np.diag(rng.uniform(0.5, 2.0, n)), np.zeros((n, n))
    if interface:
        L = rng.normal(size=(n, n)) * 0.3
        B0, B1 = B0 + L @ L.T, rng.normal(size=(n, n)) * 0.1
    fam = family(A0, A1, B0, B1)
    mu0 = rng.uniform(0.0, 0.5)
    step = cover_step(fam, mu0)
    for mu in mu0 + step.radius * np.linspace(-1, 1, 9):
        if step.radius > 0 and np.isfinite(mu):
            sigma = sl.eigvals(*(M.toarray() for M in fam.at(mu)))
            assert np.abs(sigma.imag).max() <= 1e-6 * np.abs(sigma).max(), (mu, sigma)


def test_a_crossing_without_interaction_stops_the_cover_but_not_the_truth():
    """C(μ) = [[a, μ, 0], [−μ, b, 0], [0, 0, d]]: the lower eigenvalue of the pair crosses d at
    μ* = √(((a−b)/2)² − ((a+b)/2 − d)²) without interacting, and the pair collides at c =
    |a − b|/2.  The cover cannot pass the crossing; the bracket still holds c."""
    a, b, d = 1.0, 3.0, 1.8
    c = abs(a - b) / 2
    crossing = math.sqrt(c ** 2 - ((a + b) / 2 - d) ** 2)
    fam = family(np.diag([a, b, d]), [[0, 1, 0], [-1, 0, 0], [0, 0, 0]])
    onset = dense_onset([fam], start=3.0, mu_max=10.0)
    assert onset.lower < crossing < c <= onset.upper and not onset.exact
    assert "stalls" in onset.evidence and "undecided" in onset.evidence
    assert np.abs(sl.eigvals(fam.at(onset.upper)[0].toarray()).imag).max() > 0


def test_the_march_finds_a_flutter_window_no_trial_point_sees():
    """[[μ, 1], [3/16 − μ, −μ]] flutters on (1/4, 3/4) only: every μ tried for the upper end
    (1, 2, 4, …) is flutter-free, the cover stalls at 1/4 and the verdict just past it
    certifies flutter — a bisection on the verdict alone from [0, 1] would have said none."""
    fam = family([[0, 1], [3 / 16, 0]], [[1, 0], [-1, -1]])
    onset = dense_onset([fam], start=1.0, mu_max=100.0)
    assert onset.exact and onset.lower <= 0.25 <= onset.upper and onset.width <= FLUTTER_EXACT_WIDTH


@pytest.mark.parametrize("beta", [0.0, 0.5, 0.2])
def test_the_onset_of_a_pencil_whose_mass_depends_on_mu(beta):
    """B(μ) = diag(1, 1 + βμ) (μ in B, as on a frictional interface): the eigenvalues of
    B⁻¹A(μ) meet where ((a − b/(1+βμ))² − 4μ²/(1+βμ)) vanishes."""
    a, b = 1.0, 3.0
    fam = family(np.diag([a, b]), [[0, 1], [-1, 0]], B1=np.diag([0.0, beta]))
    c = brentq(lambda m: (a - b / (1 + beta * m)) ** 2 - 4 * m * m / (1 + beta * m), 0.0, 1.5)
    onset = dense_onset([fam], start=3.0, mu_max=10.0)
    assert onset.exact and onset.lower <= c <= onset.upper and onset.width <= FLUTTER_EXACT_WIDTH


def test_at_the_collision_itself_the_answer_is_undecided_never_wrong():
    for a, b in ((1.0, 3.0), (0.5, 2.5), (1e3, 1e3 + 6)):
        c = abs(a - b) / 2
        A = np.array([[a, c], [-c, b]])
        assert dense_flutter(A, np.eye(2)).flutter is None  # a double eigenvalue: borderline
        assert cover_step(skew_pair(a, b), c).radius == 0
        onset = dense_onset([skew_pair(a, b)], start=c, mu_max=10 * c)  # the first μ tried is c itself
        assert onset.lower <= c <= onset.upper and onset.exact


# ------------------------------------------------------------------------------- scenes

def test_two_layers_flutters_from_0_630763_exactly():
    """docs/flutter.md §6: the verdict is False (a proof) at 0.6307631 and True at 0.6307634;
    the bracket must hold that transition, 1e-6 wide, below μ_c = 1.906."""
    mu = critical_friction(meicp.load_scene(SCENES / "two_layers.toml"))
    f = mu.flutter
    assert f.exact and f.width <= FLUTTER_EXACT_WIDTH and f.lower <= 0.6307634 and f.upper >= 0.6307631
    assert mu.first == "flutter" and float(mu) == f.upper and (mu.lower, mu.upper, mu.exact) == (f.lower, f.upper, True)
    assert mu.divergence.exact and mu.divergence.upper == pytest.approx(1.90603249044423, rel=1e-10)
    assert f.mode.growth_rate > 0 and abs(f.mode.sigma.imag) > f.mode.radius and "flutter first" in mu.describe()
    scene = meicp.load_scene(SCENES / "two_layers.toml")
    assert meicp.analyze(scene.with_friction(f.lower * (1 - 1e-6))).flutter is not True
    assert meicp.analyze(scene.with_friction(f.upper)).flutter is True


def _dense_spectrum(scene, mu):
    with pencil(scene.with_friction(mu)) as pen:
        return sl.eigvals(pen.A.toarray(), pen.B.toarray())


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(nx=st.integers(3, 6), rows=st.tuples(st.integers(1, 2), st.integers(1, 2)),
       shear=st.floats(-0.6, 0.6), states=st.sampled_from(["slip+", "slip-"]), stiff=st.floats(0.5, 8.0),
       seed=st.integers(0, 2 ** 16))
def test_no_complex_sigma_below_the_lower_end_and_one_at_the_upper_end(nx, rows, shear, states, stiff, seed):
    scene = two_layer_scene(nx, rows, mu=1.0, states=states, shear=shear, stiffness=(1.0, stiff))
    f = critical_friction(scene, bisection=False).flutter
    assert 0 <= f.lower <= f.upper
    rng = np.random.default_rng(seed)
    for mu in rng.uniform(0.0, 0.999 * min(f.lower, 50.0), 3):  # QZ, a tolerance far above rounding
        sigma = _dense_spectrum(scene, mu)
        assert np.abs(sigma.imag).max() <= 1e-7 * np.abs(sigma).max(), mu
    if np.isfinite(f.upper):
        sigma = _dense_spectrum(scene, f.upper)
        assert np.abs(sigma.imag).max() > max(f.mode.radius, 1e3 * np.finfo(float).eps * np.abs(sigma).max())


def test_grazing_branches_flutter_together_at_the_upper_end():
    """Two grazing contacts: a separated and two sliding branches; flutter is certified at the
    upper end in every branch (analyze agrees), and excluded below the lower end in all."""
    states = ["grazing", "slip+", "slip+", "grazing", "slip+"]
    scene = two_layer_scene(5, (2, 2), mu=3.0, states=states)
    mu = critical_friction(scene, bisection=False)
    f = mu.flutter
    assert 0 < f.lower <= f.upper < np.inf
    assert meicp.analyze(scene.with_friction(f.upper)).flutter is True
    assert meicp.analyze(scene.with_friction(0.5 * f.lower)).flutter is False


def test_flutter_false_is_the_divergence_onset_alone():
    scene = meicp.load_scene(SCENES / "two_layers.toml")
    mu = critical_friction(scene, flutter=False)
    assert mu.flutter is None and mu.first is None and float(mu) == mu.divergence.upper == pytest.approx(1.906032490)
    assert "flutter not analysed" in mu.evidence and mu.describe() == mu.divergence.describe()
    with pytest.raises(meicp.ProblemError, match="flutter must be True or False"):
        critical_friction(scene, flutter="yes")


def test_no_sliding_contact_is_flutter_free_at_every_mu():
    mu = critical_friction(two_layer_scene(5, (2, 2), mu=1.0, states="stick"))
    assert mu == np.inf and mu.flutter.lower == np.inf and mu.flutter.exact and mu.exact and mu.first is None


def test_a_budget_that_runs_out_leaves_an_honest_bracket(monkeypatch):
    monkeypatch.setattr(limits, "FLUTTER_ONSET_SOLVES", 40)
    f = critical_friction(meicp.load_scene(SCENES / "two_layers.toml"), flutter=True).flutter
    assert not f.exact and f.lower <= 0.6307634 and f.upper >= 0.6307631 and "budget" in f.evidence


def test_past_the_dense_limit_the_search_gives_the_upper_end_only(monkeypatch):
    """FLUTTER_DENSE_MAX below the pencil's order: the search proves flutter, never its
    absence — lower end 0, not exact, the upper end a certified mode above the dense proof."""
    scene = meicp.load_scene(SCENES / "two_layers.toml")
    dense = critical_friction(scene, bisection=False).flutter
    monkeypatch.setattr(limits, "FLUTTER_DENSE_MAX", 10)
    f = critical_friction(scene, bisection=False).flutter
    assert f.lower == 0 and not f.exact and dense.lower <= f.upper < np.inf and "never its absence" in f.evidence
    assert abs(f.mode.sigma.imag) > f.mode.radius


# ----------------------------------------------------------------- combining the onsets

def _onset(lower, upper, exact=True, floor=None):
    return Onset(lower, upper, exact, "", floor=floor)


@pytest.mark.parametrize("div, flu, first, value, exact", [
    (_onset(1.9, 1.9), _onset(0.63, 0.6300006), "flutter", 0.6300006, True),
    (_onset(1.9, 1.9), _onset(2.5, 2.5), "divergence", 1.9, True),
    (_onset(1.9, 1.9), _onset(1.0, 2.5, False), None, 1.9, False),   # overlap: undecided which
    (_onset(1.0, 1.9, False), _onset(0.6, 0.6000001), "flutter", 0.6000001, True),
    (_onset(1.9, 1.9), _onset(0.0, np.inf, False), None, 1.9, False),  # flutter not excluded below 1.9
    (_onset(np.inf, np.inf), _onset(np.inf, np.inf), None, np.inf, True),
    # a σ = 0 onset whose σ > 0 births are excluded only up to its floor: flutter is first only below it
    (_onset(1.9, 1.9, floor=0.7), _onset(0.63, 0.6300006), "flutter", 0.6300006, True),
    (_onset(1.9, 1.9, floor=0.5), _onset(0.63, 0.6300006), None, 0.6300006, False),
    (_onset(1.9, 1.9, floor=0.0), _onset(2.5, 2.5), "divergence", 1.9, True),  # a certified mode at 1.9
])
def test_the_overall_onset_is_the_smaller_one(div, flu, first, value, exact):
    mu = CriticalFriction.of(div, flu)
    assert mu.first == first and float(mu) == value and mu.exact is exact
    assert mu.lower == min(div.proved_free, flu.lower) and mu.upper == min(div.upper, flu.upper)


def test_flutter_is_first_only_where_divergence_born_above_sigma_0_is_excluded(monkeypatch):
    """Past the cross-check (|J| > CRITICAL_J) the divergence bracket is that of σ = 0 modes, so
    "flutter starts first" needs modes of any σ ≥ 0 excluded up to the flutter mode's μ: the
    Rayleigh bound along μ proves it here; when nothing is proved the answer is undecided (it
    said "flutter first" on the σ = 0 lower end alone)."""
    monkeypatch.setattr(limits, "CRITICAL_J", 6)
    scene = two_layer_scene(8, (2, 2), mu=1.0, states="slip-", shear=0.5)
    mu = critical_friction(scene)
    d, f = mu.divergence, mu.flutter
    assert f.exact and f.upper < d.lower and "not looked for" in d.evidence
    assert mu.first == "flutter" and f.upper < d.floor <= d.lower and mu.lower == f.lower
    assert "no divergence mode of any σ ≥ 0 for μ in [0," in d.evidence
    monkeypatch.setattr(solve, "_case_floor", lambda *args: (0.0, "nothing proved"))
    mu = critical_friction(scene)
    assert mu.first is None and mu.divergence.floor == 0.0 and mu.lower == 0.0 and not mu.exact
    assert "born at σ > 0 are excluded only for μ ≤ 0" in mu.evidence


# ------------------------------------------------------------------------ CLI and files

def test_solve_prints_both_onsets_and_results_h5_stores_them(cli, tmp_path):
    import h5py

    code, out, err = cli("solve", SCENES / "two_layers.toml", "--critical-friction", "-o", tmp_path / "o", "-q")
    assert code == 0, err
    lines = out.splitlines()
    first = next(ln for ln in lines if ln.startswith("μ_c"))
    divergence = next(ln for ln in lines if ln.startswith("  divergence"))
    flutter = next(ln for ln in lines if ln.startswith("  flutter "))
    assert "flutter first" in first and "1.90603249 (exact)" in divergence and "exact within" in flutter
    assert "interval cover, a proof" in out and "certified non-real σ" in out
    with h5py.File(tmp_path / "o" / "results.h5") as f:
        g = f["critical_friction"]
        assert g.attrs["first"] == "flutter" and g["flutter"].attrs["upper"] == g.attrs["value"] < 0.6307635
        assert g["divergence"].attrs["value"] == pytest.approx(1.90603249, rel=1e-8) and bool(g["flutter"].attrs["exact"])
        assert g["flutter/mode"].attrs["sigma_imag"] > g["flutter/mode"].attrs["radius"] > 0
    code, out, err = cli("solve", SCENES / "two_layers.toml", "--critical-friction", "--no-flutter", "-o",
                         tmp_path / "n", "-q")
    assert code == 0 and "1.90603249 (exact)" in next(ln for ln in out.splitlines() if ln.startswith("μ_c"))
    assert not any(ln.startswith("  flutter ") for ln in out.splitlines())
    with h5py.File(tmp_path / "n" / "results.h5") as f:
        assert "flutter" not in f["critical_friction"] and "divergence" in f["critical_friction"]


def test_the_probes_past_a_stalled_cover_stay_below_mu_max():
    """The crossing of the test above, asked up to μ_max between the crossing (0.98) and the
    collision (1): the probes past the stalled cover reached a certified mode above μ_max (a
    bracket outside the range asked for); none is looked for there now."""
    fam = family(np.diag([1.0, 3.0, 1.8]), [[0, 1, 0], [-1, 0, 0], [0, 0, 0]])
    onset = dense_onset([fam], start=0.5, mu_max=0.99)
    assert onset.upper == np.inf or onset.upper <= 0.99
    assert onset.lower < 0.99 and not onset.exact
