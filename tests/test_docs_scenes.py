"""docs/scenes.md documents the scene files the parser reads: exactly the keys it accepts
(``meicp.io.scene_values.KEYS``, which the parser itself checks against), the defaults it
applies, the choices it allows; its example loads and its error messages are the parser's."""

import re
import tomllib

import pytest

from meicp.core.errors import ProblemError
from meicp.io.scene import loads_scene, scene_from_dict
from meicp.io.scene_values import KEYS
from meicp.scene import BOUNDARY_KINDS, CONTACT, INTERFACE_KINDS, SOLVE, STATES

from .conftest import ROOT

DOC = (ROOT / "docs" / "scenes.md").read_text()
HEADER = "| key | meaning | units | default | allowed values |"
#: the free-form table: any PETSc option, no fixed keys
FREE_FORM = {"petsc"}


def _cells(line: str) -> list[str]:
    return [c.strip() for c in line.strip().strip("|").split("|")]


def _documented() -> dict:
    """table name ("" = top level) → {key: (meaning, units, default, allowed)}, from each
    key table under a heading that names its TOML table (``[name]`` or ``[[name]]``)."""
    out, table, lines = {}, None, DOC.splitlines()
    for k, line in enumerate(lines):
        if line.startswith("## "):
            m = re.search(r"`\[\[?(\w+)\]\]?`", line)
            table = m.group(1) if m else ("" if line.startswith("## Top level") else None)
        if line.strip() == HEADER:
            assert table is not None, f"a key table under a heading that names no TOML table (line {k + 1})"
            assert table not in out, f"two key tables for [{table}]"
            rows = {}
            for row in lines[k + 2:]:
                if not row.startswith("|"):
                    break
                key, *rest = _cells(row)
                name = re.fullmatch(r"`(\w+)`", key)
                assert name, f"[{table}]: a key cell is not one `key`: {key!r}"
                assert len(rest) == 4 and all(rest), f"[{table}].{name.group(1)}: empty or missing cells"
                rows[name.group(1)] = tuple(rest)
            out[table] = rows
    return out


DOCUMENTED = _documented()


def _example() -> str:
    return re.search(r"## Example\n.*?```toml\n(.*?)```", DOC, re.S).group(1)


def test_every_table_and_key_the_parser_accepts_is_documented_and_no_other():
    assert set(DOCUMENTED) == set(KEYS)
    assert all(re.search(rf"^## `\[{name}\]`$", DOC, re.M) for name in FREE_FORM)
    for table, keys in KEYS.items():
        assert set(DOCUMENTED[table]) == set(keys), f"[{table}]"
    # the top level's keys are the tables (and the title)
    assert set(KEYS[""]) - {"title"} == set(KEYS) - {""} | FREE_FORM


#: the smallest scene, and per table the smallest entry that the parser accepts
BASE = {"lattice": {"nx": 3},
        "layers": [{"name": "A", "rows": 1, "stiffness": 1.0, "density": 1.0},
                   {"name": "B", "rows": 2, "stiffness": 2.0, "density": 1.0}],
        "boundary": {"bottom": "contact"}, "contact": {"friction": 0.5}}
MINIMAL = {"embedded": {"name": "band", "host": "B", "stiffness": 3.0, "density": 1.0},
           "interfaces": {"below": "A", "kind": "frictional", "friction": 0.5}}
#: a key whose default shows only without another: the keys of its table, and the tables,
#: dropped with it
ALSO_DROP = {("interfaces", "kind"): ("friction",), ("boundary", "bottom"): ("contact",)}


def _resolved(table: str, key: str):
    """The value the parser gives ``table.key`` when the scene leaves it out."""
    data = {name: (list(value) if isinstance(value, list) else dict(value)) for name, value in BASE.items()}
    entry = dict(MINIMAL.get(table) or (data["layers"][0] if table == "layers" else data.get(table, {})))
    for dropped in (key, *ALSO_DROP.get((table, key), ())):
        entry.pop(dropped, None)
        data.pop(dropped, None)
    if table == "":
        return getattr(scene_from_dict(data), key)
    data[table] = [entry] + data[table][1:] if table == "layers" else [entry] if table in MINIMAL else entry
    value = getattr(scene_from_dict(data), table)
    return getattr(value[0] if isinstance(value, tuple) else value, key)


DEFAULTS = [(table, key, cells[2]) for table, keys in DOCUMENTED.items() for key, cells in keys.items()
            if re.fullmatch(r"`[^`]+`", cells[2]) or (table and cells[2].startswith("none"))]


def test_the_defaults_checked_are_most_of_them():
    assert len(DEFAULTS) >= 20


@pytest.mark.parametrize("table, key, default", DEFAULTS, ids=[f"{t or 'top'}.{k}" for t, k, _ in DEFAULTS])
def test_a_documented_default_is_the_parsers(table, key, default):
    expected = None if default.startswith("none") else tomllib.loads(f"v = {default.strip('`')}")["v"]
    assert _resolved(table, key) == expected


def test_a_key_that_is_required_is_refused_when_missing():
    for table in ("lattice", "layers", "embedded", "interfaces", "contact"):
        for key, cells in DOCUMENTED[table].items():
            if cells[2] != "required":
                continue
            data = {name: (list(value) if isinstance(value, list) else dict(value)) for name, value in BASE.items()}
            entry = dict(MINIMAL.get(table) or (data[table][0] if table == "layers" else data[table]))
            entry.pop(key)
            data[table] = [entry] + data[table][1:] if table == "layers" else ([entry] if table in MINIMAL else entry)
            with pytest.raises(ProblemError, match=rf"{table}(\[0\])?\.{key} is required"):
                scene_from_dict(data)


#: (table, key) → the choices the parser allows, from meicp.scene's constants
CHOICES = {**{("boundary", side): BOUNDARY_KINDS for side in ("top", "left", "right")},
           ("boundary", "bottom"): BOUNDARY_KINDS + (CONTACT,),
           ("interfaces", "kind"): INTERFACE_KINDS,
           ("contact", "states"): (SOLVE,) + STATES}


@pytest.mark.parametrize("table, key", sorted(CHOICES))
def test_every_allowed_choice_is_documented(table, key):
    allowed = DOCUMENTED[table][key][3]
    if allowed.startswith("as `top`"):
        allowed = DOCUMENTED[table]["top"][3] + allowed
    assert all(f'`"{choice}"`' in allowed for choice in CHOICES[table, key]), allowed


def test_the_example_loads_and_has_every_table():
    text = _example()
    scene = loads_scene(text, source="scene.toml")
    assert set(tomllib.loads(text)) == set(KEYS) - {""} | FREE_FORM | {"title"}
    assert scene.embedded and scene.load is not None and dict(scene.petsc)
    # every key of every table but the free-form one and the frictional interface's
    # (shown in the second example)
    data = tomllib.loads(text)
    for table, keys in KEYS.items():
        if table == "":
            continue
        entries = data[table] if isinstance(data[table], list) else [data[table]]
        given = set().union(*entries)
        missing = set(keys) - given - ({"friction", "states"} if table == "interfaces" else set())
        assert not missing, f"[{table}] example lacks {missing}"


def test_the_frictional_interface_example_loads_in_place_of_the_bonded_one():
    example = _example()
    frictional = re.findall(r"```toml\n(.*?)```", DOC, re.S)[1]
    bonded = re.search(r"\[\[interfaces\]\]\n(?:\w.*\n)+", example).group(0)
    scene = loads_scene(example.replace(bonded, frictional), source="scene.toml")
    assert [i.kind for i in scene.interfaces] == ["frictional"]


ERRORS = re.findall(r"^\| `([^`]+)` → `([^`]+)` \| `(.+)` \|$", DOC, re.M)


def test_the_error_table_has_rows():
    assert len(ERRORS) >= 6


@pytest.mark.parametrize("old, new, message", ERRORS, ids=[new for _, new, _ in ERRORS])
def test_a_documented_error_message_is_the_parsers(old, new, message):
    example = _example()
    assert example.count(old) >= 1
    with pytest.raises(ProblemError) as err:
        loads_scene(example.replace(old, new, 1), source="scene.toml")
    assert str(err.value) == message
