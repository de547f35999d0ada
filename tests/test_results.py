"""What ``meicp solve`` leaves on disk (``meicp.io.results.write_results``) and the ``solve``
subcommand around it, on hand-built :class:`InstabilityResult` s (no physics here):

- results.h5 round-trips: scene text, versions, states, forces, modes, certificates, verdict;
- lattice.xdmf is XML whose every DataItem names an existing dataset of the stated shape,
  and meshio reads it with the mode shapes and contact states as point data;
- the PNGs are real images; nothing temporary is left; an error before or half-way through
  leaves no file behind (and an existing directory untouched);
- ``meicp solve`` (against a stand-in for ``analyze``): exit codes, summary, default DIR.
"""

import argparse
import dataclasses
import re
import struct
import types
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

import meicp
from meicp.contact.result import InstabilityResult, Mode
from meicp.core import limits
from meicp.core.json_values import json_ready, restore_infinities
from meicp.core.errors import ProblemError
from meicp.io.results import CODE_LEGEND, FILES, STATE_CODES, scene_to_toml, write_results
from meicp.examples import two_layer_scene
from meicp.io.scene import load_scene, loads_scene
from meicp.plotting.lattice import display_scale

from .conftest import ROOT

SCENES = ROOT / "data" / "scenes"
EXPECTED = {"results.h5", "lattice.h5", "lattice.xdmf", "mode.png", "contacts.png"}
BASE_STATES = ["slip+", "slip+", "stick", "separated", "slip-"]


def smooth_shape(scene, seed=0) -> np.ndarray:
    """A normalised vector with zeros on the fixed DOFs, like a mode shape."""
    from meicp.lattice.model import LatticeModel

    model = LatticeModel(scene)
    p = model.positions()
    x = np.zeros(scene.n_dofs)
    x[0::2] = np.sin(np.pi * (p[:, 1] + 0.5) / (p[:, 1].max() + 1)) * np.cos(np.pi * p[:, 0] / p[:, 0].max() + seed)
    x[1::2] = 0.25 * np.sin(2 * np.pi * p[:, 0] / p[:, 0].max() + seed)
    x[model.fixed_mask().ravel()] = 0.0
    return x / np.linalg.norm(x)


def unstable_result(scene, *, static=True) -> InstabilityResult:
    """Two modes, base states, static forces: what analyze returns for the two_layers scene."""
    nx = scene.nx
    modes = [Mode(sigma=0.25, x=smooth_shape(scene), support=np.array([0, 1]), residual=2e-13),
             Mode(sigma=0.04, x=smooth_shape(scene, 1.0), support=np.array([1]), residual=5e-12)]
    st = None
    if static:
        # the fields of meicp.contact.static.StaticResult that write_results reads
        st = types.SimpleNamespace(r_n=np.linspace(1.0, 2.0, nx), r_t=-2.5 * np.linspace(1.0, 2.0, nx),
                                   gap=np.r_[np.zeros(nx - 2), 0.01, 0.0], slip=np.zeros(nx),
                                   held=np.zeros(nx, dtype=bool), u=0.01 * smooth_shape(scene, 2.0),
                                   interface_r_n={}, status="solved", success=True, iterations=7,
                                   equilibrium_residual=1e-15, guarantees=["unique solution"])
    eicp = types.SimpleNamespace(method="enumerate", status="solved", success=True, message="2 solutions",
                                 coverage={"supports": 31, "eigen_solves": 31})
    return InstabilityResult(status="solved", message="2 modes", iterations=31, residual=5e-12,
                             timings={"assemble": 0.01, "eicp": 0.2}, modes=modes, stable=False,
                             evidence="all 31 supports enumerated", states=list(BASE_STATES),
                             static=st, eicp=[eicp], sizes={"all": scene.n_dofs, "retained": 30,
                                                          "complementarity": 3})


@pytest.fixture(scope="module")
def two_layers():
    return load_scene(SCENES / "two_layers.toml")


@pytest.fixture(scope="module")
def written(two_layers, tmp_path_factory):
    out = tmp_path_factory.mktemp("res") / "run"
    result = unstable_result(two_layers)
    files = write_results(out, two_layers, result)
    return out, files, result


def png_size(path: Path) -> tuple[int, int]:
    raw = path.read_bytes()
    assert raw[:8] == b"\x89PNG\r\n\x1a\n" and raw[12:16] == b"IHDR"
    return struct.unpack(">II", raw[16:24])


# --------------------------------------------------------------------------- write_results

def test_files_exist_and_nothing_temporary_is_left(written):
    out, files, _ = written
    assert {p.name for p in out.iterdir()} == EXPECTED  # no .tmp, .part or staging directory
    assert set(files) == set(FILES) - {"flutter_png"} and all(p.parent == out and p.is_file() for p in files.values())
    assert files["results"] == out / "results.h5" and files["xdmf"] == out / "lattice.xdmf"


def test_results_h5_round_trip(written, two_layers):
    import h5py

    out, _, result = written
    with h5py.File(out / "results.h5", "r") as f:
        a = f.attrs
        assert a["format"] == "meicp-results" and a["verdict"] == "unstable" and a["stable"] == 0
        assert a["status"] == "solved" and bool(a["success"]) and a["n_modes"] == 2
        assert a["evidence"] == result.evidence and a["title"] == two_layers.title
        text = f["scene"].asstr()[()]
        assert text == (SCENES / "two_layers.toml").read_text()
        assert loads_scene(text) == dataclasses.replace(two_layers, source="<string>")
        s = f["scene_summary"]
        assert (s.attrs["nx"], s.attrs["ny"], s.attrs["n_dofs"]) == (5, 4, 40)
        assert s.attrs["boundary_bottom"] == "contact" and s.attrs["base_friction"] == 3.0
        assert [n.decode() for n in s["layers/name"][()]] == ["A", "B"]
        np.testing.assert_array_equal(s["layers/stiffness"][()], [1.0, 5.0])
        v = f["versions"].attrs
        for key in ("python", "numpy", "petsc", "slepc", "mpi", "meicp"):
            assert key in v and "\x00" not in str(v[key])
        assert dict(f["sizes"].attrs) == {"all": 40, "retained": 30, "complementarity": 3}
        assert dict(f["timings"].attrs) == pytest.approx(result.timings)

        c = f["contact"]
        assert c.attrs["codes"] == CODE_LEGEND
        assert [s.decode() for s in c["base/states"][()]] == BASE_STATES
        np.testing.assert_array_equal(c["base/code"][()], [STATE_CODES[s] for s in BASE_STATES])
        np.testing.assert_array_equal(c["base/nodes"][()], np.arange(5))
        assert c["base"].attrs["friction"] == 3.0 and "interfaces" not in c

        st = f["static"]
        for name in ("r_n", "r_t", "gap", "slip", "held", "u"):
            np.testing.assert_array_equal(st[name][()], getattr(result.static, name))
        assert st.attrs["status"] == "solved" and st.attrs["iterations"] == 7
        assert st.attrs["guarantees"] == "unique solution" and st.attrs["equilibrium_residual"] == 1e-15

        m = f["modes"]
        np.testing.assert_array_equal(m["sigma"][()], [0.25, 0.04])
        np.testing.assert_allclose(m["growth_rate"][()], [0.5, 0.2])
        np.testing.assert_array_equal(m["residual"][()], [2e-13, 5e-12])
        np.testing.assert_array_equal(m["x"][()], np.stack([md.x for md in result.modes]))
        for k, md in enumerate(result.modes):
            g = m[f"mode_{k}"]
            np.testing.assert_array_equal(g["support"][()], md.support)
            assert g.attrs["sigma"] == md.sigma and g.attrs["residual"] == md.residual
            assert g.attrs["display_scale"] == pytest.approx(display_scale(two_layers, md.x))
        cert = f["certificates"]
        np.testing.assert_array_equal(cert["mode_residual"][()], [2e-13, 5e-12])
        assert cert.attrs["max_mode_residual"] == 5e-12 and cert.attrs["eicp_method"] == "enumerate"
        assert '"supports": 31' in cert.attrs["eicp_coverage"]


def test_xdmf_references_existing_datasets(written, two_layers):
    import h5py

    out, files, result = written
    root = ET.parse(files["xdmf"]).getroot()
    grid = root.find("Domain/Grid")
    names = {a.get("Name"): a for a in grid.findall("Attribute")}
    assert {"mode_0", "mode_1", "contact_state", "static_u", "material"} <= set(names)
    assert names["mode_0"].get("AttributeType") == "Vector"
    items = root.iter("DataItem")
    with h5py.File(out / "lattice.h5", "r") as f:
        n = 0
        for item in items:
            h5name, _, dataset = item.text.strip().partition(":")
            assert (out / h5name).resolve() == (out / "lattice.h5").resolve()
            dims = tuple(int(d) for d in item.get("Dimensions").split())
            assert dataset in f and f[dataset].shape == dims, dataset
            n += 1
        assert n >= 8
        scale = display_scale(two_layers, result.modes[0].x)
        np.testing.assert_allclose(f["fields/mode_0"][:, :2].ravel(), scale * result.modes[0].x)
        assert np.all(f["fields/mode_0"][:, 2] == 0)
        code = f["fields/contact_state"][()]
        np.testing.assert_array_equal(code[:5], [STATE_CODES[s] for s in BASE_STATES])
        assert np.all(code[5:] == 0)
        peak = np.sqrt((f["fields/mode_0"][()] ** 2).sum(axis=1)).max()
        assert peak == pytest.approx(0.15 * 3.0)  # 15 % of the height (3 spacings)


def test_xdmf_readable_by_meshio(written, two_layers):
    meshio = pytest.importorskip("meshio")
    out, files, result = written
    mesh = meshio.read(files["xdmf"])
    assert mesh.points.shape == (two_layers.n_nodes, 3)
    assert mesh.cells[0].type == "line"
    scale = display_scale(two_layers, result.modes[0].x)
    np.testing.assert_allclose(mesh.point_data["mode_0"][:, :2].ravel(), scale * result.modes[0].x)
    np.testing.assert_array_equal(mesh.point_data["contact_state"][:5],
                                  [STATE_CODES[s] for s in BASE_STATES])


def test_xdmf_has_contact_reactions_and_node_indices(written, two_layers):
    """r_n, r_t (NaN off the contact nodes) and the indices i, j as fields ParaView and
    meshio read; the code legends in a comment at the top of the XDMF file."""
    meshio = pytest.importorskip("meshio")
    out, files, result = written
    mesh = meshio.read(files["xdmf"])
    nx = two_layers.nx
    for name in ("r_n", "r_t"):
        field = mesh.point_data[name]
        np.testing.assert_array_equal(field[:nx], getattr(result.static, name))
        assert np.all(np.isnan(field[nx:]))
    np.testing.assert_array_equal(mesh.point_data["i"], np.tile(np.arange(nx), two_layers.ny))
    np.testing.assert_array_equal(mesh.point_data["j"], np.repeat(np.arange(two_layers.ny), nx))
    head = files["xdmf"].read_text().split("<Xdmf")[0]
    assert "contact_state   0 not_a_contact_node, 1 stick, 2 slip+, 3 slip-" in head
    assert "bond_kind       0 horizontal, 1 vertical, 2 diagonal, 3 antidiagonal" in head


def test_every_dataset_says_what_it_is_and_that_the_model_is_dimensionless(written):
    """CF-style long_name and units on every dataset of both files; code legends as
    flag_values / flag_meanings / legend attributes (h5dump shows them)."""
    import h5py

    out, _, _ = written
    for name in ("results.h5", "lattice.h5"):
        with h5py.File(out / name, "r") as f:
            assert "dimensionless" in f.attrs["units_convention"]
            seen = []
            f.visititems(lambda key, obj: seen.append((key, obj)) if hasattr(obj, "shape") else None)
            assert len(seen) > 10
            for key, obj in seen:
                assert obj.attrs["units"] == "1" and obj.attrs["long_name"], (name, key)
    with h5py.File(out / "results.h5", "r") as f:
        code = f["contact/base/code"].attrs
        assert list(code["flag_values"]) == [0, 1, 2, 3, 4, 5, -1]
        assert code["flag_meanings"] == "not_a_contact_node stick slip+ slip- separated grazing unknown"
        assert "1/time^2" in f["modes/sigma"].attrs["long_name"]
    with h5py.File(out / "lattice.h5", "r") as f:
        assert f["bonds/kind"].attrs["legend"] == "0 horizontal, 1 vertical, 2 diagonal, 3 antidiagonal"
        assert f["fields/contact_state"].attrs["flag_meanings"].startswith("not_a_contact_node stick")
        assert "force" in f["fields/r_n"].attrs["long_name"]


class _Bracket(float):
    """A critical friction as issue 14's will be: a float carrying a certified bracket."""

    lower, upper, exact, evidence = 1.9, 1.91, False, "bracket by inertia"


@pytest.mark.parametrize("mu_c, expected", [
    (1.906, {"value": 1.906, "found": True}),
    (float("inf"), {"value": float("inf"), "found": False}),
    (_Bracket(1.905), {"value": 1.905, "found": True, "lower": 1.9, "upper": 1.91, "exact": False,
                       "evidence": "bracket by inertia"}),
])
def test_critical_friction_and_its_bracket_in_results_h5(tmp_path, two_layers, mu_c, expected):
    import h5py

    files = write_results(tmp_path / "o", two_layers, unstable_result(two_layers), plots=False,
                          critical_friction=mu_c)
    with h5py.File(files["results"], "r") as f:
        got = {k: (v.item() if hasattr(v, "item") else v) for k, v in f["critical_friction"].attrs.items()}
    assert got == expected


def test_a_failed_critical_friction_is_read_back(tmp_path, two_layers):
    """``meicp solve --critical-friction`` on a floating body stores ``error`` instead of a value:
    load_results reads it as such (it raised KeyError 'value' on every such file)."""
    import meicp
    from meicp.contact.critical_friction import CriticalFrictionFailed

    files = write_results(tmp_path / "o", two_layers, unstable_result(two_layers), plots=False,
                          critical_friction={"error": "μ_c undefined: the body floats"})
    back = meicp.load_results(files["results"])
    assert back.critical_friction == CriticalFrictionFailed("μ_c undefined: the body floats")
    assert "μ_c not computed: μ_c undefined" in repr(back)


def _interface_named(name: str, states="slip+"):
    from meicp.io.scene import scene_from_dict

    return scene_from_dict({
        "lattice": {"nx": 5},
        "layers": [{"name": name, "rows": 2, "stiffness": 2.0, "density": 1.0, "viscosity": 0.02},
                   {"name": "rock", "rows": 2, "stiffness": 1.0, "density": 1.0}],
        "interfaces": [{"below": name, "kind": "frictional", "friction": 3.0, "states": states}],
        "boundary": {"bottom": "fixed", "top": "fixed"}})


@pytest.mark.parametrize("name, states", [
    ("sand/clay", "slip+"), (".", "slip+"), ("..", "slip+"), ("50%/2F", "slip+"),
    ("Schicht" + "ä" * 40, ["slip+", "grazing", "slip+", "slip+", "slip+"]),
], ids=["slash", "dot", "dots", "percent", "long non-ASCII, grazing"])
def test_any_name_the_scene_accepts_comes_back_from_results_h5(tmp_path, name, states):
    """A name is an HDF5 link in results.h5 (contact/interfaces/<name>, interface_support/<name>)
    and a branch label holds it: '/' split it into groups (load_results raised TypeError, or
    lost the states), '.' could not be written (exit 3), a fixed width of 64 bytes cut a long
    name mid-character (UnicodeDecodeError)."""
    import meicp

    scene = _interface_named(name, states)
    result = meicp.analyze(scene)
    files = write_results(tmp_path / "o", scene, result, plots=False)
    back = meicp.load_results(files["results"])
    assert back.interface_states == result.interface_states and name in back.interface_states
    assert [m.branch for m in back.flutter_modes] == [m.branch for m in result.flutter_modes]
    assert [sorted(m.interface_support) for m in back.modes] == [sorted(m.interface_support) for m in result.modes]
    if not isinstance(states, str):
        assert any(m.branch.endswith(f"{name}:slip+") for m in back.flutter_modes)


def test_modal_result_written_like_any_mode(tmp_path):
    """A scene without contact: its vibration modes (σ = −ω²) with their frequency."""
    import h5py

    import meicp

    scene = load_scene(SCENES / "sheared.toml")
    result = meicp.analyze(scene, nev=3)
    files = write_results(tmp_path / "m", scene, result, plots=False)
    with h5py.File(files["results"], "r") as f:
        assert f.attrs["analysis"] == "modal" and f.attrs["verdict"] == "no contact" and f.attrs["n_modes"] == 3
        np.testing.assert_allclose(f["modes/frequency"][()], np.sqrt(-f["modes/sigma"][()]))
        assert np.all(f["modes/growth_rate"][()] == 0) and "critical_friction" not in f


def test_pngs_are_images(written):
    out, files, _ = written
    for key in ("mode_png", "contacts_png"):
        w, h = png_size(files[key])
        assert w > 600 and h > 300 and files[key].stat().st_size > 20_000
    from matplotlib.image import imread

    img = imread(files["mode_png"])
    assert img.ndim == 3 and img[..., :3].std() > 0.05  # not a blank canvas


def test_stable_result_without_contacts_or_static(tmp_path):
    scene = load_scene(SCENES / "sheared.toml")  # no base, no frictional interface
    result = InstabilityResult(status="solved", stable=True, evidence="no σ ≥ 0 solution")
    files = write_results(tmp_path / "s", scene, result, plots=True)
    assert set(files) == {"results", "lattice", "xdmf", "mode_png"}
    assert {p.name for p in (tmp_path / "s").iterdir()} == EXPECTED - {"contacts.png"}
    import h5py

    with h5py.File(files["results"], "r") as f:
        assert f.attrs["verdict"] == "stable" and f.attrs["stable"] == 1 and f.attrs["n_modes"] == 0
        assert f["modes/x"].shape == (0, scene.n_dofs) and "static" not in f
    png_size(files["mode_png"])


def test_frictional_interface_states_and_support(tmp_path):
    import h5py

    scene = load_scene(SCENES / "frictional_interface.toml")
    states = ["slip+"] * 9 + ["stick"]
    rn = np.linspace(1.0, 2.0, 10)
    static = types.SimpleNamespace(r_n=np.zeros(0), interface_r_n={"lower": rn},
                                   interface_r_t={"lower": -0.4 * rn}, interface_gap={"lower": np.zeros(10)})
    result = InstabilityResult(
        status="solved", stable=False, evidence="e", interface_states={"lower": states}, static=static,
        modes=[Mode(sigma=1.0, x=smooth_shape(scene), support=np.zeros(0, int), residual=1e-12,
                    interface_support={"lower": np.array([2, 3])})])
    files = write_results(tmp_path, scene, result)
    with h5py.File(files["results"], "r") as f:
        g = f["contact/interfaces/lower"]
        assert [s.decode() for s in g["states"][()]] == states and g.attrs["friction"] == 0.5
        np.testing.assert_array_equal(g["lower_nodes"][()], np.arange(20, 30))
        np.testing.assert_array_equal(g["upper_nodes"][()], np.arange(30, 40))
        np.testing.assert_array_equal(f["modes/mode_0/interface_support/lower"][()], [2, 3])
        np.testing.assert_array_equal(f["static/interfaces/lower/r_t"][()], -0.4 * rn)
        assert f["static/r_n"].shape == (0,)
    with h5py.File(files["lattice"], "r") as f:
        code = f["fields/contact_state"][()]
        assert np.all(code[20:40] == np.tile([STATE_CODES[s] for s in states], 2))
        assert np.all(code[:20] == 0) and np.all(code[40:] == 0)
    png_size(files["contacts_png"])


def test_scene_without_file_gets_regenerated_toml(tmp_path):
    import h5py

    for path in sorted(SCENES.glob("*.toml")):
        scene = load_scene(path)
        again = loads_scene(scene_to_toml(scene))
        assert again == dataclasses.replace(scene, source="<string>"), path.name
    scene = dataclasses.replace(load_scene(SCENES / "two_layers.toml"), source=None)
    files = write_results(tmp_path, scene, unstable_result(scene, static=False), plots=False)
    with h5py.File(files["results"], "r") as f:
        assert loads_scene(f["scene"].asstr()[()]) == dataclasses.replace(scene, source="<string>")


@pytest.mark.parametrize("breakage", ["mode length", "mode NaN", "states length", "unknown state",
                                      "support range", "unknown interface"])
def test_bad_result_writes_nothing(tmp_path, two_layers, breakage):
    result = unstable_result(two_layers)
    if breakage == "mode length":
        result.modes[1].x = result.modes[1].x[:-2]
    elif breakage == "mode NaN":
        result.modes[0].x = result.modes[0].x.copy()
        result.modes[0].x[3] = np.nan
    elif breakage == "states length":
        result.states = result.states[:-1]
    elif breakage == "unknown state":
        result.states = ["slip"] * 5
    elif breakage == "support range":
        result.modes[0].support = np.array([5])
    else:
        result.interface_states = {"B": ["stick"] * 5}
    out = tmp_path / "new" / "dir"
    with pytest.raises(ProblemError):
        write_results(out, two_layers, result)
    assert not (tmp_path / "new").exists()


def test_failure_half_way_leaves_nothing(tmp_path, two_layers, monkeypatch):
    import meicp.io.results as results

    def broken(*args, **kwargs):
        raise RuntimeError("disk full (simulated)")

    monkeypatch.setattr(results, "write_lattice", broken)  # after results.h5
    out = tmp_path / "fresh" / "run"
    with pytest.raises(RuntimeError, match="simulated"):
        write_results(out, two_layers, unstable_result(two_layers))
    assert not (tmp_path / "fresh").exists()
    # an existing directory keeps exactly what it had (an earlier run's files included)
    old = tmp_path / "old"
    old.mkdir()
    (old / "results.h5").write_bytes(b"earlier run")
    (old / "notes.txt").write_text("mine")
    with pytest.raises(RuntimeError, match="simulated"):
        write_results(old, two_layers, unstable_result(two_layers))
    assert {p.name for p in old.iterdir()} == {"results.h5", "notes.txt"}
    assert (old / "results.h5").read_bytes() == b"earlier run"


def test_a_picture_that_cannot_be_drawn_leaves_the_results_whole(tmp_path, two_layers, monkeypatch, caplog):
    """A PNG is an extra (issue 30): Matplotlib refusing one (a huge title asked for an image
    of 124,492 pixels) threw the verdict's files away; now the others are written, the PNG
    is left out with a warning, and a stale one of an earlier run is removed."""
    import meicp.plotting.lattice as plotting

    def broken(*args, **kwargs):
        raise ValueError("Image size of 124492x958 pixels is too large (simulated)")

    out = tmp_path / "run"
    write_results(out, two_layers, unstable_result(two_layers))
    assert (out / FILES["contacts_png"]).is_file()
    monkeypatch.setattr(plotting, "plot_contacts", broken)
    files = write_results(out, two_layers, unstable_result(two_layers))
    assert "contacts_png" not in files and {"results", "lattice", "xdmf", "mode_png"} <= set(files)
    assert {p.name for p in out.iterdir()} == {FILES[k] for k in ("results", "lattice", "xdmf", "mode_png")}
    assert "contacts.png not written: ValueError: Image size of 124492x958" in caplog.text


def test_a_directory_in_the_way_replaces_nothing(tmp_path, two_layers):
    """A directory named results.h5 in the output directory: the last rename failed after the
    others had replaced an earlier run's lattice.h5 and PNGs (exit 3, an internal error); now
    a ProblemError names it before anything is moved."""
    out = tmp_path / "run"
    out.mkdir()
    (out / "lattice.h5").write_bytes(b"earlier run")
    (out / "results.h5").mkdir()
    with pytest.raises(ProblemError, match="results.h5 into .* a directory of that name is in the way"):
        write_results(out, two_layers, unstable_result(two_layers), plots=False)
    assert (out / "lattice.h5").read_bytes() == b"earlier run"
    assert {p.name for p in out.iterdir()} == {"lattice.h5", "results.h5"}


def test_output_path_that_is_a_file(tmp_path, two_layers):
    (tmp_path / "f").write_text("x")
    with pytest.raises(ProblemError, match="output directory"):
        write_results(tmp_path / "f", two_layers, unstable_result(two_layers), plots=False)


# --------------------------------------------------------------------------- meicp solve

@pytest.fixture
def fake_analyze(monkeypatch):
    """``analyze`` (as ``meicp solve`` calls it) replaced by a stand-in that records its calls."""
    from meicp.cli import solve

    calls = []
    module = types.ModuleType("fake_instability")

    def analyze(scene, comm=None, scene_path=None, **overrides):
        import logging

        calls.append(scene_path)
        logging.getLogger("meicp").info("fake analysis: phase one")
        return module.make(scene)

    module.analyze = analyze
    module.make = unstable_result
    monkeypatch.setattr(solve, "analyze", analyze)
    return module, calls


def solve_args(*argv):
    from meicp.cli import solve

    parser = argparse.ArgumentParser(prog="meicp")
    parser.add_argument("-v", "--verbose", action="count", default=0)
    sub = parser.add_subparsers(dest="command")
    solve.register(sub)
    return parser.parse_args(["solve", *argv])


def test_solve_cli_unstable(tmp_path, monkeypatch, capsys, caplog, fake_analyze):
    from meicp.cli import solve

    monkeypatch.chdir(tmp_path)
    scene = str(SCENES / "two_layers.toml")
    assert solve.run(solve_args(scene)) == 0
    out, err = capsys.readouterr()
    assert fake_analyze[1] == [scene]
    assert {p.name for p in (tmp_path / "out" / "two_layers").iterdir()} == EXPECTED
    for text in ("two layers on a rough base", "40 DOFs", "stick ×1, slip+ ×2, slip- ×1, separated ×1",
                 "[>>|o<]", "UNSTABLE", "all 31 supports enumerated", "0.25", "2.0e-13", "eicp 200.0 ms",
                 "lattice.xdmf"):
        assert text in out, text
    logged = [r.getMessage() for r in caplog.records if r.name == "meicp"]
    for phase in ("loading scene", "analysis: started", "fake analysis: phase one", "writing results"):
        assert any(phase in m for m in logged), phase  # INFO is on by default for solve


def test_solve_cli_exit_codes(tmp_path, capsys, fake_analyze):
    from meicp.cli import solve

    module, calls = fake_analyze
    scene = str(SCENES / "two_layers.toml")
    module.make = lambda s: InstabilityResult(status="solved", stable=True, evidence="proved",
                                              states=["stick"] * 5)
    assert solve.run(solve_args(scene, "--no-output", "-q")) == 0
    out, err = capsys.readouterr()
    assert "STABLE" in out and "stick ×5" in out and re.search(r"^modes\s+none$", out, re.M)
    module.make = lambda s: InstabilityResult(status="max_iterations", stable=None, evidence="gave up")
    assert solve.run(solve_args(scene, "-o", str(tmp_path / "f"))) == 1
    assert "FAILED (max_iterations)" in capsys.readouterr()[0]
    assert (tmp_path / "f" / "results.h5").is_file()  # a failed analysis still leaves its record
    bad = tmp_path / "bad.toml"
    bad.write_text((SCENES / "two_layers.toml").read_text().replace("nx = 5", "nx = 5\ncolumns = 3"))
    n = len(calls)
    with pytest.raises(ProblemError, match="lattice.columns"):
        solve.run(solve_args(str(bad), "-o", str(tmp_path / "b")))
    assert len(calls) == n and not (tmp_path / "b").exists()  # failed before any analysis


def test_a_proof_with_an_infinite_sigma_window_reads_back(tmp_path, monkeypatch):
    """Format 2 writes an infinite end as null with a ``sigma_window_infinite`` flag;
    ``load_results`` gave it to DivergenceProof as a keyword (a TypeError on every results.h5
    of a Rayleigh proof at scale) and read the end as NaN."""
    doc = {"w": (0.0, float("inf")), "m": float("-inf"), "k": 1.0}
    assert restore_infinities(json_ready(doc)) == {"w": [0.0, float("inf")], "m": float("-inf"), "k": 1.0}
    monkeypatch.setattr(limits, "ENUMERATE_N", 0)
    scene = two_layer_scene(6, (2, 2), mu=0.3, states="slip-")
    result = meicp.analyze(scene, flutter=False)
    assert result.proofs[0].sigma_window == (0.0, float("inf"))
    files = write_results(tmp_path / "s", scene, result, plots=False)
    back = meicp.load_results(files["results"])
    assert back.proofs[0].sigma_window == (0.0, float("inf")) and back.divergence is False
