"""Reading one table of a scene file: the keys it accepts, each value checked for type and
range, and errors that name the scene and the key path (``layers[1].density``).  The scene's
tables themselves are read in :mod:`meicp.io.scene_tables`."""

from __future__ import annotations

import dataclasses
import difflib
import math
import reprlib
from collections.abc import Mapping

from ..core.errors import ProblemError
from ..scene import (SOLVE, STATES, Boundary, Contact, Damping, Embedded, Interface, Lattice, Layer, Load,
                     Scene, Solver)

#: the default of a key that has none: its absence is an error
REQUIRED = object()

_REPR = reprlib.Repr()
_REPR.maxstring = _REPR.maxother = 80


def fmt_value(value) -> str:
    """A value for a message: its repr, shortened (a scene may hold a million-entry list)."""
    return _REPR.repr(value)


def table_keys(cls, *skip: str) -> tuple[str, ...]:
    """The TOML keys of a table: the fields of its :mod:`meicp.scene` dataclass, which are
    named after them (``skip``: fields resolved at load time, not keys)."""
    return tuple(f.name for f in dataclasses.fields(cls) if f.name not in skip)


#: the keys each table accepts, checked before any value is read (so that a misspelt
#: required key is reported as the unknown key it is, not as the required one missing)
KEYS = {
    "": table_keys(Scene, "source"),
    "lattice": table_keys(Lattice),
    "layers": table_keys(Layer),
    "embedded": table_keys(Embedded),
    "boundary": table_keys(Boundary),
    "interfaces": table_keys(Interface, "index", "declared"),
    "contact": table_keys(Contact),
    "load": table_keys(Load),
    "damping": table_keys(Damping),
    "solver": table_keys(Solver),
}


class Table:
    """Reads the keys of one table, remembering its key path and which keys were used.

    ``keys``: every key the table accepts.  Unknown keys are reported first (with the
    nearest known one), before any missing or wrong value."""

    def __init__(self, parser: ValueChecks, data, path: str, keys: tuple[str, ...]):
        self.parser = parser
        self.path = path
        if not isinstance(data, Mapping):
            parser.fail(path, f"must be a table, got {type(data).__name__} {fmt_value(data)}")
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

    def raw(self, name: str, default=REQUIRED):
        self.used.add(name)
        if name not in self.data:
            if default is REQUIRED:
                self.parser.fail(self.key(name), "is required")
            return default
        return self.data[name]

    def integer(self, name: str, default=REQUIRED, minimum: int | None = None):
        value = self.raw(name, default)
        if value is default and name not in self.data:
            return value
        if isinstance(value, bool) or not isinstance(value, int):
            self.parser.fail(self.key(name), f"must be an integer, got {fmt_value(value)}")
        if minimum is not None and value < minimum:
            self.parser.fail(self.key(name), f"must be >= {minimum}, got {value}")
        return int(value)

    def number(self, name: str, default=REQUIRED, *, positive=False, nonnegative=False):
        value = self.raw(name, default)
        if value is default and name not in self.data:
            return value
        return self.parser.check_number(self.key(name), value, positive=positive,
                                        nonnegative=nonnegative)

    def string(self, name: str, default=REQUIRED, choices=None):
        value = self.raw(name, default)
        if value is default and name not in self.data:
            return value
        if not isinstance(value, str):
            self.parser.fail(self.key(name), f"must be a string, got {fmt_value(value)}")
        if choices is not None and value not in choices:
            self.parser.fail(self.key(name), f"must be one of {', '.join(map(repr, choices))}, "
                                             f"got {fmt_value(value)}")
        return value

    def boolean(self, name: str, default=REQUIRED):
        value = self.raw(name, default)
        if not isinstance(value, bool):
            self.parser.fail(self.key(name), f"must be true or false, got {fmt_value(value)}")
        return value

    def done(self) -> None:
        """Every key given was read (a key in ``keys`` that the parser never reads is a bug)."""
        unread = [k for k in self.data if k not in self.used]
        if unread:
            self._unknown(unread[0])


class ValueChecks:
    """Checks of single values, failing with a :class:`ProblemError` that names the scene
    (``source``) and the key path."""

    def __init__(self, source: str):
        self.source = source

    def fail(self, key: str, message: str, prefix: str = ""):
        raise ProblemError(f"{self.source}: {prefix}{key} {message}")

    def check_number(self, key, value, *, positive=False, nonnegative=False) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            self.fail(key, f"must be a number, got {fmt_value(value)}")
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
            self.fail(name, f"must be an array of tables ([[{name}]]), got {fmt_value(value)}")
        return value

    def states(self, key: str, value, n: int):
        if isinstance(value, str):
            if value != SOLVE and value not in STATES:
                self.fail(key, f"must be {SOLVE!r}, one of {', '.join(map(repr, STATES))} "
                               f"or a list of those, got {fmt_value(value)}")
            return value
        if not isinstance(value, list):
            self.fail(key, f"must be a string or a list of strings, got {fmt_value(value)}")
        if len(value) != n:
            self.fail(key, f"must list one state per column (nx = {n}), got {len(value)}")
        for k, s in enumerate(value):
            if s not in STATES:
                extra = " ('solve' stands for the whole list, not one node)" if s == SOLVE else ""
                self.fail(f"{key}[{k}]", f"must be one of {', '.join(map(repr, STATES))}, "
                                         f"got {fmt_value(s)}{extra}")
        return tuple(value)
