"""The certified bracket of the fastest flutter growth rate (docs/flutter.md §4a): the disk
bound, the dense bracket against an independent QZ, the search's bracket that never claims
the fastest, and the bracket in the CLI table, --json and results.h5."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import scipy.linalg as sl
from hypothesis import given, settings
from hypothesis import strategies as st

import meicp
from meicp.contact import flutter as fl
from meicp.contact.flutter_growth import (EXACT_WIDTH, FlutterGrowth, combine_growths, disk_growth_range,
                                         rectangle_growth)
from meicp.contact.problem import pencil
from meicp.examples import two_layer_scene

from .conftest import ROOT
from .test_flutter import lattice

SCENES = ROOT / "data" / "scenes"


@settings(max_examples=200, deadline=None)
@given(re=st.floats(-50, 50), im=st.floats(-20, 20), r=st.floats(0, 5),
       angle=st.floats(0, 2 * math.pi), t=st.floats(0, 1))
def test_every_point_of_a_disk_grows_within_its_range(re, im, r, angle, t):
    sigma = complex(re, im)
    lo, hi = disk_growth_range(sigma, r)
    z = sigma + t * r * complex(math.cos(angle), math.sin(angle))
    g = np.sqrt(complex(z)).real
    assert lo - 1e-12 * (1 + hi) <= g <= hi + 1e-12 * (1 + hi)


def qz_growths(scene):
    """Re √σ of every finite non-real σ of the sliding pencil, by scipy.linalg.eig on (A, B)."""
    with pencil(scene) as pen:
        A, B = pen.A.toarray(), pen.B.toarray()
    w = sl.eig(A, B, right=False)
    w = w[np.isfinite(w) & (np.abs(w.imag) > 1e-8 * np.abs(w).max())]
    return np.sqrt(w.astype(complex)).real


@pytest.mark.parametrize("scene", [lattice(20, (2, 2), 0.3), lattice(12, (3, 3), 1.0, states="slip-"),
                                   lattice(16, (2, 3), 3.0, shear=0.5)], ids=["mu0.3", "slip-", "sheared"])
def test_dense_bracket_is_exact_and_holds_the_fastest(scene):
    r = meicp.analyze(scene)
    g = r.flutter_growth
    fastest = qz_growths(scene).max()
    assert g.exact and g.lower <= fastest <= g.upper
    assert g.upper - g.lower <= EXACT_WIDTH * g.upper
    assert math.isclose(float(g), r.flutter_modes[0].growth_rate, rel_tol=1e-9)
    assert "the fastest, proved" in g.describe()


def test_interface_bracket_by_qz():
    scene = meicp.load_scene(SCENES / "frictional_interface.toml")
    g = meicp.analyze(scene).flutter_growth
    assert g.exact and g.lower <= qz_growths(scene).max() <= g.upper


def test_proved_flutter_free_is_a_zero_bracket():
    r = meicp.analyze(lattice(20, (2, 2), 0.0))
    assert r.flutter is False and r.flutter_growth.upper == 0.0 and r.flutter_growth.exact
    assert "no flutter (proved)" in r.flutter_growth.describe()


def test_search_bracket_never_claims_the_fastest():
    scene = lattice(32, (8, 8), 2.0)
    with pencil(scene) as pen:
        got = fl.pencil_flutter(pen, scene, dense_max=0)
        ref = fl.pencil_flutter(pen, scene)
    assert got.flutter is True and not got.growth.exact
    assert 0 < got.growth.lower <= ref.growth.upper <= got.growth.upper < math.inf
    assert "not proved the fastest" in got.growth.describe() and "Bendixson's rectangle" in got.growth.evidence


@pytest.mark.parametrize("real_max, imag_max", [(0.0, 1.7), (-0.5, 0.1), (2.0, 0.0), (-3.0, 0.0), (1e-3, 40.0)])
def test_the_rectangle_bound_is_its_corner(real_max, imag_max):
    """No σ with Re σ ≤ real_max, |Im σ| ≤ imag_max grows faster than the corner (sampled
    densely over the rectangle's boundary and inside), and the corner itself is attained."""
    x = np.linspace(real_max - 5.0, real_max, 201)
    y = np.linspace(-imag_max, imag_max, 201)
    z = x[:, None] + 1j * y[None, :]
    worst = np.sqrt(z).real.max()
    bound = rectangle_growth(real_max, imag_max)
    assert worst <= bound and bound <= np.sqrt(complex(real_max, imag_max)).real * (1 + 1e-14)
    assert rectangle_growth(math.inf, 1.0) == math.inf


@settings(max_examples=15, deadline=None)
@given(nx=st.integers(6, 24), rows=st.integers(2, 4), mu=st.floats(0.05, 6.0), state=st.sampled_from(["slip+", "slip-"]))
def test_the_search_bracket_holds_qz_fastest(nx, rows, mu, state):
    """On random base-contact lattices the search's bracket (a certified mode below,
    Bendixson's rectangle above — Gershgorin's Re σ bound, or the divergence verdict's
    Rayleigh bound) contains the fastest growth of every eigenvalue QZ finds."""
    scene = two_layer_scene(nx, (rows, rows), mu=mu, states=state, shear=0.5)
    searched, dense = meicp.analyze(scene, flutter_dense_max=0), meicp.analyze(scene)
    growth = searched.flutter_growth
    fastest = qz_growths(scene).max(initial=0.0)
    assert growth.upper is not None and growth.lower <= dense.flutter_growth.upper * (1 + 1e-9)
    assert fastest <= growth.upper and dense.flutter_growth.lower <= growth.upper


def test_branches_combine_to_the_widest_bracket():
    a, b = FlutterGrowth(0.2, 0.2000000001, "a"), FlutterGrowth(0.1, 0.3, "b")
    both = combine_growths([a, b])
    assert (both.lower, both.upper) == (0.1, 0.3) and not both.exact
    assert combine_growths([a, FlutterGrowth(0.1, None)]).upper is None
    assert combine_growths([None]) is None


def test_a_large_pencil_says_not_proved_in_the_table_json_and_h5(cli, tmp_path, monkeypatch):
    import h5py

    out = tmp_path / "run"
    code, text, _ = cli("solve", SCENES / "two_layers.toml", "-o", out, "--json", "-q")
    doc = json.loads(text)
    assert code == 0 and doc["flutter_growth"]["exact"] is True
    assert math.isclose(doc["flutter_growth"]["lower"], doc["flutter_modes"][0]["growth_rate"], rel_tol=1e-9)
    with h5py.File(out / "results.h5") as f:
        assert f.attrs["flutter_growth_exact"] == 1
        assert math.isclose(f.attrs["flutter_growth_upper"], doc["flutter_growth"]["upper"])
    code, text, _ = cli("solve", SCENES / "two_layers.toml", "--no-output", "-q")
    assert "the fastest, proved" in text and "fastest first)" in text


def test_search_result_rows_say_fastest_found(monkeypatch):
    from meicp.core import limits

    monkeypatch.setattr(limits, "FLUTTER_DENSE_MAX", 0)
    scene = lattice(32, (8, 8), 2.0)
    r = meicp.analyze(scene)
    rows = dict((k, v) for k, v in r.summary_rows(scene) if k)
    assert r.flutter is True and not r.flutter_growth.exact
    assert "not proved the fastest" in rows["flutter growth"]
    assert "fastest found first, not proved the fastest" in rows["flutter modes"]
    # the upper end is Bendixson's rectangle: finite, loose, and written as a number
    assert "proved ≤" in rows["flutter growth"]
    assert r.to_dict()["flutter_growth"]["upper"] == r.flutter_growth.upper < math.inf
    assert "upper_infinite" not in r.to_dict()["flutter_growth"] and r.to_dict()["flutter_growth"]["upper_loose"]
    assert "by Bendixson's rectangle" in rows["flutter growth"]


def test_flutter_dense_max_buys_the_exact_bracket(monkeypatch, cli):
    """Past the dense limit the search gives a lower bound only; flutter_dense_max (and
    --flutter-dense-max) takes the dense path further: the same fastest mode, proved."""
    from meicp.core import limits
    from meicp.core.errors import ProblemError

    monkeypatch.setattr(limits, "FLUTTER_DENSE_MAX", 0)
    scene = lattice(32, (8, 8), 2.0)
    found = meicp.analyze(scene)
    proved = meicp.analyze(scene, flutter_dense_max=2000)
    assert not found.flutter_growth.exact and proved.flutter_growth.exact
    assert found.flutter_growth.lower <= proved.flutter_growth.upper * (1 + 1e-12)
    for bad in (-1, 2.5, True, "100"):
        with pytest.raises(ProblemError, match="flutter_dense_max"):
            meicp.analyze(scene, flutter_dense_max=bad)
    code, text, _ = cli("solve", SCENES / "two_layers.toml", "--no-output", "-q", "--flutter-dense-max", "0")
    assert code == 0 and "not proved the fastest" in text
    with pytest.raises(SystemExit) as exit_:  # argparse's usage error
        cli("solve", SCENES / "two_layers.toml", "--no-output", "-q", "--flutter-dense-max", "-3")
    assert exit_.value.code == 2


@settings(max_examples=12, deadline=None)
@given(nx=st.integers(4, 10), lower=st.integers(1, 3), upper=st.integers(1, 3), mu=st.floats(0.05, 4.0),
       shear=st.sampled_from([0.0, 0.4, -0.3]), state=st.sampled_from(["slip+", "slip-"]))
def test_the_fastest_growth_of_qz_lies_in_the_bracket(nx, lower, upper, mu, shear, state):
    scene = lattice(nx, (lower, upper), mu, states=state, shear=shear)
    g = meicp.analyze(scene, flutter=True).flutter_growth
    growths = qz_growths(scene)
    fastest = growths.max() if growths.size else 0.0
    assert g.lower <= fastest * (1 + 1e-9) + 1e-300
    if g.upper is not None:
        assert fastest <= g.upper * (1 + 1e-9)


def test_a_defective_eigenvalue_widens_the_bracket_never_breaks_it():
    """A Jordan block of σ = −1 (κ infinite: its disk is unbounded) beside a clear flutter
    pair: the pair is certified, the bracket is not exact, and it still holds the pair."""
    A = np.array([[-1.0, 1.0, 0.0, 0.0], [0.0, -1.0, 0.0, 0.0], [0.0, 0.0, -4.0, 1.0], [0.0, 0.0, -1.0, -4.0]])
    got = fl.dense_flutter(A, np.eye(4))
    pair = np.sqrt(complex(-4.0, 1.0)).real
    assert got.flutter is True and got.growth.lower <= pair <= got.growth.upper
    assert not got.growth.exact
