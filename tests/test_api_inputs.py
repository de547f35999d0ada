"""The public API made for studies (issue 30): a scene in any form (Scene, path, dict, TOML
text), ``Scene.with_friction`` / ``with_states`` / ``with_load``, explicit keywords (a
misspelt one is a TypeError with the nearest name), every argument checked with a
ProblemError naming it, what ``comm=None`` means, short reprs, and ``meicp.load_results``
reading back what the writer of ``meicp solve`` wrote."""

from __future__ import annotations

import dataclasses
import inspect
import math
import pydoc
import re
import tomllib

import h5py
import numpy as np
import pytest
import scipy.sparse as sp

import meicp
from meicp.core.errors import ProblemError
from meicp.io.results import critical_friction_record, write_results
from meicp.io.scene import as_scene, loads_scene

from .conftest import ROOT

SCENES = ROOT / "data" / "scenes"
TWO_LAYERS = SCENES / "two_layers.toml"
TEXT = TWO_LAYERS.read_text()
M3 = np.array([[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 2.0]])
A2 = -np.array([[1.0, 1.0], [1.0, 2.0]])


def same_scene(a, b) -> bool:
    return dataclasses.replace(a, source=None) == dataclasses.replace(b, source=None)


# ------------------------------------------------------------------ a scene in any form

FORMS = {"Scene": lambda: meicp.load_scene(TWO_LAYERS), "Path": lambda: TWO_LAYERS, "str path": lambda: str(TWO_LAYERS),
         "dict": lambda: tomllib.loads(TEXT), "TOML text": lambda: TEXT,
         "to_dict": lambda: meicp.load_scene(TWO_LAYERS).to_dict()}


@pytest.fixture(scope="module")
def reference():
    scene = meicp.load_scene(TWO_LAYERS)
    return scene, meicp.analyze(scene), meicp.critical_friction(scene)


@pytest.mark.parametrize("form", FORMS)
def test_every_form_of_a_scene_gives_the_same_answer(form, reference):
    scene, result, mu_c = reference
    given = FORMS[form]()
    assert same_scene(as_scene(given), scene)
    r = meicp.analyze(given)
    assert (r.stable, r.divergence, r.flutter, r.states) == (result.stable, result.divergence, result.flutter,
                                                             result.states) == (False, True, True, ["slip+"] * 5)
    assert [m.sigma for m in r.modes] == [m.sigma for m in result.modes]
    assert [m.sigma for m in r.flutter_modes] == [m.sigma for m in result.flutter_modes]
    mu = meicp.critical_friction(given)
    assert (float(mu), mu.lower, mu.exact) == (float(mu_c), mu_c.lower, mu_c.exact)
    K, M = meicp.assemble(given)
    K0, M0 = meicp.assemble(scene)
    assert sp.issparse(K) and abs(K - K0).max() == 0 and abs(M - M0).max() == 0


@pytest.mark.parametrize("given, pattern", [
    ("no/such/scene.toml", r"^cannot read scene file 'no/such/scene.toml': no such file$"),
    ("lattice = {nx = 5}", r"no such file \(TOML text is taken as such only when it spans several lines\)"),
    (TEXT.replace("nx = 5", "nxx = 5"), r"^<TOML text>: unknown key lattice.nxx \(did you mean nx\?"),
    ("[lattice\nnx = 5\n", r"^<TOML text>: not valid TOML"),
    ({"lattice": {"nx": 5}}, r"^<dict>: layers is required"),
    (b"[lattice]\nnx = 5\n", r"^scene must be a Scene, a scene file's path, a dict or TOML text, got bytes$"),
    (5, r"^scene must be a Scene, a scene file's path, a dict or TOML text, got int$"),
], ids=["missing-file", "one-line-toml", "toml-unknown-key", "toml-invalid", "dict-incomplete", "bytes", "int"])
def test_a_bad_scene_in_any_form_is_a_problem_error(given, pattern):
    for call in (meicp.analyze, meicp.critical_friction, meicp.assemble):
        with pytest.raises(ProblemError, match=pattern):
            call(given)


def test_to_dict_reads_back_to_an_equal_scene_for_every_shipped_scene():
    for path in sorted(SCENES.glob("*.toml")):
        scene = meicp.load_scene(path)
        table = scene.to_dict()
        assert same_scene(meicp.io.scene.scene_from_dict(table), scene), path.name
        assert tomllib.loads(meicp.io.results.scene_to_toml(scene)) == table, path.name


# ------------------------------------------------------------------ Scene.with_*

def test_with_friction_is_the_scene_file_with_that_friction():
    scene = meicp.load_scene(TWO_LAYERS)
    changed = scene.with_friction(0.5)
    assert same_scene(changed, loads_scene(TEXT.replace("friction = 3.0", "friction = 0.5")))
    assert changed.source == f"{TWO_LAYERS} + with_friction(0.5)"  # not the file: its text is no longer this scene
    assert scene.contact.friction == 3.0  # frozen: a new scene
    assert scene.with_friction(np.float64(0.25)).contact.friction == 0.25
    assert scene.with_friction(np.int64(2)).contact.friction == 2.0
    assert meicp.analyze(scene.with_friction(0.3)).stable is True  # docs/benchmarks.md: stable below μ ≈ 0.631


def test_with_friction_on_interfaces_and_the_base():
    table = tomllib.loads(TEXT)
    table["interfaces"] = [{"below": "A", "kind": "frictional", "friction": 0.6, "states": "stick"}]
    scene = as_scene(table)
    assert scene.frictional_interfaces()[0].friction == 0.6
    both = scene.with_friction(0.2)
    assert both.contact.friction == 0.2 and both.frictional_interfaces()[0].friction == 0.2
    one = scene.with_friction(0.2, interface="A")
    assert one.contact.friction == 3.0 and one.frictional_interfaces()[0].friction == 0.2
    base = scene.with_friction(0.2, interface="base")
    assert base.contact.friction == 0.2 and base.frictional_interfaces()[0].friction == 0.6
    with pytest.raises(ProblemError, match=r"interface='B' names no frictional contact of this scene; its "
                                           r"frictional contacts: 'base' \(the rigid base\), 'A'"):
        scene.with_friction(0.2, interface="B")
    with pytest.raises(ProblemError, match=r"interface='A' is bonded: the interface above layer 'A' has no friction"):
        meicp.load_scene(TWO_LAYERS).with_friction(0.2, interface="A")


@pytest.mark.parametrize("mu, pattern", [
    (-1, r"with_friction\(-1\): contact.friction must be >= 0, got -1"),
    ("0.5", r"contact.friction must be a number, got '0.5'"),
    (math.nan, r"contact.friction must be finite, got nan"),
    (True, r"contact.friction must be a number, got True"),
    (1e13, r"contact.friction = 1e\+13 is above 1e\+12"),
])
def test_with_friction_refuses_what_a_scene_file_refuses(mu, pattern):
    with pytest.raises(ProblemError, match=pattern):
        meicp.load_scene(TWO_LAYERS).with_friction(mu)


def test_with_states_on_the_base_and_an_interface():
    scene = meicp.load_scene(TWO_LAYERS)
    assert scene.with_states("stick").contact.states == "stick"
    per_node = ["stick", "slip+", "slip-", "separated", "grazing"]
    assert scene.with_states(per_node).contact.states == tuple(per_node)
    assert scene.with_states(tuple(per_node)).contact.states == tuple(per_node)
    solved = meicp.analyze(scene.with_states("solve"))
    assert solved.static is not None and solved.states == ["stick"] * 5
    with pytest.raises(ProblemError, match=r"contact.states must list one state per column \(nx = 5\), got 4"):
        scene.with_states(["stick"] * 4)
    with pytest.raises(ProblemError, match=r"contact.states\[2\] must be one of 'stick'"):
        scene.with_states(["stick", "stick", "slide", "stick", "stick"])
    with pytest.raises(ProblemError, match=r"contact.states must be a string or a list of strings, got 3"):
        scene.with_states(3)
    itf = meicp.load_scene(SCENES / "frictional_interface.toml")
    below = itf.frictional_interfaces()[0].below
    assert itf.with_states("stick", interface=below).frictional_interfaces()[0].states == "stick"
    with pytest.raises(ProblemError, match=r"interface='base' is no contact: the scene has no rigid base"):
        itf.with_states("stick")


def test_with_load_changes_the_fields_given():
    scene = meicp.load_scene(TWO_LAYERS)
    assert scene.with_load(gravity=0.1).load == dataclasses.replace(scene.load, gravity=0.1)
    assert scene.with_load(top_displacement=np.array([0.1, -0.2])).load.top_displacement == (0.1, -0.2)
    assert scene.with_load(top_displacement=None).load.top_displacement is None
    with pytest.raises(ProblemError, match=r"load.top_displacement\[1\] must be a number, got 'x'"):
        scene.with_load(top_displacement=(0.1, "x"))
    with pytest.raises(ProblemError, match=r"load.side_displacement prescribes x = 0.1 on the left side, which needs"):
        scene.with_load(side_displacement=(0.1, 0.0))
    assert set(inspect.signature(meicp.Scene.with_load).parameters) - {"self"} == {
        f.name for f in dataclasses.fields(meicp.scene.Load)}  # a new [load] key needs its keyword here


def test_the_examples_module_has_no_second_friction_helper():
    import meicp.examples

    assert not hasattr(meicp.examples, "with_friction")


# ------------------------------------------------------------------ keywords

KEYWORD_CASES = [
    (lambda **kw: meicp.analyze(TWO_LAYERS, **kw), "analyze", "flutterr", "flutter"),
    (lambda **kw: meicp.analyze(TWO_LAYERS, **kw), "analyze", "lam_mni", "lam_min"),
    (lambda **kw: meicp.critical_friction(TWO_LAYERS, **kw), "critical_friction", "mu_maxx", "mu_max"),
    (lambda **kw: meicp.assemble(TWO_LAYERS, **kw), "assemble", "com", "comm"),
    (lambda **kw: meicp.solve_eicp(A2, np.eye(2), **kw), "solve_eicp", "lam_mni", "lam_min"),
    (lambda **kw: meicp.solve_eicp(A2, np.eye(2), **kw), "solve_eicp", "nevv", "nev"),
    (lambda **kw: meicp.solve_lcp(M3, [-2.0, 4, -4], **kw), "solve_lcp", "max_itre", "max_iter"),
    (lambda **kw: meicp.classify(M3, **kw), "classify", "exact_limt", "exact_limit"),
    (lambda **kw: meicp.load_scene(TWO_LAYERS, **kw), "load_scene", "pth", None),
    (lambda **kw: meicp.load_results("results.h5", **kw), "load_results", "pat", "path"),
    (lambda **kw: meicp.load_scene(TWO_LAYERS).with_friction(0.3, **kw), "with_friction", "interfaces", "interface"),
    (lambda **kw: meicp.load_scene(TWO_LAYERS).with_load(**kw), "with_load", "gravty", "gravity"),
]


@pytest.mark.parametrize("call, name, wrong, right", KEYWORD_CASES,
                         ids=[f"{c[1]}-{c[2]}" for c in KEYWORD_CASES])
def test_an_unknown_keyword_is_a_type_error_naming_the_nearest(call, name, wrong, right):
    """Before: ``analyze(s, flutterr=False)`` computed flutter, ``solve_eicp(A, B,
    lam_mni=5.0)`` returned λ = 0.586."""
    with pytest.raises(TypeError, match=rf"^{name}\(\) got an unexpected keyword argument '{wrong}'"
                                        + (rf"; did you mean '{right}'\?$" if right else "")):
        call(**{wrong: 1})


def test_public_functions_show_explicit_signatures_and_whole_numpy_docstrings():
    for name in ("analyze", "critical_friction", "assemble", "load_results", "solve_lcp", "solve_eicp"):
        fn = getattr(meicp, name)
        params = inspect.signature(fn).parameters
        var = [p.name for p in params.values() if p.kind is inspect.Parameter.VAR_KEYWORD]
        assert var == (["method_options"] if name.startswith("solve_") else []), name
        text = pydoc.render_doc(fn, renderer=pydoc.plaintext)
        assert "Parameters\n" in text and "Returns\n" in text, name
        assert all(p in text for p in params), name
    assert "flutter: 'bool | None' = None" in pydoc.render_doc(meicp.analyze, renderer=pydoc.plaintext)
    assert "mu_max: 'float' = 1000.0" in pydoc.render_doc(meicp.critical_friction, renderer=pydoc.plaintext)


# ------------------------------------------------------------------ argument values

BAD_ARGUMENTS = [
    ("analyze-comm", lambda: meicp.analyze(TWO_LAYERS, comm="world"), r"^comm must be None, an mpi4py communicator"),
    ("analyze-nev", lambda: meicp.analyze(TWO_LAYERS, nev=0), r"^nev must be ≥ 1, got 0"),
    ("analyze-target", lambda: meicp.analyze(TWO_LAYERS, target="0"), r"^target must be a real number, got '0'"),
    ("analyze-max-j", lambda: meicp.analyze(TWO_LAYERS, max_j=99), r"^max_j must be ≤ 26, got 99"),
    ("analyze-options", lambda: meicp.analyze(TWO_LAYERS, options=["eps_tol"]), r"^options must be a dict"),
    ("analyze-flutter", lambda: meicp.analyze(TWO_LAYERS, flutter="no"), r"^flutter must be True or False"),
    ("analyze-lam-max", lambda: meicp.analyze(TWO_LAYERS, lam_max=1.0), r"^analyze does not take 'lam_max'"),
    ("cf-mu-max-text", lambda: meicp.critical_friction(TWO_LAYERS, mu_max="5"), r"^mu_max must be a real number, got '5'"),
    ("cf-mu-max-negative", lambda: meicp.critical_friction(TWO_LAYERS, mu_max=-1), r"^mu_max must be > 0, got -1.0"),
    ("cf-mu-max-inf", lambda: meicp.critical_friction(TWO_LAYERS, mu_max=math.inf), r"^mu_max must be a finite number"),
    ("cf-tol-negative", lambda: meicp.critical_friction(TWO_LAYERS, tol=-1), r"^tol must be > 0, got -1.0"),
    ("cf-tol-zero", lambda: meicp.critical_friction(TWO_LAYERS, tol=0), r"^tol must be > 0, got 0.0"),
    ("cf-tol-loose", lambda: meicp.critical_friction(TWO_LAYERS, tol=0.5), r"^tol must be ≤ 0.01, got 0.5"),
    ("cf-bisection", lambda: meicp.critical_friction(TWO_LAYERS, bisection="yes"), r"^bisection must be True or False"),
    ("cf-comm", lambda: meicp.critical_friction(TWO_LAYERS, comm="world"), r"^comm must be None, an mpi4py"),
    ("assemble-comm", lambda: meicp.assemble(TWO_LAYERS, comm=3), r"^comm must be None, an mpi4py communicator .* got int 3"),
    ("lcp-q-text", lambda: meicp.solve_lcp(M3, ["1", "2", "3"]), r"^q is not a numeric vector: it holds <U1 values"),
    ("lcp-M-text", lambda: meicp.solve_lcp([["2", "0"], ["0", "2"]], [1, 1]), r"^M is not a numeric matrix"),
    ("lcp-comm", lambda: meicp.solve_lcp(M3, [-2.0, 4, -4], comm="world"), r"^comm must be None"),
    ("lcp-method", lambda: meicp.solve_lcp(M3, [-2.0, 4, -4], method=["lemke"]), r"^method must be a method name"),
    ("eicp-comm", lambda: meicp.solve_eicp(A2, np.eye(2), comm="world"), r"^comm must be None"),
    ("eicp-all-solutions", lambda: meicp.solve_eicp(A2, np.eye(2), all_solutions="yes"),
     r"^all_solutions must be True or False"),
    ("eicp-B-text", lambda: meicp.solve_eicp(A2, [["1", "0"], ["0", "1"]]), r"^B is not a numeric matrix"),
    ("load-results-missing", lambda: meicp.load_results("no/such/results.h5"),
     r"^cannot read results file 'no/such/results.h5': no such file"),
]


@pytest.mark.parametrize("call, pattern", [c[1:] for c in BAD_ARGUMENTS], ids=[c[0] for c in BAD_ARGUMENTS])
def test_a_bad_argument_is_a_problem_error_naming_it(call, pattern):
    with pytest.raises(ProblemError, match=pattern):
        call()


# ------------------------------------------------------------------ comm=None

def test_comm_none_is_comm_world_for_the_scene_functions_and_serial_for_assemble(monkeypatch):
    from mpi4py import MPI

    import meicp.api

    seen = {}
    monkeypatch.setattr(meicp.api, "_analyze", lambda scene, comm, **kw: seen.setdefault("analyze", comm))
    monkeypatch.setattr(meicp.api, "_critical_friction", lambda scene, **kw: seen.setdefault("cf", kw["comm"]))
    meicp.analyze(TWO_LAYERS)
    meicp.critical_friction(TWO_LAYERS)
    assert seen["analyze"] is MPI.COMM_WORLD and seen["cf"] is MPI.COMM_WORLD
    K, M = meicp.assemble(TWO_LAYERS)
    assert sp.issparse(K) and sp.issparse(M)


# ------------------------------------------------------------------ reprs

def test_reprs_are_short_and_say_the_answer(reference):
    scene, result, mu_c = reference
    text = repr(result)
    assert text.startswith("InstabilityResult(UNSTABLE: divergence σ=0.3291 (1 mode), flutter growth 0.174")
    static = meicp.analyze(scene.with_states("solve"))
    modal = meicp.analyze(SCENES / "embedded_layer.toml")
    lcp = meicp.solve_lcp(M3, [-2.0, 4, -4])
    eicp = meicp.solve_eicp(A2, np.eye(2))
    failed = meicp.solve_lcp(np.array([[-1.0]]), [-1.0], method="lemke")
    objects = [result, static, static.static, modal, result.modes[0], result.flutter_modes[0], mu_c, scene, lcp,
               failed, eicp, eicp.solutions[0], meicp.classify(M3), meicp.game_value(M3)]
    for obj in objects:
        assert len(repr(obj)) < 300 and "\n" not in repr(obj), repr(obj)
    assert repr(modal).startswith("InstabilityResult(NO CONTACT: modal analysis: 6 vibration modes")
    assert repr(mu_c).startswith("CriticalFriction(0.63076") and repr(mu_c).endswith("— flutter first)")
    assert str(mu_c) == repr(float(mu_c)) and repr(mu_c.divergence) == "Onset(1.90603249 (exact))"
    assert repr(lcp) == "LCPResult(solved by lemke: x=[1 0 2], residual 0.0e+00, 3 iterations)"
    assert repr(failed).startswith("LCPResult(ray_termination (lemke): ")
    wide = meicp.Mode(sigma=0.3, x=np.zeros(2400), support=np.arange(300), residual=1e-16)
    assert repr(wide) == "Mode(σ=0.3, growth rate 0.547723, support [0 1 2 3 4 5 ... (300 values)], residual 1.0e-16)"


# ------------------------------------------------------------------ load_results

def _compare(back, result) -> None:
    """Every field results.h5 holds, as the analysis returned it."""
    assert back.to_dict() == result.to_dict()
    assert (back.stable, back.divergence, back.flutter, back.verdict) == (result.stable, result.divergence,
                                                                         result.flutter, result.verdict)
    assert back.evidence == result.evidence and back.flutter_evidence == result.flutter_evidence
    assert back.proofs == result.proofs and back.divergence_verdict == result.divergence_verdict
    assert back.states == result.states and back.interface_states == result.interface_states
    assert len(back.modes) == len(result.modes) and len(back.flutter_modes) == len(result.flutter_modes)
    for a, b in zip(back.modes, result.modes):
        assert a.sigma == b.sigma and a.residual == b.residual and np.array_equal(a.x, b.x)
        assert np.array_equal(a.support, b.support) and a.interface_support.keys() == b.interface_support.keys()
    for a, b in zip(back.flutter_modes, result.flutter_modes):
        assert a.sigma == b.sigma and np.array_equal(a.x, b.x) and np.array_equal(a.support, b.support)
        assert (a.growth_rate, a.frequency, a.radius, a.branch, a.found_by) == (b.growth_rate, b.frequency, b.radius,
                                                                               b.branch, b.found_by)
    assert [(e.method, e.status, e.message) for e in back.eicp if e] == [
        (e.method, e.status, e.message) for e in result.eicp if e]
    assert back.timings == pytest.approx(result.timings) and back.sizes == result.sizes


@pytest.mark.parametrize("states", ["slip+", "solve"])
def test_load_results_gives_back_what_was_written(tmp_path, states):
    scene = meicp.load_scene(TWO_LAYERS).with_states(states)
    result = meicp.analyze(scene)
    mu_c = meicp.critical_friction(scene)
    files = write_results(tmp_path, scene, result, critical_friction=critical_friction_record(mu_c), plots=False)
    back = meicp.load_results(files["results"])
    _compare(back, result)
    assert isinstance(back.critical_friction, meicp.CriticalFriction)
    assert (float(back.critical_friction), back.critical_friction.lower, back.critical_friction.exact,
            back.critical_friction.evidence) == (float(mu_c), mu_c.lower, mu_c.exact, mu_c.evidence)
    assert repr(back) == repr(result).replace(", 40 DOFs", f", μ_c {float(mu_c):.6g}, 40 DOFs")
    if states == "solve":
        assert back.static.success and back.static.states == result.static.states == ["stick"] * 5
        for name in ("r_n", "r_t", "gap", "slip", "held", "u"):
            assert np.array_equal(getattr(back.static, name), getattr(result.static, name)), name
        assert back.static.guarantees == result.static.guarantees
        assert back.static.equilibrium_residual == result.static.equilibrium_residual
    else:
        assert back.static is None and back.modes and back.flutter_modes


def test_load_results_of_the_solve_command(tmp_path, cli):
    """``meicp solve --critical-friction`` writes it; load_results reads the same answer."""
    out = tmp_path / "run"
    code, _, _ = cli("solve", TWO_LAYERS, "-o", out, "--critical-friction", "-q")
    assert code == 0
    back = meicp.load_results(out / "results.h5")
    result, mu_c = meicp.analyze(TWO_LAYERS), meicp.critical_friction(TWO_LAYERS)
    assert {k: v for k, v in back.to_dict().items() if k != "timings"} == {
        k: v for k, v in result.to_dict().items() if k != "timings"}
    assert back.proofs == result.proofs and back.modes[0].sigma == result.modes[0].sigma
    assert np.array_equal(back.modes[0].x, result.modes[0].x)
    assert repr(back.critical_friction) == repr(mu_c) and back.critical_friction.evidence == mu_c.evidence
    with h5py.File(out / "results.h5") as f:
        assert same_scene(loads_scene(f["scene"][()].decode()), meicp.load_scene(TWO_LAYERS))


def test_load_results_refuses_what_is_not_a_results_file(tmp_path):
    text = tmp_path / "scene.toml"
    text.write_text(TEXT)
    with pytest.raises(ProblemError, match=r"scene.toml: not an HDF5 file"):
        meicp.load_results(text)
    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as f:
        f.attrs["format"] = "something-else"
    with pytest.raises(ProblemError, match=r"other.h5: not a meicp results file \(format 'something-else'"):
        meicp.load_results(other)
    with h5py.File(other, "w") as f:
        f.attrs["format"], f.attrs["format_version"] = "meicp-results", 99
    with pytest.raises(ProblemError, match=r"format version 99 is newer than this meicp reads"):
        meicp.load_results(other)
    assert re.search(r"results\.h5", meicp.load_results.__doc__)
