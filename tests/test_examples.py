"""What the documentation shows runs: the README's Python example, and every shipped scene
with the command data/scenes/README.md names for it (as scikit-fem runs its examples)."""

import contextlib
import io
import re

import pytest

import meicp
from meicp.cli.exit import Exit

from .conftest import ROOT

SCENES = ROOT / "data" / "scenes"
#: columns and rows of the coarsened copies of the 10⁶-DOF scenes
COARSE = {"nx = 1000": "nx = 40", "rows = 250": "rows = 5"}


def _scene_table() -> dict:
    """scene file → (command, verdict) from data/scenes/README.md."""
    rows = re.findall(r"^\| `([\w.]+\.toml)` \| `([^`]+)` \| *([\w ]*?) *\|", (SCENES / "README.md").read_text(), re.M)
    return {name: (command, verdict) for name, command, verdict in rows}


TABLE = _scene_table()


def test_every_shipped_scene_is_listed_with_its_command():
    assert set(TABLE) == {p.name for p in SCENES.glob("*.toml")}
    assert {command for command, _ in TABLE.values()} == {"meicp solve", "mpirun -n 2 meicp solve",
                                                          "meicp lattice"}


@pytest.mark.parametrize("name", sorted(n for n, (c, _) in TABLE.items() if c == "meicp solve"))
def test_solve_scene(cli, name):
    code, out, err = cli("solve", SCENES / name, "--no-output", "-q")
    assert code == Exit.OK, err
    assert re.search(rf"^verdict\s+{TABLE[name][1]}$", out, re.M), out
    assert re.search(r"^divergence\s+(NO )?DIVERGENCE$", out, re.M), out  # every shipped scene decides (issue 33)


def _coarsened(tmp_path, name):
    """The scene as shipped, or coarsened to 40 columns and 10 rows when it has 10⁶ DOFs."""
    text = (SCENES / name).read_text()
    if meicp.load_scene(SCENES / name).n_dofs < 1_000_000:
        return SCENES / name
    for old, new in COARSE.items():
        assert old in text
        text = text.replace(old, new)
    (tmp_path / name).write_text(text)
    return tmp_path / name


@pytest.mark.parametrize("name", sorted(n for n, (c, _) in TABLE.items() if c == "mpirun -n 2 meicp solve"))
def test_large_solve_scene_coarsened(cli, tmp_path, name):
    assert meicp.load_scene(SCENES / name).n_dofs == 1_000_000
    code, out, err = cli("solve", _coarsened(tmp_path, name), "--no-output", "-q")
    assert code == Exit.OK, err
    assert re.search(r"^verdict\s+(STABLE|UNSTABLE|UNDECIDED)$", out, re.M), out
    assert re.search(r"^divergence\s+(NO )?DIVERGENCE$", out, re.M), out  # decided, [solver] as shipped


@pytest.mark.parametrize("name", sorted(n for n, (c, _) in TABLE.items() if c == "meicp lattice"))
def test_lattice_scene(cli, tmp_path, name):
    code, out, err = cli("lattice", SCENES / name, "-o", tmp_path)
    assert code == Exit.OK, err
    stem = name.removesuffix(".toml")
    assert {p.name for p in tmp_path.iterdir()} == {f"{stem}.h5", f"{stem}.xdmf", f"{stem}.png"}
    # no contact: `solve` gives the lattice's modal analysis (the 10⁶-DOF scene coarsened)
    code, out, err = cli("solve", _coarsened(tmp_path, name), "--no-output", "-q")
    assert code == Exit.OK, err
    assert TABLE[name][1] == "NO CONTACT"
    assert re.search(r"^verdict\s+NO CONTACT: modal analysis$", out, re.M), out
    assert re.search(r"^modes\s+\d+ certified vibration modes? \(σ = −ω², lowest frequency first\)$", out, re.M), out


def test_readme_python_example(monkeypatch):
    """The README's example, run as written from the repository root; what it prints is
    what its comments say."""
    code = re.search(r"```python\n(.*?)```", (ROOT / "README.md").read_text(), re.S).group(1)
    monkeypatch.chdir(ROOT)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, "README.md", "exec"), {})
    lines = out.getvalue().splitlines()
    assert lines[0].startswith("False enumeration of all 32 supports")
    sigma, rate, support = lines[1].split(" ", 2)
    assert float(sigma) == pytest.approx(0.329, abs=5e-4) and float(rate) == pytest.approx(0.574, abs=5e-4)
    assert support == "[0 1 2 3 4]"
    assert lines[2] == "True True"
    assert float(lines[3].split(":")[0]) == pytest.approx(0.174, abs=5e-4) and "the fastest, proved" in lines[3]
    onset, first, mu_c = lines[4].split()
    assert float(onset) == pytest.approx(0.630763, abs=1e-6) and first == "flutter"
    assert float(mu_c) == pytest.approx(1.906, abs=5e-4)
    assert lines[5] == "True [1. 0. 2.]"
    assert lines[6] == "InstabilityResult(UNSTABLE: divergence σ=0.3291 (1 mode), flutter growth 0.174 (3 modes), 40 DOFs)"


def test_the_benchmarks_two_layer_scene_is_the_shipped_one():
    """meicp.examples.two_layer_scene builds data/scenes/two_layers.toml (the failure map's scene)."""
    import dataclasses

    from meicp.examples import two_layer_scene

    shipped = meicp.load_scene(SCENES / "two_layers.toml")
    built = two_layer_scene(5, (2, 2), mu=3.0, load=(0.06, -0.1), petsc={"eps_tol": 1e-10},
                            title=shipped.title)
    same = {f.name for f in dataclasses.fields(shipped)} - {"source", "interfaces"}
    assert all(getattr(built, name) == getattr(shipped, name) for name in same)
    assert [(i.kind, i.stiffness) for i in built.interfaces] == [(i.kind, i.stiffness) for i in shipped.interfaces]
