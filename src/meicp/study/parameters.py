"""The parameters a study varies, by key, and the grids of values it varies them over.

:func:`scene_with` is the one place a key becomes a changed :class:`~meicp.scene.Scene`
(``dataclasses.replace`` of the frozen fields), checked by the scene file's own parser, so
that a value a scene file would refuse is refused here with the same words.  The keys:

==============================  ===========================================================
``friction`` (``mu``)           μ of the rough base and of every frictional interface
``contact.friction``            μ of the rough base only
``interfaces.NAME.friction``    μ of one frictional interface (NAME: its lower layer's name
                                or the interface's index from 0, bottom first)
``layers.NAME.stiffness``       a layer's bond stiffness k (NAME: its name or index)
``layers.NAME.density``         a layer's density ρ
``shear``                       the top row's prescribed x displacement (``[load]``
                                ``top_displacement[0]``)
``compression``                 the top row's prescribed downward displacement
                                (−``top_displacement[1]``)
``gravity``                     ``[load] gravity``
``lattice.shear``               the reference geometry's shear (x += shear·y)
==============================  ===========================================================

The load keys matter only where the scene solves its contact states (``states =
"solve"``); a scene without ``[load]`` starts from zero load.  A layer's new stiffness is
carried to the bonds joining it to its neighbours and to its embedded bands when those
follow the lattice's default rule (their stiffness equals the rule's for the old value);
a stiffness the scene gives explicitly is kept.

:func:`parse_values` reads a grid: ``"A:B:N"`` (N values from A to B, ends included) or a
comma-separated list.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..core.errors import ProblemError
from ..core.validation import as_real
from ..io.results_records import scene_to_toml
from ..io.scene import loads_scene
from ..scene import Scene

#: alternative spellings of a key
ALIASES = {"mu": "friction"}
#: the keys for ``meicp sweep --help``
PARAMETER_HELP = """\
  friction (mu)                μ of the rough base and of every frictional interface
  contact.friction             μ of the rough base only
  interfaces.NAME.friction     μ of one frictional interface (NAME: its lower layer, or an index)
  layers.NAME.stiffness        a layer's bond stiffness k (NAME: the layer's name, or its index from 0)
  layers.NAME.density          a layer's density ρ
  shear                        the top row's prescribed x displacement ([load] top_displacement[0])
  compression                  the top row's prescribed downward displacement (−top_displacement[1])
  gravity                      [load] gravity
  lattice.shear                the reference geometry's shear (x += shear·y)
(the load keys act where the scene solves its contact states: states = "solve")"""
#: the most values one sweep takes (a typo such as 0:1:1e9 is refused, not started)
MAX_VALUES = 100_000


def parameter_keys(scene: Scene) -> list[str]:
    """Every key :func:`scene_with` accepts for ``scene``, layers and interfaces by name."""
    keys = []
    frictional = scene.frictional_interfaces()
    if scene.contact is not None or frictional:
        keys.append("friction")
    if scene.contact is not None:
        keys.append("contact.friction")
    keys += [f"interfaces.{itf.below}.friction" for itf in frictional]
    for layer in scene.layers:
        keys += [f"layers.{layer.name}.stiffness", f"layers.{layer.name}.density"]
    keys += ["shear", "compression", "gravity", "lattice.shear"]
    return keys


def describe(scene: Scene, key: str) -> str:
    """What ``key`` changes in ``scene``, for titles and summaries (checks the key)."""
    key = _canonical(scene, key)
    if key == "friction":
        parts = (["the base"] if scene.contact is not None else []) + [
            f"interface {itf.below!r}" for itf in scene.frictional_interfaces()]
        return "friction coefficient μ of " + " and ".join(parts)
    head, _, rest = key.partition(".")
    if head == "layers":
        name, field = rest.rsplit(".", 1)
        return f"{'bond stiffness k' if field == 'stiffness' else 'density ρ'} of layer {name!r}"
    if head == "interfaces":
        return f"friction coefficient μ of interface {rest.rsplit('.', 1)[0]!r}"
    return {"contact.friction": "friction coefficient μ of the base",
            "shear": "top row's prescribed x displacement",
            "compression": "top row's prescribed downward displacement",
            "gravity": "gravity", "lattice.shear": "reference shear of the lattice"}[key]


def is_friction(key: str) -> bool:
    """Whether ``key`` (canonical) is a friction coefficient: its onsets are μ_c and μ_f."""
    return key == "friction" or key.endswith(".friction")


def scene_with(scene: Scene, key: str, value) -> Scene:
    """``scene`` with the parameter ``key`` set to ``value``, everything else unchanged.

    Parameters
    ----------
    scene : Scene
        The scene to change (not modified: scenes are frozen).
    key : str
        One of :func:`parameter_keys` (the module docstring says what each changes);
        ``layers.NAME`` and ``interfaces.NAME`` also take the index from 0, bottom first.
    value : float
        The new value, checked as the scene file's parser checks it.

    Returns
    -------
    Scene
        The changed scene.

    Raises
    ------
    ProblemError
        An unknown key (the message lists the valid ones), a key this scene has nothing
        for (a friction without a frictional contact), or a value the scene file would
        refuse.
    """
    key = _canonical(scene, key)
    value = as_real(value, key)
    head, _, rest = key.partition(".")
    if key == "friction":
        return scene.with_friction(value)
    if key == "contact.friction":
        return scene.with_friction(value, interface="base")
    if head == "interfaces":
        return scene.with_friction(value, interface=rest.rsplit(".", 1)[0])
    if key in ("shear", "compression", "gravity"):
        return _with_load(scene, key, value)
    if head == "layers":
        name, field = rest.rsplit(".", 1)
        new = _with_layer(scene, name, field, value)
    else:  # lattice.shear
        new = dataclasses.replace(scene, lattice=dataclasses.replace(scene.lattice, shear=value))
    _check(new, key, value)
    return new


def _canonical(scene: Scene, key) -> str:
    """``key`` as :func:`parameter_keys` spells it (aliases, layer and interface indices
    resolved), or a ProblemError listing the valid keys."""
    if not isinstance(key, str):
        raise ProblemError(f"the parameter key must be a string, got {key!r}")
    key = ALIASES.get(key.strip(), key.strip())
    head, _, rest = key.partition(".")
    if head in ("layers", "interfaces") and rest.count(".") >= 1:
        name, field = rest.rsplit(".", 1)
        names = ([layer.name for layer in scene.layers] if head == "layers"
                 else [itf.below for itf in scene.interfaces])
        if name not in names and name.isdigit() and int(name) < len(names):
            key = f"{head}.{names[int(name)]}.{field}"
    valid = parameter_keys(scene)
    if key in valid:
        return key
    why = ""
    if head == "interfaces" and any(key == f"interfaces.{i.below}.friction" for i in scene.interfaces if i.bonded):
        why = " (that interface is bonded: it has no friction)"
    elif key == "friction" or key == "contact.friction":
        why = " (the scene has no rough base" + ("" if key == "contact.friction" else " and no frictional interface") + ")"
    raise ProblemError(f"unknown parameter {key!r}{why}; this scene's parameters are: {', '.join(valid)}")


def _with_layer(scene: Scene, name: str, field: str, value: float) -> Scene:
    k = scene.layer_index(name)
    old = scene.layers[k]
    layer = dataclasses.replace(old, **{field: value})
    layers = scene.layers[:k] + (layer,) + scene.layers[k + 1:]
    if field != "stiffness":
        return dataclasses.replace(scene, layers=layers)
    pair = scene.lattice.pair_stiffness

    def follows(current, before, after):  # a stiffness the default rule gave keeps following it
        return after if current is not None and current == before else current

    interfaces = []
    for itf in scene.interfaces:
        if itf.bonded and k in (itf.index, itf.index + 1):
            lower, upper = scene.layers[itf.index], scene.layers[itf.index + 1]
            new_pair = pair(layers[itf.index].stiffness, layers[itf.index + 1].stiffness)
            itf = dataclasses.replace(itf, stiffness=follows(itf.stiffness, pair(lower.stiffness, upper.stiffness),
                                                             new_pair))
        interfaces.append(itf)
    embedded = tuple(dataclasses.replace(e, interface_stiffness=follows(
        e.interface_stiffness, pair(e.stiffness, old.stiffness), pair(e.stiffness, value)))
        if e.host == name else e for e in scene.embedded)
    return dataclasses.replace(scene, layers=layers, interfaces=tuple(interfaces), embedded=embedded)


def _with_load(scene: Scene, key: str, value: float) -> Scene:
    """The top row's x displacement (``shear``), minus its y displacement (``compression``)
    or ``gravity``, by :meth:`Scene.with_load`."""
    if key == "gravity":
        return scene.with_load(gravity=value)
    ux, uy = (scene.load.top_displacement if scene.load else None) or (0.0, 0.0)
    return scene.with_load(top_displacement=(value, uy) if key == "shear" else (ux, -value))


def _check(scene: Scene, key: str, value: float) -> None:
    """The scene file's parser on the changed scene: every rule a file obeys (ranges, the
    stiffness contrast, a load that needs a fixed top row) holds for it too."""
    loads_scene(scene_to_toml(scene), source=f"{key} = {value:g}")


def parse_values(spec) -> np.ndarray:
    """The values of a sweep: ``"A:B:N"`` (``numpy.linspace(A, B, N)``), a comma-separated
    list ``"0.5,1,2"``, or a sequence of numbers.  Finite, without repeats, at most
    :data:`MAX_VALUES`; ProblemError naming what is wrong."""
    if isinstance(spec, str):
        text = spec.strip()
        if text.count(":") == 2:
            a, b, n = (part.strip() for part in text.split(":"))
            start, stop = _number(a, "the range's start A"), _number(b, "the range's end B")
            try:
                count = int(n)
            except ValueError:
                raise ProblemError(f"the range's count N in A:B:N must be an integer, got {n!r}") from None
            if not 1 <= count <= MAX_VALUES:
                raise ProblemError(f"the range's count N in A:B:N must lie in [1, {MAX_VALUES:,}], got {count}")
            if count > 1 and start == stop:
                raise ProblemError(f"the range {text!r} repeats one value {count} times: give A ≠ B or N = 1")
            values = np.linspace(start, stop, count)
        elif ":" in text:
            raise ProblemError(f"a range is A:B:N (start, end, number of values), got {spec!r}")
        else:
            parts = [p.strip() for p in text.split(",")]
            if not text or any(not p for p in parts):
                raise ProblemError(f"a list of values is comma-separated numbers (or a range A:B:N), got {spec!r}")
            values = np.array([_number(p, "a value of the list") for p in parts])
    else:
        try:
            items = list(np.ravel(np.asarray(spec, dtype=object)))
        except TypeError:
            raise ProblemError(f"values must be 'A:B:N', a comma-separated list or numbers, got {spec!r}") from None
        values = np.array([as_real(v, "each value") for v in items], dtype=float)
    if values.size == 0:
        raise ProblemError("values: none given")
    if values.size > MAX_VALUES:
        raise ProblemError(f"values: {values.size:,} given, at most {MAX_VALUES:,} per sweep")
    if np.unique(values).size != values.size:
        raise ProblemError(f"values: repeated value(s) {sorted({v for v in values.tolist() if (values == v).sum() > 1})}")
    return values


def _number(text: str, what: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ProblemError(f"{what} must be a number, got {text!r}") from None
    return as_real(value, what)
