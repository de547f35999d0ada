"""The scene: one layered lattice, its boundary conditions, contacts, load and solver
settings, as frozen dataclasses (docs/design.md §10).  The vocabulary every package shares — the
lattice is built from it, the contact analysis reads its states, the results record it —
so it depends on nothing but :mod:`meicp.core`.

Reading and checking a scene file is :mod:`meicp.io.scene`'s job (it documents the TOML
keys, which are named like the fields below); a scene built in code is checked by the same
parser through :func:`meicp.io.scene.scene_from_dict`.  For studies, a scene changes by
:meth:`Scene.with_friction`, :meth:`Scene.with_states` and :meth:`Scene.with_load`: each
writes the scene as its table (:meth:`Scene.to_dict`), changes it and reads it back through
that parser — which :mod:`meicp.io.scene` hands to this module (:func:`use_parser`) when
``meicp`` is imported, so that this module depends on :mod:`meicp.core` alone — hence a
bad value is a ProblemError naming its key, as in a file.

Resolved when a scene is loaded, so that later code has one place to look:
``Scene.interfaces`` has one entry per pair of adjacent layers, bottom to top (those not
declared are bonded with the lattice's default rule), and every bonded interface or
embedded band carries its numeric ``stiffness``; a frictional interface has ``stiffness =
None`` and no bonds (its contact law is added by :mod:`meicp.contact`).
``Embedded.columns`` is resolved to a number.
"""

from __future__ import annotations

import dataclasses
import numbers
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from .core.errors import ProblemError
from .core.validation import checked_keywords

#: boundary condition names for any side; "contact" is allowed on the bottom only
BOUNDARY_KINDS = ("free", "fixed", "fixed_x", "fixed_y")
CONTACT = "contact"
SIDES = ("top", "bottom", "left", "right")
#: contact node states (docs/design.md §6.3, §7.1), and "solve" = find them from the static LCP
STATES = ("stick", "slip+", "slip-", "separated", "grazing")
SOLVE = "solve"
INTERFACE_KINDS = ("bonded", "frictional")
#: what ``interface=`` of :meth:`Scene.with_friction` and :meth:`Scene.with_states` calls the rigid base
BASE = "base"

#: a scene table → a checked Scene (:func:`meicp.io.scene.scene_from_dict`), set by
#: :func:`use_parser`
_parse = None


def use_parser(parse) -> None:
    """Make ``parse(table, source=...)`` the parser the ``Scene.with_*`` methods read their
    changed table back with (:mod:`meicp.io.scene` calls it when it is imported)."""
    global _parse
    _parse = parse


class _Unchanged:
    """The default of :meth:`Scene.with_load`'s keywords: leave that field as it is."""

    def __repr__(self) -> str:
        return "unchanged"


UNCHANGED = _Unchanged()


class FrozenOptions(Mapping):
    """A read-only, picklable mapping (the ``[petsc]`` table): scenes can be sent between
    ranks with mpi4py and hashed like the other frozen fields."""

    __slots__ = ("_data",)

    def __init__(self, data=()):
        object.__setattr__(self, "_data", dict(data))

    def __getitem__(self, key):
        return self._data[key]

    def __iter__(self):
        return iter(self._data)

    def __len__(self) -> int:
        return len(self._data)

    def __setattr__(self, name, value):
        raise AttributeError("FrozenOptions is read-only")

    def __reduce__(self):
        return (FrozenOptions, (self._data,))

    def __hash__(self) -> int:
        return hash(tuple(sorted(self._data.items())))

    def __eq__(self, other) -> bool:
        return isinstance(other, Mapping) and dict(self) == dict(other)

    def __repr__(self) -> str:
        return f"FrozenOptions({self._data!r})"


@dataclass(frozen=True)
class Lattice:
    """The ``[lattice]`` table: columns, spacing, reference shear, default k_AB rule."""

    nx: int
    spacing: float = 1.0
    shear: float = 0.0
    interface_stiffness: str | float = "mean"

    def pair_stiffness(self, k_a: float, k_b: float) -> float:
        """The default stiffness of a bond joining materials of stiffness ``k_a`` and ``k_b``."""
        if self.interface_stiffness == "mean":
            return 0.5 * (k_a + k_b)
        return float(self.interface_stiffness)


@dataclass(frozen=True)
class Layer:
    """One ``[[layers]]`` entry: a band of ``rows`` node rows of one material."""

    name: str
    rows: int
    stiffness: float
    density: float
    viscosity: float | None = None


@dataclass(frozen=True)
class Embedded:
    """One ``[[embedded]]`` entry: a rectangle of another material inside layer ``host``.

    Rows ``row .. row+rows-1`` counted from the host's bottom row, columns
    ``column .. column+columns-1``.  ``stiffness`` is the bond stiffness inside the band,
    ``interface_stiffness`` (resolved) the stiffness of bonds between band and host.
    ``viscosity``: the dashpot of the bonds inside the band (None: none); a bond between band
    and host gets the mean of the two viscosities.
    """

    name: str
    host: str
    stiffness: float
    density: float
    row: int = 0
    rows: int = 1
    column: int = 0
    columns: int = 0
    interface_stiffness: float = 0.0
    viscosity: float | None = None


@dataclass(frozen=True)
class Boundary:
    """``[boundary]``: per side ``free``, ``fixed``, ``fixed_x``, ``fixed_y``; bottom may be ``contact``."""

    top: str = "free"
    bottom: str = "free"
    left: str = "free"
    right: str = "free"

    def fixed_components(self, side: str) -> tuple[bool, bool]:
        """Whether the (x, y) displacement of the nodes of ``side`` is prescribed (Dirichlet)."""
        kind = getattr(self, side)
        return {"fixed": (True, True), "fixed_x": (True, False),
                "fixed_y": (False, True)}.get(kind, (False, False))


@dataclass(frozen=True)
class Interface:
    """The interface between layer ``below`` (index ``index``) and layer ``index + 1``.

    ``kind`` is ``bonded`` (bonds with ``stiffness`` cross it) or ``frictional`` (no bonds;
    the top row of the lower layer and the bottom row of the upper layer are in Coulomb
    contact with coefficient ``friction``, node states ``states``, docs/design.md §6.1 (b)).
    ``viscosity``: bonded only, the dashpot of the bonds crossing it (None: the mean of the
    two layers'). ``declared`` tells whether the scene file has an entry for it.
    """

    below: str
    index: int
    kind: str = "bonded"
    stiffness: float | None = None
    friction: float | None = None
    states: str | tuple[str, ...] | None = None
    viscosity: float | None = None
    declared: bool = False

    @property
    def bonded(self) -> bool:
        return self.kind == "bonded"


@dataclass(frozen=True)
class Contact:
    """``[contact]``: the rigid rough base under the bottom row."""

    friction: float
    states: str | tuple[str, ...] = SOLVE


@dataclass(frozen=True)
class Load:
    """``[load]``: prescribed top-row displacement, prescribed x displacement of the left and
    right columns (``side_displacement``, lateral shortening) and gravity; used by
    ``states = "solve"`` (the static equilibrium, :mod:`meicp.contact.static`)."""

    top_displacement: tuple[float, float] | None = None
    gravity: float = 0.0
    side_displacement: tuple[float, float] | None = None


@dataclass(frozen=True)
class Damping:
    """``[damping]``: mass-proportional damping, ``C += mass · M`` (the bonds' dashpots are
    the layers' and bands' ``viscosity``; docs/damping.md)."""

    mass: float = 0.0


@dataclass(frozen=True)
class Solver:
    """``[solver]``: method name and the common controls (``None`` = the solver's default)."""

    method: str = "auto"
    all_solutions: bool = False
    lam_min: float | None = None
    nev: int | None = None
    tol: float | None = None
    max_iterations: int | None = None
    flutter: bool = True


@dataclass(frozen=True)
class Scene:
    """A whole scene file.  ``interfaces`` has one entry per adjacent pair of layers."""

    lattice: Lattice
    layers: tuple[Layer, ...]
    boundary: Boundary = field(default_factory=Boundary)
    interfaces: tuple[Interface, ...] = ()
    embedded: tuple[Embedded, ...] = ()
    contact: Contact | None = None
    load: Load | None = None
    damping: Damping | None = None
    solver: Solver = field(default_factory=Solver)
    petsc: Mapping[str, Any] = field(default_factory=FrozenOptions)
    title: str = ""
    source: str | None = None

    @property
    def nx(self) -> int:
        return self.lattice.nx

    @property
    def ny(self) -> int:
        """Node rows, all layers together."""
        return sum(layer.rows for layer in self.layers)

    @property
    def n_nodes(self) -> int:
        return self.nx * self.ny

    @property
    def n_dofs(self) -> int:
        return 2 * self.n_nodes

    def layer_index(self, name: str) -> int:
        for k, layer in enumerate(self.layers):
            if layer.name == name:
                return k
        raise KeyError(name)

    @property
    def damped(self) -> bool:
        """Whether the scene has damping: a viscosity > 0 somewhere or ``[damping] mass`` > 0
        (every one 0 or absent: exactly the undamped model)."""
        etas = [m.viscosity for m in self.layers + self.embedded] + [i.viscosity for i in self.interfaces]
        return any(eta for eta in etas if eta is not None) or bool(self.damping and self.damping.mass)

    def frictional_interfaces(self) -> tuple[Interface, ...]:
        return tuple(itf for itf in self.interfaces if itf.kind == "frictional")

    def __repr__(self) -> str:
        name = self.title or self.source or "scene"
        contacts = ([f"base μ={self.contact.friction:g}"] if self.contact else []) + \
            [f"interface {i.below!r} μ={i.friction:g}" for i in self.frictional_interfaces()]
        return (f"Scene({name!r}: {self.nx}x{self.ny} nodes, {len(self.layers)} layer(s)"
                + "".join(f", {c}" for c in contacts) + ")")

    # ---------------------------------------------------------------- as a table, and changed

    def to_dict(self) -> dict:
        """The scene as the table a scene file holds (TOML keys, plain lists and dicts):
        :func:`meicp.io.scene.scene_from_dict` reads it back to an equal scene (``source``
        aside).  Values resolved at load time are written as resolved (an embedded band's
        ``columns``), interfaces not declared are left out (they are bonded by the lattice's
        rule again)."""
        table = {"title": self.title} if self.title else {}
        table["lattice"] = _table(self.lattice)
        table["layers"] = [_table(layer) for layer in self.layers]
        if self.embedded:
            table["embedded"] = [_table(e) for e in self.embedded]
        table["boundary"] = _table(self.boundary)
        declared = [itf for itf in self.interfaces if itf.declared]
        if declared:
            table["interfaces"] = [
                _table(itf, ("index", "declared") + (("friction", "states") if itf.bonded else ("stiffness",)))
                for itf in declared]
        if self.contact is not None:
            table["contact"] = _table(self.contact)
        if self.load is not None:
            table["load"] = _table(self.load)
        if self.damping is not None:
            table["damping"] = _table(self.damping)
        table["solver"] = _table(self.solver)
        if len(self.petsc):
            table["petsc"] = dict(self.petsc)
        return table

    @checked_keywords()
    def with_friction(self, mu, *, interface: str | None = None) -> "Scene":
        """This scene with Coulomb friction ``mu`` (states and everything else unchanged).

        Parameters
        ----------
        mu : float
            The friction coefficient, ≥ 0 (checked as ``contact.friction`` is in a file).
        interface : str or None
            None: every frictional contact, the rigid base and every frictional
            interface; ``"base"``: the rigid base only; the name of a layer: the
            frictional interface above that layer only.

        Returns
        -------
        Scene
            A new scene, checked by the scene-file parser; its ``source`` says what changed.

        Raises
        ------
        ProblemError
            A bad ``mu`` (naming the key, e.g. ``contact.friction``), or an ``interface``
            that names no frictional contact of this scene.
        """
        return self._with_contact_value("with_friction", "friction", _plain_number(mu), repr(mu), interface,
                                        every=interface is None)

    @checked_keywords()
    def with_states(self, states, *, interface: str | None = None) -> "Scene":
        """This scene with the contact states ``states`` (friction and everything else
        unchanged).

        Parameters
        ----------
        states : str or sequence of str
            ``"solve"`` (from the static equilibrium under ``[load]``), one state for every
            contact node (``stick``, ``slip+``, ``slip-``, ``separated``, ``grazing``), or
            one state per column, left to right (checked as in a file).
        interface : str or None
            None or ``"base"``: the rigid base; the name of a layer: the frictional
            interface above that layer.

        Returns
        -------
        Scene
            A new scene, checked by the scene-file parser; its ``source`` says what changed.

        Raises
        ------
        ProblemError
            A bad state (naming the key, e.g. ``contact.states[3]``), or an ``interface``
            that names no frictional contact of this scene.
        """
        value = states if isinstance(states, str) or not _iterable(states) else list(states)
        shown = repr(states) if isinstance(states, str) or not isinstance(value, list) else f"<{len(value)} states>"
        return self._with_contact_value("with_states", "states", value, shown, interface, every=False)

    @checked_keywords()
    def with_load(self, *, top_displacement=UNCHANGED, side_displacement=UNCHANGED, gravity=UNCHANGED) -> "Scene":
        """This scene with its ``[load]`` changed: the fields given, the others as they are
        (None removes a displacement).

        Parameters
        ----------
        top_displacement : pair of float or None
            Prescribed displacement ``(ux, uy)`` of the top row (needs a top boundary that
            is not free).
        side_displacement : pair of float or None
            Prescribed x displacement ``(left_ux, right_ux)`` of the side columns (lateral
            shortening; a nonzero one needs that side ``fixed`` or ``fixed_x``).
        gravity : float
            Body force ``−gravity·ρ·a³`` on every node, in y.

        Returns
        -------
        Scene
            A new scene, checked by the scene-file parser; its ``source`` says what changed.

        Raises
        ------
        ProblemError
            A bad value, naming the key (``load.top_displacement[1]``).
        """
        table = self.to_dict()
        load = table.setdefault("load", {})
        given = {"top_displacement": top_displacement, "side_displacement": side_displacement, "gravity": gravity}
        given = {k: v for k, v in given.items() if v is not UNCHANGED}
        for key, value in given.items():
            if value is None:
                load.pop(key, None)
            elif isinstance(value, str) or not _iterable(value):
                load[key] = _plain_number(value)
            else:
                load[key] = [_plain_number(v) for v in value]
        return self._rebuilt(table, "with_load(" + ", ".join(f"{k}={v!r}" for k, v in given.items()) + ")")

    def _with_contact_value(self, method: str, field: str, value, shown: str, interface, *,
                            every: bool) -> "Scene":
        """This scene with ``field`` set to ``value`` on the contact lines ``interface`` names
        (the rigid base when None, unless ``every``: all of them), read back by the parser."""
        table = self.to_dict()
        for key in self._contact_keys(method, BASE if interface is None and not every else interface, every=every):
            self._contact_table(table, key)[field] = value
        return self._rebuilt(table, f"{method}({shown}" + (f", interface={interface!r})" if interface else ")"))

    def _contact_keys(self, method: str, interface, *, every: bool) -> list[str]:
        """The contact lines ``interface`` names: ``"base"`` (the rigid base) or the name of
        the layer under a frictional interface; all of them when ``every``."""
        names = ([BASE] if self.contact is not None else []) + [i.below for i in self.frictional_interfaces()]
        listed = ", ".join(f"{n!r} (the rigid base)" if n == BASE and k == 0 and self.contact is not None
                           else f"{n!r} (the interface above layer {n!r})" for k, n in enumerate(names)) or "none"
        if every:
            if not names:
                raise ProblemError(f"{method}: the scene has no frictional contact (boundary.bottom is "
                                   f"{self.boundary.bottom!r} and no interface is frictional)")
            return names
        if not isinstance(interface, str):
            raise ProblemError(f"interface must be None, {BASE!r} or a layer's name, got {interface!r}")
        if interface == BASE and self.contact is not None and BASE in names[1:]:
            raise ProblemError(f"interface={BASE!r} is ambiguous: the layer under a frictional interface is "
                               f"named {BASE!r} too")
        if interface in names:
            return [interface]
        why = "names no frictional contact of this scene"
        if any(i.below == interface for i in self.interfaces):
            why = f"is bonded: the interface above layer {interface!r} has no friction"
        elif interface == BASE:
            why = f"is no contact: the scene has no rigid base (boundary.bottom is {self.boundary.bottom!r})"
        raise ProblemError(f"{method}: interface={interface!r} {why}; its frictional contacts: {listed}")

    @staticmethod
    def _contact_table(table: dict, key: str) -> dict:
        if key == BASE:
            return table["contact"]
        return next(t for t in table["interfaces"] if t["below"] == key)

    def _rebuilt(self, table: dict, change: str) -> "Scene":
        if _parse is None:  # pragma: no cover - meicp/__init__ imports meicp.io.scene
            raise RuntimeError("no scene parser: import meicp (meicp.io.scene hands it over)")
        return _parse(table, source=f"{self.source or self.title or 'scene'} + {change}")


def _iterable(value) -> bool:
    try:
        iter(value)
    except TypeError:
        return False
    return True


def _plain_number(value):
    """A NumPy scalar as the Python number TOML would give (the parser takes int and float
    only); anything else as it is, for the parser to judge."""
    if isinstance(value, numbers.Integral) and not isinstance(value, bool):
        return int(value)
    if isinstance(value, numbers.Real) and not isinstance(value, bool):
        return float(value)
    return value


def _plain(value):
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    return value


def _table(obj, skip=()) -> dict:
    """A scene dataclass as its table: fields named after their keys, None (no value) left out."""
    return {f.name: _plain(getattr(obj, f.name)) for f in dataclasses.fields(obj)
            if f.name not in skip and getattr(obj, f.name) is not None}
