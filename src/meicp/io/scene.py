"""Scene files: TOML (docs/design.md §10.1) parsed and checked into a :class:`~meicp.scene.Scene`.

A scene declares one layered lattice, its boundary conditions, its contacts and how to
solve it (the dataclasses are in :mod:`meicp.scene`; this module only parses and validates).  :func:`load_scene` reads a file, :func:`loads_scene` a string and
:func:`scene_from_dict` an already parsed table.  Every key is checked: an unknown key, a
value of the wrong type or out of range raises :class:`~meicp.core.errors.ProblemError`
naming the key path (``layers[1].density``) before anything else happens.  Unknown keys
are reported first, with the nearest known key (``lattice.nxx``: did you mean nx?), then
missing ones.

The whole schema, with defaults (``required`` = no default)::

    title = ""                    # optional free text

    [lattice]
    nx = 5                        # required, integer >= 2: nodes per row, left to right
    spacing = 1.0                 # a > 0: node spacing, also the mass a³ per unit density
    shear = 0.0                   # reference simple shear: node (i, j) at (a·i + shear·a·j, a·j)
    interface_stiffness = "mean"  # default k_AB of a bond joining two materials:
                                  # "mean" ((k_A + k_B) / 2) or a number > 0

    [[layers]]                    # required, at least one, bottom to top
    name = "A"                    # required, unique among layers and embedded bands
    rows = 2                      # required, integer >= 1
    stiffness = 1.0               # required, > 0: k of every bond inside the layer
    density = 1.0                 # required, > 0: node mass ρ·a³ (both DOFs)

    [[embedded]]                  # optional: a band of another material inside a layer
    name = "stiff"                # required, unique
    host = "A"                    # required: the layer it lies in
    row = 0                       # first row, counted from the host's bottom row (default 0)
    rows = 1                      # thickness in rows (default 1); row + rows <= host rows
    column = 0                    # first column (default 0)
    columns = 3                   # width in columns (default: to the right edge)
    stiffness = 10.0              # required, > 0
    density = 1.0                 # required, > 0
    interface_stiffness = 2.0     # k of bonds to the host (default: lattice rule)

    [boundary]                    # each side: "free" (default), "fixed", "fixed_x", "fixed_y";
    top = "fixed"                 # bottom may also be "contact" (a rigid rough base, needs
    bottom = "contact"            # [contact]).  fixed_x / fixed_y fix one component only.
    left = "free"
    right = "free"

    [[interfaces]]                # optional, between layer `below` and the layer above it
    below = "A"                   # required: a layer that is not the top one
    kind = "bonded"               # "bonded" (default) | "frictional"
    stiffness = 3.0               # bonded only: k_AB (default: lattice rule)
    friction = 0.6                # frictional only, required, >= 0: Coulomb μ
    states = "solve"              # frictional only: see [contact].states (default "solve")

    [contact]                     # the rigid base; required iff boundary.bottom = "contact"
    friction = 3.0                # required, >= 0: Coulomb μ
    states = "slip+"              # "solve" (default: from the static LCP), one state for all
                                  # contact nodes, or a list of nx states, left to right, from
                                  # stick | slip+ | slip- | separated | grazing

    [load]                        # optional
    top_displacement = [0.06, -0.1]   # prescribed displacement of the top row (needs a
                                      # top boundary that is not "free")
    side_displacement = [0.05, -0.05] # prescribed x displacement of the left and right
                                      # columns [left_ux, right_ux] (lateral shortening); a
                                      # nonzero value needs that side "fixed" or "fixed_x"
                                      # (default: none, i.e. fixed sides stay at 0);
                                      # at a corner the top row's, then a fixed bottom
                                      # row's prescription wins
    gravity = 0.0                 # body force -gravity·ρ·a³ on every node, in y

    [solver]
    method = "auto"               # a method name, checked by the solver that uses it
    all_solutions = false         # enumerate every complementarity solution
    lam_min = <none>              # list only the modes with σ >= lam_min (>= 0), optional;
                                  # the verdict is about every σ >= 0 whatever it is
    nev = <none>                  # eigenpairs per eigen-solve (integer >= 1), optional
    tol = <none>                  # certificate tolerance in (0, 0.01], optional
    max_iterations = <none>       # integer >= 1, optional
    flutter = true                # also decide flutter of steady sliding (docs/flutter.md)

    [petsc]                       # free-form: PETSc options (without the leading dash and
    eps_tol = 1e-10               # without the solver's prefix); scalar values only

Values that are each in range but not together are refused too: node coordinates and
masses ρ·a³ must be finite normal doubles, and the bond stiffnesses of a scene may differ by
at most ``MAX_STIFFNESS_CONTRAST``.  Files are read within bounds (:func:`read_scene_text`:
a regular file, at most ``MAX_SCENE_BYTES``, UTF-8, nesting at most ``MAX_NESTING`` deep);
whether the scene fits the machine is checked where it is used
(:func:`meicp.lattice.size.check_size`).

What is resolved at load time (the interfaces not declared, default stiffnesses, the width
of an embedded band) is described in :mod:`meicp.scene`.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import os
import re
import reprlib
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ..core.errors import ProblemError
from ..core.validation import MAX_TOL
from ..scene import (BOUNDARY_KINDS, CONTACT, INTERFACE_KINDS, SIDES, SOLVE, STATES, Boundary, Contact,
                     Embedded, FrozenOptions, Interface, Lattice, Layer, Load, Scene, Solver)
from .problem_files import read_text


# --------------------------------------------------------------------------- loading

def as_scene(scene) -> Scene:
    """``scene`` itself, or the Scene read from it when it is a scene file path (str or
    ``os.PathLike``): what the public entry points accept."""
    return load_scene(scene) if isinstance(scene, (str, os.PathLike)) else scene


#: the largest scene file read (a per-node state list of 10⁵ columns is about 1 MB)
MAX_SCENE_BYTES = 4 * 2 ** 20
#: the deepest nesting of arrays / inline tables, and the longest dotted key, accepted: a
#: scene needs 3; tomllib recurses on the first and is quadratic in the second (a 60 kB
#: key ``a.a.a...`` takes gigabytes)
MAX_NESTING = 32


def read_scene_text(path) -> str:
    """The text of a scene file, read within bounds: a regular file (not ``/dev/zero`` or
    a FIFO), at most ``MAX_SCENE_BYTES``, UTF-8 (a byte-order mark is dropped).  Raises
    :class:`ProblemError` naming the file and the problem."""
    path = Path(path)
    if not path.exists():
        raise ProblemError(f"cannot read scene file {str(path)!r}: no such file")
    data = read_text(path, MAX_SCENE_BYTES, what="scene", limit_name="meicp.io.scene.MAX_SCENE_BYTES")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ProblemError(f"{path}: not UTF-8 text (byte 0x{data[exc.start]:02x} at offset {exc.start} "
                           "is invalid): a scene file is TOML, which is UTF-8") from None


def load_scene(path) -> Scene:
    """Read and validate a TOML scene file.  Raises :class:`ProblemError` naming the key."""
    return loads_scene(read_scene_text(path), source=str(path))


def loads_scene(text: str, source: str = "<string>") -> Scene:
    """Parse and validate scene TOML given as a string."""
    if not isinstance(text, str):
        raise ProblemError(f"{source}: scene text must be a string, got {type(text).__name__}")
    text = text.removeprefix("\ufeff")  # a byte-order mark is not TOML, but harmless
    _check_nesting(text, source)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ProblemError(f"{source}: not valid TOML: {exc}") from None
    except RecursionError:
        raise ProblemError(f"{source}: not a scene: arrays or tables nested too deeply") from None
    return scene_from_dict(data, source=source)


#: what matters to nesting in TOML text: strings and comments (skipped whole), brackets,
#: braces, dots and the characters that end a key
_LEXEMES = re.compile(r'"""(?:[^\\]|\\.)*?"""|\'\'\'.*?\'\'\'|"(?:[^"\\\n]|\\.)*"|\'[^\'\n]*\'|#[^\n]*|[][{}.=,\n]',
                      re.S)


def _check_nesting(text: str, source: str) -> None:
    """Refuse nesting deeper than MAX_NESTING before tomllib sees it: brackets and braces
    outside strings and comments, and dots in one key outside strings."""
    depth = dots = 0
    for m in _LEXEMES.finditer(text):
        c = m.group()
        if c in "[{":
            depth += 1
        elif c in "]}":
            depth -= 1
        elif c == ".":
            dots += 1
        if c in "=,[]{}\n":
            dots = 0
        if depth > MAX_NESTING or dots > MAX_NESTING:
            what = "arrays or inline tables nested" if depth > MAX_NESTING else "a dotted key"
            line = text.count("\n", 0, m.start()) + 1
            raise ProblemError(f"{source}: line {line}: {what} deeper than {MAX_NESTING} levels: not a scene")


def scene_from_dict(data: Mapping, source: str = "<dict>") -> Scene:
    """Validate an already parsed scene table (as :mod:`tomllib` returns it)."""
    return _SceneParser(source).parse(data)


# --------------------------------------------------------------------------- validation

_REQUIRED = object()
#: the smallest normal double: a node mass below it loses precision, 0 makes B singular
_TINY = 2.2250738585072014e-308
#: the largest ratio of two bond stiffnesses in one scene: where a bond of stiffness k meets
#: one of k·C, the first keeps about 16 − log10(C) digits in K (double precision); with the
#: stiff layer floating on the base, two_layers.toml gives the same verdict up to C = 1e12
#: and σ < 0 "modes" from 1e14 on
MAX_STIFFNESS_CONTRAST = 1e12


_REPR = reprlib.Repr()
_REPR.maxstring = _REPR.maxother = 80


def _fmt(value) -> str:
    """A value for a message: its repr, shortened (a scene may hold a million-entry list)."""
    return _REPR.repr(value)


def _keys(cls, *skip: str) -> tuple[str, ...]:
    """The TOML keys of a table: the fields of its :mod:`meicp.scene` dataclass, which are
    named after them (``skip``: fields resolved at load time, not keys)."""
    return tuple(f.name for f in dataclasses.fields(cls) if f.name not in skip)


#: the keys each table accepts, checked before any value is read (so that a misspelt
#: required key is reported as the unknown key it is, not as the required one missing)
KEYS = {
    "": _keys(Scene, "source"),
    "lattice": _keys(Lattice),
    "layers": _keys(Layer),
    "embedded": _keys(Embedded),
    "boundary": _keys(Boundary),
    "interfaces": _keys(Interface, "index", "declared"),
    "contact": _keys(Contact),
    "load": _keys(Load),
    "solver": _keys(Solver),
}


class _Table:
    """Reads the keys of one table, remembering its key path and which keys were used.

    ``keys``: every key the table accepts.  Unknown keys are reported first (with the
    nearest known one), before any missing or wrong value."""

    def __init__(self, parser: "_SceneParser", data, path: str, keys: tuple[str, ...]):
        self.parser = parser
        self.path = path
        if not isinstance(data, Mapping):
            parser.fail(path, f"must be a table, got {type(data).__name__} {_fmt(data)}")
        self.data = data
        self.keys = keys
        self.used: set[str] = set()
        for name in data:
            if name not in keys:
                self._unknown(name)

    def _unknown(self, name) -> None:
        near = difflib.get_close_matches(str(name), self.keys, n=1)
        hint = f"did you mean {near[0]}? " if near else ""
        self.parser.fail(self.key(name), f"({hint}known here: {', '.join(self.keys)})", prefix="unknown key ")

    def key(self, name: str) -> str:
        return f"{self.path}.{name}" if self.path else name

    def raw(self, name: str, default=_REQUIRED):
        self.used.add(name)
        if name not in self.data:
            if default is _REQUIRED:
                self.parser.fail(self.key(name), "is required")
            return default
        return self.data[name]

    def integer(self, name: str, default=_REQUIRED, minimum: int | None = None):
        value = self.raw(name, default)
        if value is default and name not in self.data:
            return value
        if isinstance(value, bool) or not isinstance(value, int):
            self.parser.fail(self.key(name), f"must be an integer, got {_fmt(value)}")
        if minimum is not None and value < minimum:
            self.parser.fail(self.key(name), f"must be >= {minimum}, got {value}")
        return int(value)

    def number(self, name: str, default=_REQUIRED, *, positive=False, nonnegative=False):
        value = self.raw(name, default)
        if value is default and name not in self.data:
            return value
        return self.parser.check_number(self.key(name), value, positive=positive,
                                        nonnegative=nonnegative)

    def string(self, name: str, default=_REQUIRED, choices=None):
        value = self.raw(name, default)
        if value is default and name not in self.data:
            return value
        if not isinstance(value, str):
            self.parser.fail(self.key(name), f"must be a string, got {_fmt(value)}")
        if choices is not None and value not in choices:
            self.parser.fail(self.key(name), f"must be one of {', '.join(map(repr, choices))}, "
                                             f"got {_fmt(value)}")
        return value

    def boolean(self, name: str, default=_REQUIRED):
        value = self.raw(name, default)
        if not isinstance(value, bool):
            self.parser.fail(self.key(name), f"must be true or false, got {_fmt(value)}")
        return value

    def done(self) -> None:
        """Every key given was read (a key in ``keys`` that the parser never reads is a bug)."""
        unread = [k for k in self.data if k not in self.used]
        if unread:
            self._unknown(unread[0])


class _SceneParser:
    def __init__(self, source: str):
        self.source = source

    def fail(self, key: str, message: str, prefix: str = ""):
        raise ProblemError(f"{self.source}: {prefix}{key} {message}")

    def check_number(self, key, value, *, positive=False, nonnegative=False) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            self.fail(key, f"must be a number, got {_fmt(value)}")
        value = float(value)
        if not math.isfinite(value):
            self.fail(key, f"must be finite, got {value}")
        if positive and not value > 0:
            self.fail(key, f"must be > 0, got {value:g}")
        if nonnegative and not value >= 0:
            self.fail(key, f"must be >= 0, got {value:g}")
        return value

    def array_of_tables(self, data, name: str) -> list:
        value = data.get(name, [])
        if not isinstance(value, list) or not all(isinstance(v, Mapping) for v in value):
            self.fail(name, f"must be an array of tables ([[{name}]]), got {_fmt(value)}")
        return value

    def states(self, key: str, value, n: int):
        if isinstance(value, str):
            if value != SOLVE and value not in STATES:
                self.fail(key, f"must be {SOLVE!r}, one of {', '.join(map(repr, STATES))} "
                               f"or a list of those, got {_fmt(value)}")
            return value
        if not isinstance(value, list):
            self.fail(key, f"must be a string or a list of strings, got {_fmt(value)}")
        if len(value) != n:
            self.fail(key, f"must list one state per column (nx = {n}), got {len(value)}")
        for k, s in enumerate(value):
            if s not in STATES:
                extra = " ('solve' stands for the whole list, not one node)" if s == SOLVE else ""
                self.fail(f"{key}[{k}]", f"must be one of {', '.join(map(repr, STATES))}, "
                                         f"got {_fmt(s)}{extra}")
        return tuple(value)

    # ---------------------------------------------------------------- the whole scene
    def parse(self, data) -> Scene:
        top = _Table(self, data, "", KEYS[""])
        title = top.string("title", "")
        lattice = self.lattice(top.raw("lattice"))
        top.used.update({"layers", "embedded", "interfaces"})
        layers = self.layers(data, lattice)
        embedded = self.embedded(data, lattice, layers)
        interfaces = self.interfaces(data, lattice, layers)
        boundary = self.boundary(top.raw("boundary", {}))
        contact_data = top.raw("contact", None)
        contact = None
        if contact_data is not None:
            contact = self.contact(contact_data, lattice)
        if boundary.bottom == CONTACT and contact is None:
            self.fail("contact", "is required when boundary.bottom = \"contact\" "
                                 "(give at least contact.friction)")
        if contact is not None and boundary.bottom != CONTACT:
            self.fail("contact", f"describes the rigid base, but boundary.bottom is "
                                 f"{boundary.bottom!r}, not \"contact\"")
        load_data = top.raw("load", None)
        load = None if load_data is None else self.load(load_data, boundary)
        solver = self.solver(top.raw("solver", {}))
        petsc = self.petsc(top.raw("petsc", {}))
        top.done()
        ny = sum(layer.rows for layer in layers)
        if ny * lattice.nx * 2 >= 2**62:
            self.fail("layers", f"declare {ny} rows x {lattice.nx} columns: too many DOFs")
        self.magnitudes(lattice, ny, layers, embedded, interfaces, contact, load)
        return Scene(lattice=lattice, layers=tuple(layers), boundary=boundary,
                     interfaces=tuple(interfaces), embedded=tuple(embedded), contact=contact,
                     load=load, solver=solver, petsc=petsc, title=title, source=self.source)

    def lattice(self, data) -> Lattice:
        t = _Table(self, data, "lattice", KEYS["lattice"])
        nx = t.integer("nx", minimum=2)
        spacing = t.number("spacing", 1.0, positive=True)
        shear = t.number("shear", 0.0)
        kab = t.raw("interface_stiffness", "mean")
        if isinstance(kab, str):
            if kab != "mean":
                self.fail("lattice.interface_stiffness", f"must be \"mean\" or a number > 0, got {kab!r}")
        else:
            kab = self.check_number("lattice.interface_stiffness", kab, positive=True)
        t.done()
        return Lattice(nx=nx, spacing=spacing, shear=shear, interface_stiffness=kab)

    def layers(self, data, lattice) -> list[Layer]:
        if "layers" not in data:
            self.fail("layers", "is required: at least one [[layers]] table, bottom to top")
        entries = self.array_of_tables(data, "layers")
        if not entries:
            self.fail("layers", "must have at least one [[layers]] table")
        layers, names = [], set()
        for k, entry in enumerate(entries):
            t = _Table(self, entry, f"layers[{k}]", KEYS["layers"])
            name = t.string("name")
            if not name:
                self.fail(t.key("name"), "must not be empty")
            if name in names:
                self.fail(t.key("name"), f"repeats the layer name {name!r}")
            names.add(name)
            layer = Layer(name=name, rows=t.integer("rows", minimum=1),
                          stiffness=t.number("stiffness", positive=True),
                          density=t.number("density", positive=True))
            t.done()
            layers.append(layer)
        return layers

    def embedded(self, data, lattice, layers) -> list[Embedded]:
        entries = self.array_of_tables(data, "embedded")
        by_name = {layer.name: layer for layer in layers}
        out, names, boxes = [], set(by_name), []
        for k, entry in enumerate(entries):
            t = _Table(self, entry, f"embedded[{k}]", KEYS["embedded"])
            name = t.string("name")
            if not name:
                self.fail(t.key("name"), "must not be empty")
            if name in names:
                self.fail(t.key("name"), f"repeats the name {name!r} (layer and band names are unique)")
            names.add(name)
            host = t.string("host")
            if host not in by_name:
                self.fail(t.key("host"), f"must name a layer ({', '.join(map(repr, by_name))}), got {host!r}")
            hrows = by_name[host].rows
            row = t.integer("row", 0, minimum=0)
            rows = t.integer("rows", 1, minimum=1)
            if row + rows > hrows:
                self.fail(t.key("rows"), f"row + rows = {row + rows} exceeds the {hrows} rows of layer {host!r}")
            column = t.integer("column", 0, minimum=0)
            if column >= lattice.nx:
                self.fail(t.key("column"), f"must be < nx = {lattice.nx}, got {column}")
            columns = t.integer("columns", lattice.nx - column, minimum=1)
            if column + columns > lattice.nx:
                self.fail(t.key("columns"), f"column + columns = {column + columns} exceeds nx = {lattice.nx}")
            stiffness = t.number("stiffness", positive=True)
            density = t.number("density", positive=True)
            kab = t.number("interface_stiffness", None, positive=True)
            if kab is None:
                kab = lattice.pair_stiffness(stiffness, by_name[host].stiffness)
            t.done()
            box = (host, row, row + rows, column, column + columns)
            for other_k, other in boxes:
                if (other[0] == host and box[1] < other[2] and other[1] < box[2]
                        and box[3] < other[4] and other[3] < box[4]):
                    self.fail(f"embedded[{k}]", f"overlaps embedded[{other_k}] in layer {host!r}")
            boxes.append((k, box))
            out.append(Embedded(name=name, host=host, stiffness=stiffness, density=density,
                                row=row, rows=rows, column=column, columns=columns,
                                interface_stiffness=kab))
        return out

    def interfaces(self, data, lattice, layers) -> list[Interface]:
        entries = self.array_of_tables(data, "interfaces")
        index = {layer.name: k for k, layer in enumerate(layers)}
        declared: dict[int, Interface] = {}
        for k, entry in enumerate(entries):
            t = _Table(self, entry, f"interfaces[{k}]", KEYS["interfaces"])
            below = t.string("below")
            if below not in index:
                self.fail(t.key("below"), f"must name a layer ({', '.join(map(repr, index))}), got {below!r}")
            i = index[below]
            if i == len(layers) - 1:
                self.fail(t.key("below"), f"names the top layer {below!r}: there is no layer above it")
            if i in declared:
                self.fail(t.key("below"), f"repeats the interface above layer {below!r}")
            kind = t.string("kind", "bonded", INTERFACE_KINDS)
            if kind == "bonded":
                for bad in ("friction", "states"):
                    if bad in entry:
                        self.fail(t.key(bad), "applies to kind = \"frictional\" only")
                stiffness = t.number("stiffness", None, positive=True)
                if stiffness is None:
                    stiffness = lattice.pair_stiffness(layers[i].stiffness, layers[i + 1].stiffness)
                itf = Interface(below=below, index=i, kind=kind, stiffness=stiffness, declared=True)
            else:
                if "stiffness" in entry:
                    self.fail(t.key("stiffness"), "applies to kind = \"bonded\" only "
                                                  "(a frictional interface has no bonds)")
                friction = t.number("friction", positive=False, nonnegative=True)
                states = self.states(t.key("states"), t.raw("states", SOLVE), lattice.nx)
                itf = Interface(below=below, index=i, kind=kind, friction=friction,
                                states=states, declared=True)
            t.done()
            declared[i] = itf
        out = []
        for i in range(len(layers) - 1):
            out.append(declared.get(i) or Interface(
                below=layers[i].name, index=i, kind="bonded",
                stiffness=lattice.pair_stiffness(layers[i].stiffness, layers[i + 1].stiffness)))
        return out

    def boundary(self, data) -> Boundary:
        t = _Table(self, data, "boundary", KEYS["boundary"])
        values = {}
        for side in SIDES:
            choices = BOUNDARY_KINDS + ((CONTACT,) if side == "bottom" else ())
            values[side] = t.string(side, "free", choices)
        t.done()
        return Boundary(**values)

    def contact(self, data, lattice) -> Contact:
        t = _Table(self, data, "contact", KEYS["contact"])
        friction = t.number("friction", nonnegative=True)
        states = self.states("contact.states", t.raw("states", SOLVE), lattice.nx)
        t.done()
        return Contact(friction=friction, states=states)

    def load(self, data, boundary) -> Load:
        t = _Table(self, data, "load", KEYS["load"])
        top = t.raw("top_displacement", None)
        if top is not None:
            if not isinstance(top, list) or len(top) != 2:
                self.fail("load.top_displacement", f"must be a list of 2 numbers [ux, uy], got {_fmt(top)}")
            top = tuple(self.check_number(f"load.top_displacement[{k}]", v) for k, v in enumerate(top))
            if boundary.top == "free":
                self.fail("load.top_displacement", "needs a top boundary that is fixed "
                                                   "(boundary.top is \"free\")")
        side = t.raw("side_displacement", None)
        if side is not None:
            if not isinstance(side, list) or len(side) != 2:
                self.fail("load.side_displacement", f"must be a list of 2 numbers [left_ux, right_ux], "
                                                    f"got {_fmt(side)}")
            side = tuple(self.check_number(f"load.side_displacement[{k}]", v) for k, v in enumerate(side))
            for k, name in enumerate(("left", "right")):
                if side[k] != 0.0 and not boundary.fixed_components(name)[0]:
                    self.fail("load.side_displacement", f"prescribes x = {side[k]:g} on the {name} side, "
                              f"which needs boundary.{name} = \"fixed\" or \"fixed_x\" "
                              f"(it is {getattr(boundary, name)!r})")
        gravity = t.number("gravity", 0.0)
        t.done()
        return Load(top_displacement=top, gravity=gravity, side_displacement=side)

    def solver(self, data) -> Solver:
        t = _Table(self, data, "solver", KEYS["solver"])
        method = t.string("method", "auto")
        if not method:
            self.fail("solver.method", "must not be empty")
        s = Solver(method=method,
                   all_solutions=t.boolean("all_solutions", False),
                   lam_min=t.number("lam_min", None, nonnegative=True),
                   nev=t.integer("nev", None, minimum=1),
                   tol=t.number("tol", None, positive=True),
                   max_iterations=t.integer("max_iterations", None, minimum=1),
                   flutter=t.boolean("flutter", True))
        t.done()
        if s.tol is not None and s.tol > MAX_TOL:
            self.fail("solver.tol", f"must be <= {MAX_TOL:g} (a relative certificate tolerance; a looser "
                                    f"one certifies nothing), got {s.tol:g}")
        return s

    def magnitudes(self, lattice, ny: int, layers, embedded, interfaces, contact, load) -> None:
        """Values each in range alone but not together: coordinates and node masses must be
        finite normal floats, and the bond stiffnesses (and a friction coefficient, which
        multiplies them in a slipping node's row) within MAX_STIFFNESS_CONTRAST of each
        other."""
        a = lattice.spacing
        extent = max(lattice.nx - 1 + abs(lattice.shear) * (ny - 1), ny - 1, 1)
        if not math.isfinite(a * extent) or not math.isfinite(a * math.hypot(1.0, lattice.shear)):
            self.fail("lattice.spacing", f"= {a:g} with nx = {lattice.nx}, {ny} rows and shear = "
                                         f"{lattice.shear:g} puts nodes beyond double precision")
        cube = a * a * a  # the mass per unit density; a ** 3 would raise OverflowError
        if not (math.isfinite(cube) and cube >= _TINY):
            self.fail("lattice.spacing", f"= {a:g}: the node mass per unit density a³ = {cube:g} is beyond "
                                         "double precision (a must lie in about [3e-103, 5e102])")
        masses = [(f"layers[{k}].density", m.density) for k, m in enumerate(layers)]
        masses += [(f"embedded[{k}].density", e.density) for k, e in enumerate(embedded)]
        for key, rho in masses:
            mass = rho * cube
            if not (math.isfinite(mass) and mass >= _TINY):
                self.fail(key, f"= {rho:g} with lattice.spacing = {a:g} gives a node mass ρ·a³ = {mass:g}, "
                               "beyond double precision (it must lie in [2.2e-308, 1.8e308])")
            if load is not None and not math.isfinite(load.gravity * mass):
                self.fail("load.gravity", f"= {load.gravity:g} times the node mass of {key} overflows")
        stiff = [(f"layers[{k}].stiffness", m.stiffness) for k, m in enumerate(layers)]
        stiff += [(f"embedded[{k}].stiffness", e.stiffness) for k, e in enumerate(embedded)]
        stiff += [(f"embedded[{k}].interface_stiffness", e.interface_stiffness) for k, e in enumerate(embedded)]
        stiff += [(f"interfaces.stiffness (below = {i.below!r})", i.stiffness) for i in interfaces
                  if i.bonded and i.declared]
        if not isinstance(lattice.interface_stiffness, str):
            stiff.append(("lattice.interface_stiffness", lattice.interface_stiffness))
        (k_lo, lo), (k_hi, hi) = min(stiff, key=lambda t: t[1]), max(stiff, key=lambda t: t[1])
        if hi > MAX_STIFFNESS_CONTRAST * lo:
            self.fail(k_lo, f"= {lo:g} and {k_hi} = {hi:g} differ by {hi / lo:.1e}, more than "
                            f"{MAX_STIFFNESS_CONTRAST:.0e}: the softer bonds are lost in the rounding of "
                            "the stiffer ones where they meet (measured: wrong modes from 1e14 on); model a "
                            "rigid part with fixed boundary conditions instead")
        frictions = [("contact.friction", contact.friction)] if contact is not None else []
        frictions += [(f"interfaces.friction (below = {i.below!r})", i.friction) for i in interfaces
                      if not i.bonded]
        for key, mu in frictions:
            if mu > MAX_STIFFNESS_CONTRAST:
                self.fail(key, f"= {mu:g} is above {MAX_STIFFNESS_CONTRAST:.0e}: a slipping node's row sums "
                               "μ times the normal stiffness and the tangential one, which would be lost in "
                               "rounding (measured: spurious modes at μ = 1e300)")

    def petsc(self, data) -> Mapping[str, Any]:
        if not isinstance(data, Mapping):
            self.fail("petsc", f"must be a table, got {_fmt(data)}")
        out = {}
        for key, value in data.items():
            if isinstance(value, (Mapping, list)) or not isinstance(value, (str, int, float, bool)):
                self.fail(f"petsc.{key}", f"must be a string, number or boolean, got {_fmt(value)}")
            if isinstance(value, float) and not math.isfinite(value):
                self.fail(f"petsc.{key}", f"must be finite, got {value}")
            name = key.lstrip("-")
            if not name or any(c.isspace() for c in name):
                self.fail(f"petsc.{key}", "is not a valid PETSc option name")
            out[name] = value
        return FrozenOptions(out)
