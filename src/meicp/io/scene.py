"""Scene files: TOML (docs/design.md §10.1) parsed and checked into a :class:`~meicp.scene.Scene`.

A scene declares one layered lattice, its boundary conditions, its contacts and how to
solve it (the dataclasses are in :mod:`meicp.scene`; this module only parses and validates).  :func:`load_scene` reads a file, :func:`loads_scene` a string and
:func:`scene_from_dict` an already parsed table (read table by table in
:mod:`meicp.io.scene_tables`, each value checked in :mod:`meicp.io.scene_values`).  Every key is checked: an unknown key, a
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
    viscosity = 0.02              # optional, >= 0: a dashpot per bond (Kelvin–Voigt; none: 0)

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
    viscosity = 0.1               # optional, >= 0 (bonds to the host: the mean with the host's)

    [boundary]                    # each side: "free" (default), "fixed", "fixed_x", "fixed_y";
    top = "fixed"                 # bottom may also be "contact" (a rigid rough base, needs
    bottom = "contact"            # [contact]).  fixed_x / fixed_y fix one component only.
    left = "free"
    right = "free"

    [[interfaces]]                # optional, between layer `below` and the layer above it
    below = "A"                   # required: a layer that is not the top one
    kind = "bonded"               # "bonded" (default) | "frictional"
    stiffness = 3.0               # bonded only: k_AB (default: lattice rule)
    viscosity = 0.03              # bonded only, >= 0: η of its bonds (default: the layers' mean)
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

    [damping]                     # optional (docs/damping.md)
    mass = 0.0                    # >= 0: C += mass·M

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
at most ``MAX_STIFFNESS_CONTRAST`` (:mod:`meicp.io.scene_tables`).  Files are read within
bounds (:func:`read_scene_text`: a regular file, at most ``MAX_SCENE_BYTES``, UTF-8, nesting
at most ``MAX_NESTING`` deep); whether the scene fits the machine is checked where it is
used (:func:`meicp.lattice.size.check_size`).

What is resolved at load time (the interfaces not declared, default stiffnesses, the width
of an embedded band) is described in :mod:`meicp.scene`.
"""

from __future__ import annotations

import os
import re
import tomllib
from collections.abc import Mapping
from pathlib import Path

from .. import scene as scene_module
from ..core.errors import ProblemError
from ..core.validation import checked_keywords
from ..scene import Scene
from .problem_files import read_text
from .scene_tables import SceneParser


# --------------------------------------------------------------------------- loading

def as_scene(scene, name: str = "scene") -> Scene:
    """The Scene that ``scene`` gives: what every public function taking a scene accepts.

    - a :class:`Scene`: itself;
    - a ``Mapping``: a parsed scene table, checked by :func:`scene_from_dict`;
    - a ``str`` with a line break: TOML text, parsed by :func:`loads_scene` (a scene always
      spans several lines: TOML puts each key on its own line);
    - any other ``str`` or an ``os.PathLike``: the path of a scene file (:func:`load_scene`;
      a missing file is "no such file").

    Anything else is a ProblemError naming ``name`` and what it may be."""
    if isinstance(scene, Scene):
        return scene
    if isinstance(scene, Mapping):
        return scene_from_dict(scene)
    if isinstance(scene, str) and "\n" in scene:
        return loads_scene(scene, source="<TOML text>")
    if isinstance(scene, (str, os.PathLike)):
        return load_scene(scene)
    raise ProblemError(f"{name} must be a Scene, a scene file's path, a dict or TOML text, "
                       f"got {type(scene).__name__}")


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
    if not isinstance(path, (str, os.PathLike)):
        raise ProblemError(f"a scene file's path must be a str or os.PathLike, got {type(path).__name__}")
    path = Path(path)
    if not path.exists():
        hint = (" (TOML text is taken as such only when it spans several lines)"
                if any(c in str(path) for c in "=[") else "")
        raise ProblemError(f"cannot read scene file {str(path)!r}: no such file{hint}")
    data = read_text(path, MAX_SCENE_BYTES, what="scene", limit_name="meicp.io.scene.MAX_SCENE_BYTES")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ProblemError(f"{path}: not UTF-8 text (byte 0x{data[exc.start]:02x} at offset {exc.start} "
                           "is invalid): a scene file is TOML, which is UTF-8") from None


@checked_keywords()
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
    return SceneParser(source).parse(data)


# Scene.with_friction & co. read their changed table back with this very parser
scene_module.use_parser(scene_from_dict)
