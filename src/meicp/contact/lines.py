"""The contact lines of a scene, built once: which nodes touch, with which friction, in which
states (docs/design.md §7.1).

A :class:`ContactLine` is the rigid base (``name = "base"``) or one frictional interface (named
by its lower layer): its node pairs and its μ, read from the scene and the lattice, and the
state of each contact once known.  The static equilibrium and the MEiCP maps read the same
lines.  States are a :class:`ContactState` from the moment they enter (the scene, the static
equilibrium's result, a caller's override) to the output, where :func:`state_names` turns them
back into the scene's strings.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from enum import Enum

import numpy as np

from ..core.errors import ProblemError
from ..scene import SOLVE, STATES

#: the rigid base's line (frictional interfaces go by their lower layer's name)
BASE = "base"


class ContactState(str, Enum):
    """The state of one contact (docs/design.md §4): its value is the scene's string."""

    STICK = "stick"
    SLIP_PLUS = "slip+"
    SLIP_MINUS = "slip-"
    SEPARATED = "separated"
    GRAZING = "grazing"

    @property
    def slip_sign(self) -> int:
        """+1 for slip+, −1 for slip−, 0 otherwise."""
        return _SLIP_SIGN.get(self, 0)


assert tuple(s.value for s in ContactState) == STATES  # the scene's vocabulary, in its order
_SLIP_SIGN = {ContactState.SLIP_PLUS: 1, ContactState.SLIP_MINUS: -1}


@dataclass(frozen=True)
class ContactLine:
    """One contact line.  ``upper``: the node of each contact that carries its DOFs (the base's
    contact node, or the upper node whose DOFs become the relative displacement
    ``d = u_upper − u_lower``); ``lower``: the lower side's node (None for the base);
    ``friction``: μ; ``states``: one :class:`ContactState` per contact, left to right, or None
    while unresolved (the scene says ``"solve"``); ``key``: the scene key of its states, which
    messages name."""

    name: str
    upper: np.ndarray
    lower: np.ndarray | None
    friction: float
    states: tuple | None = None
    key: str = "states"

    @property
    def size(self) -> int:
        return int(self.upper.size)

    def in_states(self, states) -> "ContactLine":
        """This line with its states replaced (parsed: strings or :class:`ContactState`)."""
        return dataclasses.replace(self, states=parse_states(states, self.size, self.key))


def contact_lines(scene, model) -> tuple[ContactLine, ...]:
    """The scene's contact lines, the base first, then each frictional interface, with the
    scene's prescribed states (None where it says ``"solve"``).  Raises ProblemError for a
    state list of the wrong length or an unknown state."""
    lines = []
    if model.boundary.bottom == "contact":
        nodes = model.contact_nodes()
        key = "contact.states"
        lines.append(ContactLine(BASE, nodes, None, float(scene.contact.friction),
                                 _prescribed(scene.contact.states, nodes.size, key), key))
    for k, itf in enumerate(scene.interfaces):
        if itf.kind != "frictional":
            continue
        lower, upper = model.interface_node_pairs(itf.index)
        key = f"interfaces[{k}].states"
        lines.append(ContactLine(itf.below, upper, lower, float(itf.friction),
                                 _prescribed(itf.states, upper.size, key), key))
    return tuple(lines)


def with_states(lines, override: dict | None) -> tuple[ContactLine, ...]:
    """``lines`` with the states of ``override`` (line name → states, e.g. the static
    equilibrium's) put in; every line must then have its states (ProblemError naming the line
    whose states still need the static equilibrium)."""
    override = override or {}
    out = tuple(line.in_states(override[line.name]) if line.name in override else line for line in lines)
    for line in out:
        if line.states is None:
            raise ProblemError(f"{line.key} = \"solve\" needs the static equilibrium first")
    return out


def parse_states(states, count: int, key: str) -> tuple:
    """One :class:`ContactState` per contact from one state or a list (strings or states)."""
    if states == SOLVE or states is None:
        raise ProblemError(f"{key} = \"solve\" needs the static equilibrium first")
    if isinstance(states, str):
        states = (states,) * count
    states = tuple(states)
    if len(states) != count:
        raise ProblemError(f"{key} has {len(states)} states for {count} contact nodes")
    bad = [s for s in states if s not in STATES]
    if bad:
        raise ProblemError(f"{key}: unknown state {bad[0]!r} (expected one of {', '.join(STATES)})")
    return tuple(ContactState(s) for s in states)


def _prescribed(states, count: int, key: str) -> tuple | None:
    return None if states == SOLVE or states is None else parse_states(states, count, key)


def state_names(states) -> list[str]:
    """The scene's strings of ``states``: what results, files and messages show."""
    return [ContactState(s).value for s in states]
