"""The `meicp` command as scripts and pipelines drive it: --version, --help's exit codes and
PETSc prefixes, `solve --json`, -v/-q after the subcommand, --method/--target/--nev, the
critical friction in results.h5, PETSc options that nothing read or that PETSc rejects,
log stages per phase, progress lines, and the CLI spelling of the API's hints."""

import ast
import json
import logging
import re

import h5py
import pytest

import meicp
from meicp.cli.exit import MEANING, Exit
from meicp.cli.main import build_parser
from meicp.petsc.options import PREFIXES

from .conftest import ROOT, meicp_cmd, mpirun, run

SCENES = ROOT / "data" / "scenes"


def test_version_exits_0():
    out = run(meicp_cmd() + ["--version"])
    assert out.returncode == 0 and out.stdout.strip() == f"meicp {meicp.__version__}"


def test_help_lists_the_exit_codes_and_every_petsc_prefix():
    text = build_parser().format_help()
    for prefix in PREFIXES:
        assert f"-{prefix} " in text, prefix
    for code, meaning in MEANING.items():
        assert f"  {int(code)}  {meaning[:40]}" in text
    assert set(MEANING) == set(Exit)


def test_every_prefix_in_the_code_comes_from_the_registry():
    """No solver spells its own "meicp_…_" prefix: they are the constants of
    meicp.petsc.options, so --help's table cannot miss one."""
    literal = re.compile(r"^meicp_[a-z_]+_$")
    found = []
    for path in (ROOT / "src" / "meicp").rglob("*.py"):
        if path.as_posix().endswith("petsc/options.py"):
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and literal.match(node.value):
                found.append(f"{path.name}: {node.value}")
    assert found == []


@pytest.mark.parametrize("argv, verbosity", [
    (["solve", "s.toml"], (0, False)),
    (["solve", "s.toml", "-v"], (1, False)),
    (["-v", "solve", "s.toml", "-vv"], (3, False)),
    (["solve", "s.toml", "-q"], (0, True)),
    (["-q", "lcp", "f.dat"], (0, True)),
    (["eicp", "f.h5", "-v"], (1, False)),
    (["info", "-q"], (0, True)),
])
def test_v_and_q_are_accepted_after_the_subcommand_too(argv, verbosity):
    from meicp.cli.arguments import verbosity_of

    assert verbosity_of(build_parser().parse_args(argv)) == verbosity


def test_solve_json_is_the_only_stdout_and_carries_sigma_and_mu_c(tmp_path):
    """`--json` with -v after the subcommand: progress on stderr, one JSON document on stdout."""
    out = run(meicp_cmd() + ["solve", str(SCENES / "two_layers.toml"), "--json", "--critical-friction",
                             "-o", str(tmp_path / "o"), "-v"])
    assert out.returncode == 0, out.stderr
    doc = json.loads(out.stdout)
    assert doc["verdict"] == "UNSTABLE" and doc["stable"] is False and doc["analysis"] == "instability"
    assert doc["modes"][0]["sigma"] == pytest.approx(0.3290549424, rel=1e-9)
    assert doc["modes"][0]["support"] == [0, 1, 2, 3, 4] and doc["modes"][0]["residual"] <= 1e-10
    mu_c = doc["critical_friction"]  # flutter starts first (docs/flutter.md §6), divergence at 1.906
    assert mu_c["divergence"]["value"] == pytest.approx(1.906032490, rel=1e-8) and mu_c["found"] is True
    assert mu_c["first"] == "flutter" and mu_c["value"] == mu_c["flutter"]["upper"] == pytest.approx(0.6307632, rel=1e-6)
    assert set(mu_c) == {"value", "found", "lower", "upper", "exact", "evidence", "first", "divergence", "flutter"}
    assert doc["output"]["results"].endswith("results.h5") and doc["versions"]["petsc"]
    assert set(doc["wall"]) >= {"analyze", "critical_friction", "write", "total"}
    assert "analysis: started" in out.stderr  # progress went to stderr
    with h5py.File(tmp_path / "o" / "results.h5") as f:
        g = f["critical_friction"]
        assert g.attrs["value"] == pytest.approx(mu_c["value"], rel=1e-14) and bool(g.attrs["found"])
        assert "enumerated" in g.attrs["evidence"] and g["divergence"].attrs["value"] == mu_c["divergence"]["value"]


def test_infinite_ends_of_the_critical_friction_are_null_with_a_flag_in_json():
    """A direction proved free of σ = 0 modes at every μ has lower = upper = value = inf
    (results.h5 stores the float inf).  --json wrote null (read as "unknown"), then the string
    "inf" (a string where a number belongs); now null with ``<key>_infinite: 1``, and NaN stays
    a bare null (solve --critical-friction with a finite lower end: tests/test_hostile_api.py,
    solve-critical-friction-inf-json)."""
    from types import SimpleNamespace

    from meicp.cli.solve import solve_json
    from meicp.contact.critical_friction import CriticalFriction
    from meicp.contact.result import InstabilityResult

    mu = CriticalFriction(float("inf"), float("inf"), True, "proved at every μ")
    doc = solve_json(SimpleNamespace(scene="s.toml"), meicp.load_scene(SCENES / "two_layers.toml"),
                     InstabilityResult(status="solved"), ranks=1, mu_c=mu)
    got = doc["critical_friction"]
    assert {k: got[k] for k in ("value", "found", "lower", "upper", "exact", "evidence", "value_infinite",
                                "lower_infinite", "upper_infinite")} == {
        "value": None, "found": False, "lower": None, "upper": None, "exact": True, "evidence": "proved at every μ",
        "value_infinite": 1, "lower_infinite": 1, "upper_infinite": 1}
    assert (doc["format"], doc["format_version"]) == ("meicp-solve", 2)
    # the onsets' records: an infinite end said by their flags (flutter not analysed: None)
    assert got["first"] is None and got["flutter"] is None
    assert got["divergence"]["lower"] is None and got["divergence"]["none_at_any_mu"] is True
    assert got["divergence"]["found"] is False
    json.dumps(doc, allow_nan=False)  # valid JSON


def test_overrides_of_the_scenes_solver_table(cli, tmp_path):
    code, out, err = cli("solve", SCENES / "two_layers.toml", "-o", tmp_path / "o", "-q",
                         "--method", "active-set", "--target", "0.1", "--nev", "2")
    assert code == Exit.OK, err
    assert re.search(r"^evidence\s+search from σ = 0\.1: a certified divergence mode", out, re.M), out  # --target
    with h5py.File(tmp_path / "o" / "results.h5") as f:
        assert dict(f["overrides"].attrs) == {"method": "active-set", "target": 0.1, "nev": 2}
        assert f.attrs["verdict"] == "unstable"
    code, out, err = cli("solve", SCENES / "sheared.toml", "--no-output", "-q", "--nev", "2")
    assert code == Exit.OK and "2 certified vibration modes" in out
    with pytest.raises(SystemExit) as exc:  # argparse: a method analyze cannot decide with
        cli("solve", SCENES / "two_layers.toml", "--no-output", "--method", "rayleigh")
    assert exc.value.code == Exit.BAD_INPUT


def test_an_inconclusive_search_says_what_to_type(cli, tmp_path):
    """The active-set search proves nothing when it finds no mode; its advice is spelt as
    this command's flag, not as Python ("method='enumerate'").  A floating lattice (top free,
    every contact separated: three σ = 0 rigid motions, within rounding of the Rayleigh
    bound) searched away from them (target −5) is undecided."""
    text = (SCENES / "two_layers.toml").read_text()
    for old, new in (('top = "fixed"', 'top = "free"'), ("top_displacement = [0.06, -0.1]", ""),
                     ('states = "slip+"', 'states = "separated"')):
        assert old in text
        text = text.replace(old, new)
    scene = tmp_path / "floating.toml"
    scene.write_text(text)
    code, out, err = cli("solve", scene, "--no-output", "-q", "--method", "active-set", "--target", "-5",
                         "--nev", "1")
    assert code == Exit.FAILED
    assert "use --method enumerate" in out and "method='" not in out


def test_a_flutter_mode_answers_when_the_divergence_search_is_inconclusive(tmp_path):
    """Density 1e-300 in layer A: the enumeration is undecided (LAPACK's QZ does not converge)
    while certified flutter modes prove the scene unstable.  The question is answered: exit
    0 and status ``solved`` in the JSON and in results.h5 alike (it exited 1, "FAILED
    (inconclusive), last verdict UNSTABLE"), divergence undecided with the failure named."""
    text = (SCENES / "two_layers.toml").read_text()
    assert text.count("density = 1.0") == 1  # layer A's (B has 2.0)
    scene = tmp_path / "light.toml"
    scene.write_text(text.replace("density = 1.0", "density = 1e-300"))
    out = run(meicp_cmd() + ["solve", str(scene), "--json", "-o", str(tmp_path / "o"), "-q"])
    assert out.returncode == Exit.OK, out.stderr
    doc = json.loads(out.stdout)
    assert (doc["verdict"], doc["stable"], doc["divergence"], doc["flutter"]) == ("UNSTABLE", False, None, True)
    assert doc["status"] == "solved" and doc["success"] is True
    assert "did not converge" in doc["divergence_failure"] and doc["message"] == doc["divergence_failure"]
    with h5py.File(tmp_path / "o" / "results.h5") as f:
        a = f.attrs
        assert (a["status"], bool(a["success"]), a["verdict"]) == ("solved", True, "unstable")
        assert (a["stable"], a["divergence"], a["flutter"]) == (0, -1, 1)
        assert a["divergence_failure"] == doc["divergence_failure"]


def test_unused_petsc_options_are_reported_whatever_their_prefix_and_stages_are_logged():
    """`-- -eps_tol 1e-3` (no prefix) was silently ignored; -log_view showed one "Main Stage"."""
    out = run(meicp_cmd() + ["solve", str(SCENES / "two_layers.toml"), "--no-output", "-q", "--",
                             "-eps_tol", "1e-3", "-meicp_as_eps_tol", "1e-9", "-log_view"])
    assert out.returncode == 0, out.stderr
    assert re.search(r"PETSc options not used by any solver: -eps_tol, -meicp_as_eps_tol$", out.stderr, re.M)
    stages = out.stdout.split("Summary of Stages:")[1].split("\n\n")[0]
    for phase in ("assemble", "reduce", "eigen"):
        assert re.search(rf"^\s*\d+:\s+{phase}:", stages, re.M), stages


def test_a_value_petsc_rejects_is_named_as_bad_input():
    out = run(meicp_cmd() + ["solve", str(SCENES / "sheared.toml"), "--no-output", "-q", "--",
                             "-meicp_ghep_eps_tol", "abc"])
    assert out.returncode == Exit.BAD_INPUT, out.stderr
    assert "PETSc cannot use an option value under -meicp_ghep_: Input string abc has no numeric value" in out.stderr
    assert "(given: -meicp_ghep_eps_tol abc)" in out.stderr and "Traceback" not in out.stderr


def test_modal_analysis_as_json_on_two_ranks():
    """A scene without contact on 2 ranks: the distributed modal analysis, printed once."""
    out = run(mpirun(2) + meicp_cmd() + ["solve", str(SCENES / "sheared.toml"), "--no-output", "--json",
                                          "--critical-friction"], timeout=180)
    assert out.returncode == 0, out.stderr
    doc = json.loads(out.stdout)
    assert doc["ranks"] == 2 and doc["analysis"] == "modal" and doc["verdict"] == "NO CONTACT: modal analysis"
    assert doc["stable"] is True and doc["critical_friction"] is None and len(doc["modes"]) == 6
    serial = meicp.analyze(SCENES / "sheared.toml")
    assert [m["sigma"] for m in doc["modes"]] == pytest.approx([m.sigma for m in serial.modes], rel=1e-9)
    assert all(m["frequency"] == pytest.approx((-m["sigma"]) ** 0.5) for m in doc["modes"])


def test_progress_lines_of_a_long_enumeration(monkeypatch, caplog):
    """An enumeration over 8,192 supports printed nothing for 7.8 s, even with -vv."""
    import numpy as np

    from meicp.core import progress

    monkeypatch.setattr(progress, "FIRST", 0.0)
    monkeypatch.setattr(progress, "INTERVAL", 0.0)
    rng = np.random.default_rng(0)
    A = -rng.uniform(0.1, 1.0, (13, 13))
    with caplog.at_level(logging.INFO, logger="meicp"):
        r = meicp.solve_eicp(A, np.eye(13), method="enumerate")
    assert len(r.solutions) == 2 ** 13 - 1
    lines = [m.getMessage() for m in caplog.records if m.getMessage().startswith("enumeration:")]
    assert len(lines) >= 10
    assert re.match(r"enumeration: [\d,]+ of 8,192 supports \(\d+ %\), [\d,.]+ supports/s, (about|under) .+ "
                    r"left; support size 1 of 13", lines[1]), lines[1]
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="meicp"):  # -q
        meicp.solve_eicp(A[:6, :6], np.eye(6), method="enumerate")
    assert not caplog.records


def test_progress_is_throttled_by_time():
    from meicp.core.progress import FIRST, INTERVAL, Progress

    now = [0.0]
    logger = logging.getLogger("meicp")
    records = []
    handler = logging.Handler()
    handler.emit = records.append
    logger.addHandler(handler)
    level = logger.level
    logger.setLevel(logging.INFO)
    try:
        p = Progress("search", total=100, unit="steps", clock=lambda: now[0])
        for k in range(1, 101):
            now[0] = 0.05 * k  # 5 s in all
            p.update(k)
    finally:
        logger.removeHandler(handler)
        logger.setLevel(level)
    assert len(records) == 1 + int((5.0 - FIRST) // INTERVAL)
    assert re.fullmatch(r"search: 40 of 100 steps \(40 %\), 20 steps/s, about 3 s left", records[0].getMessage())


def test_petsc_table_entries_no_solver_read_are_reported(tmp_path):
    """two_layers.toml is small enough to enumerate densely: its [petsc] table reaches no
    solver, so a value PETSc would reject ("abc") went unnoticed with exit 0; at 30 contacts
    the SLEPc search reads it and nothing is reported."""
    text = (SCENES / "two_layers.toml").read_text()
    small = tmp_path / "small.toml"
    small.write_text(text.replace("eps_tol = 1e-10", 'eps_tol = "abc"'))
    out = run(meicp_cmd() + ["solve", str(small), "--no-output", "-q", "--no-flutter"])
    assert out.returncode == 0, out.stderr
    assert re.search(r"\[petsc\] entries reached no PETSc solver .*: eps_tol$", out.stderr, re.M), out.stderr
    wide = tmp_path / "wide.toml"
    wide.write_text(text.replace("nx = 5", "nx = 30"))
    out = run(meicp_cmd() + ["solve", str(wide), "--no-output", "-q", "--no-flutter"])
    assert "reached no PETSc solver" not in out.stderr, out.stderr


def test_every_json_document_writes_numbers_as_numbers():
    # lcp --json wrote ±inf as null (read as "unknown"), solve --json as the strings "inf"/"-inf";
    # now one convention for every document (meicp.core.json_values): a number or null, an
    # infinite one flagged by its sign in <key>_infinite (a list's flag: a list of signs)
    import numpy as np

    from meicp.core.json_values import json_ready

    doc = json_ready({"scale": np.float64(np.inf), "game": {"value": -np.inf, "x": (np.nan, 2)},
                      "window": [0.0, np.inf], "flag": np.bool_(True), "n": np.int64(3), "timings": {"t": 0.5},
                      "x": np.array([1.0, -np.inf])})
    assert doc == {"scale": None, "scale_infinite": 1, "game": {"value": None, "value_infinite": -1, "x": [None, 2]},
                   "window": [0.0, None], "window_infinite": [0, 1], "flag": True, "n": 3, "timings": {"t": 0.5},
                   "x": [1.0, None], "x_infinite": [0, -1]}
    assert json.loads(json.dumps(doc, allow_nan=False)) == doc  # valid JSON, no Infinity/NaN tokens
