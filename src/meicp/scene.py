"""The scene: one layered lattice, its boundary conditions, contacts, load and solver
settings, as frozen dataclasses (docs/design.md §10).  The vocabulary every package shares — the
lattice is built from it, the contact analysis reads its states, the results record it —
so it depends on nothing but :mod:`meicp.core`.

Reading and checking a scene file is :mod:`meicp.io.scene`'s job (it documents the TOML
keys, which are named like the fields below); a scene built in code is checked by the same
parser through :func:`meicp.io.scene.scene_from_dict`.

Resolved when a scene is loaded, so that later code has one place to look:
``Scene.interfaces`` has one entry per pair of adjacent layers, bottom to top (those not
declared are bonded with the lattice's default rule), and every bonded interface or
embedded band carries its numeric ``stiffness``; a frictional interface has ``stiffness =
None`` and no bonds (its contact law is added by :mod:`meicp.contact`).
``Embedded.columns`` is resolved to a number.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

#: boundary condition names for any side; "contact" is allowed on the bottom only
BOUNDARY_KINDS = ("free", "fixed", "fixed_x", "fixed_y")
CONTACT = "contact"
SIDES = ("top", "bottom", "left", "right")
#: contact node states (docs/design.md §6.3, §7.1), and "solve" = find them from the static LCP
STATES = ("stick", "slip+", "slip-", "separated", "grazing")
SOLVE = "solve"
INTERFACE_KINDS = ("bonded", "frictional")


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


@dataclass(frozen=True)
class Embedded:
    """One ``[[embedded]]`` entry: a rectangle of another material inside layer ``host``.

    Rows ``row .. row+rows-1`` counted from the host's bottom row, columns
    ``column .. column+columns-1``.  ``stiffness`` is the bond stiffness inside the band,
    ``interface_stiffness`` (resolved) the stiffness of bonds between band and host.
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
    ``declared`` tells whether the scene file has an entry for it.
    """

    below: str
    index: int
    kind: str = "bonded"
    stiffness: float | None = None
    friction: float | None = None
    states: str | tuple[str, ...] | None = None
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

    def frictional_interfaces(self) -> tuple[Interface, ...]:
        return tuple(itf for itf in self.interfaces if itf.kind == "frictional")
