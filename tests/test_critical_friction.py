"""The certified bracket of the critical friction (issue 14 part 4): it contains the
enumerated μ_c, its float behaves as a float, and a frictional interface or a large |J|
still gets an honest answer."""
import json
import math
import pickle
from pathlib import Path

import h5py
import numpy as np
import pytest

import meicp
import meicp.contact.critical_friction.solve as cf
from meicp.contact.critical_friction import CriticalFriction, critical_friction
from meicp.core import limits
from meicp.core.errors import ProblemError

from meicp.examples import two_layer_scene

SCENES = [(nx, states, shear) for nx in (6, 9, 12) for states in ("slip+", "slip-") for shear in (0.5, -0.5)]


@pytest.mark.parametrize("nx,states,shear", SCENES)
def test_the_bracket_contains_the_enumerated_critical_friction(nx, states, shear, monkeypatch):
    scene = two_layer_scene(nx, (2, 2), mu=1.0, states=states, shear=shear)
    exact = critical_friction(scene, bisection=False, flutter=False)
    assert exact.exact and exact.lower == exact.upper == float(exact)
    monkeypatch.setattr(limits, "CRITICAL_J", 0)  # force the bracket on a scene enumeration can check
    b = critical_friction(scene, flutter=False)
    assert b.lower <= b.upper and "lower end" in b.evidence
    if math.isfinite(exact):
        assert b.lower <= exact * (1 + 1e-12) and b.upper >= exact * (1 - 1e-12)
        assert math.isfinite(b.upper) and b.upper == pytest.approx(float(exact), rel=1e-9)  # found the mode
    else:
        assert b.upper == np.inf


def test_the_float_behaves_as_a_float():
    mu = CriticalFriction(1.5, 1.4, False, "a proof and a mode")
    assert mu == 1.5 and mu + 1 == 2.5 and mu < 2 and f"{mu:.3f}" == "1.500" and math.isfinite(mu)
    assert isinstance(mu, float) and json.dumps(float(mu)) == "1.5" and np.float64(mu) == 1.5
    back = pickle.loads(pickle.dumps(mu))
    assert (back, back.lower, back.upper, back.exact, back.evidence) == (1.5, 1.4, 1.5, False, "a proof and a mode")
    assert "in [1.4, 1.5]" in mu.describe() and mu.width == pytest.approx(1 / 15)
    none = CriticalFriction(np.inf, 3.0, False, "")
    assert none == np.inf and none.width == np.inf and "no σ = 0 mode found" in none.describe()


def test_a_wide_lattice_gets_a_narrow_bracket():
    mu = critical_friction(two_layer_scene(60, (2, 2), mu=1.0, states="slip-", shear=0.5), flutter=False)
    assert mu.exact and 1.080 < mu.lower <= mu.upper < 1.4605 and mu.width <= cf.EXACT_WIDTH  # issue 14: ≤ 1.4605
    assert "certified on the whole reduced lattice" in mu.evidence


def test_a_stable_direction_is_proved_free_of_modes_at_every_mu():
    mu = critical_friction(two_layer_scene(40, (4, 4), mu=1.0, states="slip+", shear=0.5), flutter=False)
    assert mu == np.inf and mu.lower == np.inf and mu.exact and "∞" in mu.evidence


def test_cli_prints_the_bracket_and_results_h5_stores_it(cli, tmp_path):
    import h5py

    scenes = Path(__file__).resolve().parents[1] / "data" / "scenes"
    text = (scenes / "two_layers.toml").read_text().replace("nx = 5", "nx = 30")
    path = tmp_path / "wide.toml"
    path.write_text(text)
    code, out, err = cli("solve", path, "--critical-friction", "--no-flutter", "-o", tmp_path / "o", "-q")
    assert code == 0, err
    line = next(ln for ln in out.splitlines() if ln.startswith("μ_c"))
    assert "exact" in line and "proved ≥" in line and "|J| = 30: lower end" in out
    with h5py.File(tmp_path / "o" / "results.h5") as f:
        g = f["critical_friction"].attrs
        assert g["lower"] <= g["value"] == g["upper"] and bool(g["exact"]) and "upper end" in g["evidence"]


def test_the_lower_end_is_at_least_the_uncondensed_bound():
    """μ_lo = 1/λ_max(−sym(P̃₁KQ̃), Q̃ᵀKQ̃) of the issue; the condensed proof is never weaker."""
    import scipy.linalg as sl

    from meicp.contact.condensation import pieces_of
    from meicp.contact.lines import contact_lines
    from meicp.contact.maps import reduced_system
    from meicp.lattice.assembly import assemble_scipy
    from meicp.lattice.model import LatticeModel

    scene = two_layer_scene(24, (2, 2), mu=1.0, states="slip-", shear=0.5)
    model = LatticeModel(scene)
    K, M = assemble_scipy(model)
    p = pieces_of(K, M, reduced_system(model, contact_lines(scene, model), ()), friction="unit")
    N = p.N.toarray()
    top = sl.eigh(-0.5 * (N + N.T), p.Kt.toarray(), eigvals_only=True)[-1]
    mu = critical_friction(scene, flutter=False)
    assert 0 < 1 / top <= mu.lower <= mu.upper


@pytest.mark.parametrize("name", ["frictional_interface", "sheared_slip_minus", "two_layers"])
def test_the_bracket_contains_the_enumerated_value_on_shipped_scenes(name, monkeypatch):
    """Including a frictional interface (its slip rows are in J too: at σ = 0 the split holds)."""
    import meicp

    scene = meicp.load_scene(Path(__file__).resolve().parents[1] / "data" / "scenes" / f"{name}.toml")
    exact = critical_friction(scene, bisection=False, flutter=False)
    monkeypatch.setattr(limits, "CRITICAL_J", 0)
    b = critical_friction(scene, flutter=False)
    assert b.lower <= exact * (1 + 1e-12) and b.upper >= exact * (1 - 1e-12)


def test_divergence_born_above_zero_is_no_contradiction_of_mu_c():
    """Tall soft-under-stiff lattice sheared against its slip: a pair of real σ > 0 is born
    near μ ≈ 494 (out of a complex pair) and never passes through σ = 0.  μ_c (σ = 0) does
    not exist up to mu_max, which the bisection check took for a contradiction and raised
    ConvergenceError (and `solve --critical-friction` threw the finished analysis away); the
    evidence now says where the modes start and that they start above σ = 0."""
    import re

    import meicp

    scene = two_layer_scene(6, (2, 6), mu=500.0, states="slip-", shear=-0.5)
    got = critical_friction(scene, flutter=False)
    assert math.isinf(float(got)) and got.lower == 1000.0 and got.exact
    start = float(re.search(r"from μ ≈ ([0-9.]+), born at σ", got.evidence).group(1))

    def at(mu):
        return meicp.analyze(scene.with_friction(mu), method="enumerate", flutter=False)

    above, below = at(start * 1.001), at(start * 0.999)
    assert above.divergence is True and min(m.sigma for m in above.modes) > 1e-3
    assert below.divergence is False


def test_solve_keeps_its_analysis_when_the_critical_friction_fails(cli, tmp_path, monkeypatch):
    """`solve --critical-friction` printed nothing and wrote nothing when μ_c failed after the
    analysis had finished; now the summary and the outputs stand, μ_c says why (a warning, a
    row, a JSON field and results.h5's /critical_friction), and the exit code is the verdict's:
    μ_c is an extra (a floating layer, where μ_c is undefined: tests/test_hostile_scene.py)."""
    import json

    import meicp.cli.solve as solve
    from meicp.core.errors import ConvergenceError

    def failing(scene, comm=None, flutter=None):
        raise ConvergenceError("μ as an eigenvalue and existence disagree")

    monkeypatch.setattr(solve, "critical_friction", failing)
    scenes = Path(__file__).resolve().parents[1] / "data" / "scenes"
    code, text, err = cli("solve", scenes / "two_layers.toml", "--critical-friction", "-o", tmp_path / "o", "-q")
    assert code == 0 and "UNSTABLE" in text and "μ_c               not determined: μ as an eigenvalue" in text
    assert "μ_c not determined: μ as an eigenvalue" in err  # the warning, under -q too
    with h5py.File(tmp_path / "o" / "results.h5") as f:
        assert f["critical_friction"].attrs["error"] == "μ as an eigenvalue and existence disagree"
    code, text, err = cli("solve", scenes / "two_layers.toml", "--critical-friction", "--json", "--no-output")
    doc = json.loads(text)
    assert code == 0 and doc["critical_friction"] == {"error": "μ as an eigenvalue and existence disagree"}


SCENE_DIR = Path(__file__).resolve().parents[1] / "data" / "scenes"


def test_critical_friction_of_a_scene_without_contact_is_refused():
    """No rough base, no frictional interface: nothing for friction to be critical for — a
    ProblemError naming what is missing, not the bisection check's ConvergenceError."""
    with pytest.raises(ProblemError, match="needs a frictional contact"):
        critical_friction(meicp.load_scene(SCENE_DIR / "four_node_cell.toml"))
    with pytest.raises(ProblemError, match="needs a frictional contact"):
        critical_friction(meicp.load_scene(SCENE_DIR / "embedded_layer.toml"))
