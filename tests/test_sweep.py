"""``meicp.sweep`` and ``meicp sweep``: each row is ``meicp.analyze`` of the changed scene, a
rerun into the same directory skips what is done, and bad keys, values and ranges are refused
before any work."""

import csv
import json
import logging

import numpy as np
import pytest

import meicp
from meicp.core import limits
from meicp.core.errors import ProblemError
from meicp.study import Onset, SweepRow, parameter_keys, parse_values, scene_with
from meicp.study import driver
from meicp.study.result import read_rows

from .conftest import ROOT

SCENES = ROOT / "data" / "scenes"
TWO_LAYERS = SCENES / "two_layers.toml"
#: across both onsets of two_layers.toml (flutter from 0.6308, divergence from 1.906)
MUS = [0.3, 1.0, 2.5]


@pytest.fixture
def scene():
    return meicp.load_scene(TWO_LAYERS)


@pytest.fixture
def counted(monkeypatch):
    """The analyses the sweep runs, counted (by value)."""
    calls = []
    real = driver.analyze

    def analyze(scene, comm=None, **options):
        calls.append(scene.contact.friction)
        return real(scene, comm, **options)

    monkeypatch.setattr(driver, "analyze", analyze)
    return calls


def _columns(path, drop=("seconds",)):
    with open(path, newline="") as f:
        return [{k: v for k, v in row.items() if k not in drop} for row in csv.DictReader(f)]


def test_each_row_is_analyze_of_the_changed_scene(scene):
    result = meicp.sweep(scene, "friction", MUS, progress=False)
    assert result.values == MUS
    for row, mu in zip(result.rows, MUS):
        r = meicp.analyze(scene_with(scene, "friction", mu))
        assert (row.divergence, row.flutter, row.stable, row.verdict) == (r.divergence, r.flutter, r.stable, r.verdict)
        assert row.sigma == (r.modes[0].sigma if r.modes else None)
        assert row.flutter_growth == (r.flutter_modes[0].growth_rate if r.flutter_modes else None)
        assert row.status == r.status
    # the grid brackets both onsets where two_layers.toml has them (docs/flutter.md §6)
    assert (result.flutter_onset.lower, result.flutter_onset.upper) == (0.3, 1.0)
    assert (result.divergence_onset.lower, result.divergence_onset.upper) == (1.0, 2.5)
    assert "μ_c ∈ (1, 2.5]" in repr(result) and len(repr(result)) < 300


def test_flutter_growth_bound_is_proved_by_the_dense_spectrum_only(scene, monkeypatch):
    """Dense path: an upper bound within rounding of the mode found (0 without flutter);
    the search path sees part of the spectrum: its Bendixson bound is proved but loose, so the
    row has no bound and the growth found is a lower bound."""
    rows = meicp.sweep(scene, "friction", [0.3, 2.5], progress=False).rows
    assert rows[0].flutter is False and rows[0].flutter_growth_bound == 0.0
    assert rows[1].flutter_growth <= rows[1].flutter_growth_bound <= rows[1].flutter_growth + 1e-8
    monkeypatch.setattr(limits, "FLUTTER_DENSE_MAX", 0)
    row = meicp.sweep(scene, "friction", [2.5], progress=False).rows[0]
    assert row.flutter is True and row.flutter_growth_bound is None
    searched = meicp.analyze(scene.with_friction(2.5)).flutter_growth
    assert searched.loose and searched.upper >= rows[1].flutter_growth_bound
    assert row.flutter_growth == pytest.approx(rows[1].flutter_growth, rel=1e-8)


def test_a_rerun_skips_the_values_done_and_a_changed_scene_starts_over(scene, counted, tmp_path, caplog):
    out = tmp_path / "sweep"
    first = meicp.sweep(scene, "friction", MUS[:2], out=out, progress=False)
    assert counted == MUS[:2] and sorted(first.files) == ["csv", "json", "png"]
    assert all(p.is_file() for p in first.files.values())
    again = meicp.sweep(scene, "mu", MUS, out=out, progress=False)  # one value more
    assert counted == MUS and again.resumed == 2
    assert [r.value for r in read_rows(out / "sweep.csv")[0]] == MUS
    assert json.loads((out / "sweep.json").read_text())["state"] == "complete"
    # a run cut short mid-line: the cut record is analysed again, the others are not
    text = (out / "sweep.csv").read_text()
    (out / "sweep.csv").write_text(text[:text.rindex("\n", 0, len(text) - 1) + 20])
    counted.clear()
    meicp.sweep(scene, "friction", MUS, out=out, progress=False)
    assert counted == [MUS[-1]]
    counted.clear()
    meicp.sweep(scene, "friction", MUS, out=out, progress=False, resume=False)
    assert counted == MUS
    counted.clear()
    with caplog.at_level(logging.WARNING, logger="meicp"):
        changed = scene_with(scene, "layers.B.density", 3.0)
        result = meicp.sweep(changed, "friction", MUS[:1], out=out, progress=False)
    assert counted == MUS[:1] and "starting over" in caplog.text
    assert result.values == MUS[:1] and len(read_rows(out / "sweep.csv")[0]) == 1


def test_bad_keys_values_and_ranges_are_refused_before_any_work(scene, counted, tmp_path):
    out = tmp_path / "never"
    with pytest.raises(ProblemError, match="unknown parameter 'layers.C.stiffness'.*layers.A.stiffness"):
        meicp.sweep(scene, "layers.C.stiffness", [1.0], out=out)
    with pytest.raises(ProblemError, match="interface 'A' is bonded|bonded: it has no friction"):
        meicp.sweep(scene, "interfaces.A.friction", [1.0], out=out)
    with pytest.raises(ProblemError, match="contact.friction must be >= 0"):
        meicp.sweep(scene, "friction", [1.0, -1.0], out=out)
    with pytest.raises(ProblemError, match="layers\\[1\\].stiffness must be > 0"):
        meicp.sweep(scene, "layers.B.stiffness", "0:5:3", out=out)
    with pytest.raises(ProblemError, match="values: none given"):
        meicp.sweep(scene, "friction", out=out)
    with pytest.raises(ProblemError, match="per_point_comm"):
        meicp.sweep(scene, "friction", [1.0], per_point_comm="all", out=out)
    # an analyze option misspelt is analyze's TypeError, raised before the first value (it was a
    # RuntimeError at the first value, with a sweep.json saying "running" left behind)
    with pytest.raises(TypeError, match="sweep.*'flutterr'.*did you mean 'flutter'"):
        meicp.sweep(scene, "friction", [1.0], out=out, flutterr=False)
    with pytest.raises(TypeError, match="did you mean 'method'"):
        meicp.sweep(scene, "friction", [1.0], out=out, metod="auto")
    assert counted == [] and not out.exists()


@pytest.mark.parametrize("spec, match", [("0:1", "A:B:N"), ("a:1:3", "start A must be a number"),
                                         ("0:1:0", "count N"), ("0:1:2.5", "must be an integer"),
                                         ("0:0:3", "repeats one value"), ("1,,2", "comma-separated"),
                                         ("1,2,1", "repeated"), ("0:inf:3", "finite"), ([], "none given")])
def test_bad_grids_name_the_problem(spec, match):
    with pytest.raises(ProblemError, match=match):
        parse_values(spec)


def test_grids():
    assert parse_values("0:3:4").tolist() == [0.0, 1.0, 2.0, 3.0]
    assert parse_values(" 0.5, 1,2 ").tolist() == [0.5, 1.0, 2.0]
    assert parse_values(np.array([1, 2])).tolist() == [1.0, 2.0]


def test_scene_with_sets_what_its_key_names(scene):
    """A layer's stiffness carries to the bonds the default rule gave (two_layers.toml's
    interface is declared without a stiffness: the mean); load keys set the top row."""
    soft = scene_with(scene, "layers.0.stiffness", 0.5)
    assert soft.layers[0].stiffness == 0.5 and soft.interfaces[0].stiffness == pytest.approx(2.75)
    fixed = scene_with(scene_with(scene, "layers.A.stiffness", 0.5), "layers.B.stiffness", 5.0)
    assert fixed.interfaces[0].stiffness == pytest.approx(2.75)
    load = scene_with(scene_with(scene, "shear", 0.2), "compression", 0.3).load
    assert load.top_displacement == (0.2, -0.3)
    assert scene_with(scene, "lattice.shear", 0.5).lattice.shear == 0.5
    assert scene_with(scene, "mu", 0.7).to_dict() == scene_with(scene, "contact.friction", 0.7).to_dict()
    itf = meicp.load_scene(SCENES / "frictional_interface.toml")
    name = itf.frictional_interfaces()[0].below
    both = scene_with(itf, "friction", 0.25)
    assert {i.friction for i in both.frictional_interfaces()} == {0.25}
    one = scene_with(itf, f"interfaces.{name}.friction", 0.25)
    assert one.frictional_interfaces()[0].friction == 0.25
    assert f"interfaces.{name}.friction" in parameter_keys(itf)
    assert scene.layers[0].stiffness == 1.0  # scenes are frozen: the original is unchanged


def _row(value, divergence, flutter):
    return SweepRow(value, "", None, divergence, None, flutter, None, None, None, "solved", 0.0, "")


def test_onsets_are_brackets_from_the_grid():
    rows = [_row(0.0, False, False), _row(1.0, False, None), _row(2.0, None, True), _row(3.0, True, True)]
    assert Onset.of("divergence", rows) == Onset("divergence", 1.0, 3.0)  # undecided at 2: skipped
    assert Onset.of("flutter", rows) == Onset("flutter", 0.0, 2.0)
    assert Onset.of("divergence", rows[:2]).upper is None
    assert Onset.of("flutter", rows[2:]).lower is None
    assert "not proved absent" in Onset.of("flutter", rows[2:], "μ_f").describe()


def test_csv_round_trip_and_the_map(scene, tmp_path):
    result = meicp.sweep(scene, "friction", MUS, progress=False)
    assert read_rows(result.to_csv(tmp_path / "rows.csv")) == (result.rows, 0)
    png = result.plot(tmp_path / "map.png", marks=[(1.906, "μ_c")])
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(ProblemError, match="does not exist"):
        result.plot(tmp_path / "missing" / "map.png")


def test_cli_sweep_writes_the_table_the_csv_the_json_and_the_map(cli, tmp_path):
    out = tmp_path / "s"
    code, stdout, stderr = cli("sweep", TWO_LAYERS, "--mu", "0.3,1,2.5", "-o", out)
    assert code == 0, stderr
    assert {p.name for p in out.iterdir()} == {"sweep.csv", "sweep.json", "stability_map.png"}
    assert "μ_c ∈ (1, 2.5]" in stdout and "μ_f ∈ (0.3, 1]" in stdout
    assert stderr.count("meicp sweep:") == 3  # one progress line per value
    assert [r["value"] for r in _columns(out / "sweep.csv")] == ["0.3", "1.0", "2.5"]
    code, stdout, stderr = cli("sweep", TWO_LAYERS, "--param", "layers.B.density", "--values", "1,2", "-o",
                               tmp_path / "d", "--json", "-q")
    assert code == 0 and stderr == ""
    doc = json.loads(stdout)
    assert doc["format"] == "meicp-sweep" and doc["parameter"] == "layers.B.density" and len(doc["rows"]) == 2
    # the layout version of every --json document, in sweep.json too (it said 1)
    stored = json.loads((tmp_path / "d" / "sweep.json").read_text(encoding="utf-8"))
    assert doc["format_version"] == stored["format_version"] == 2


@pytest.mark.parametrize("args, match", [(["--mu", "0:3"], "argument --mu: a range is A:B:N"),
                                         (["--mu", "0:3:many"], "count N in A:B:N must be an integer"),
                                         (["--param", "layers.Z.stiffness", "--values", "1,2"],
                                          "unknown parameter 'layers.Z.stiffness'"),
                                         (["--param", "shear", "--mu", "1,2"], "--mu sets the friction"),
                                         ([], "one of the arguments --mu --values is required")])
def test_cli_sweep_bad_input_exits_2_and_writes_nothing(cli, capsys, tmp_path, args, match):
    try:
        code, _, stderr = cli("sweep", TWO_LAYERS, "-o", tmp_path / "s", *args)
    except SystemExit as exc:  # argparse: a usage error naming the flag
        code, stderr = exc.code, capsys.readouterr().err
    assert code == 2 and match in stderr, stderr
    assert not (tmp_path / "s").exists()


def test_fewer_values_than_ranks_end_cleanly(tmp_path):
    """One value on 2 ranks: the idle rank initialises PETSc too (its finalisation is
    collective), else the job aborted at exit with "stack smashing detected"."""
    from .conftest import meicp_cmd, mpirun, run

    res = run(mpirun(2) + meicp_cmd() + ["sweep", str(SCENES / "two_layers.toml"), "--mu", "0.5", "-o",
                                         str(tmp_path / "one"), "-q"], timeout=240)
    assert res.returncode == 0, res.stderr[-2000:]
    assert (tmp_path / "one" / "sweep.csv").read_text().count("\n") == 2


def test_a_damped_sweep_brackets_the_proved_damped_onset(scene):
    """With damping η = 0.02 in both layers each row is the damped analysis, and the grid's
    flutter bracket holds the onset critical_friction proves (1.3845, docs/damping.md)."""
    data = scene.to_dict()
    for layer in data["layers"]:
        layer["viscosity"] = 0.02
    damped = meicp.io.scene.scene_from_dict(data)
    result = meicp.sweep(damped, "friction", [1.0, 1.5, 2.5], progress=False)
    assert [row.stable for row in result.rows] == [True, False, False]
    mu_f = meicp.critical_friction(damped).flutter
    assert result.flutter_onset.lower <= mu_f.lower <= mu_f.upper <= result.flutter_onset.upper
    assert (result.flutter_onset.lower, result.flutter_onset.upper) == (1.0, 1.5)
