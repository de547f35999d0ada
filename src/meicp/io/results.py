"""Everything ``meicp solve`` leaves on disk: :func:`write_results`.

In the output directory::

    results.h5      the scene, versions, contact states and forces, modes, verdict (below)
    lattice.h5      the lattice (:func:`~meicp.io.lattice_output.write_lattice`) with node
    lattice.xdmf    fields ``mode_0``, ``mode_1``... (each scaled as in the PNG),
                    ``contact_state`` (codes below), the node indices ``i`` and ``j``, and,
                    when the static equilibrium was solved, ``static_u`` (its displacement)
                    and the contact reactions ``r_n``, ``r_t`` (NaN off the contact nodes):
                    open the .xdmf in ParaView, Warp By Vector with ``mode_k`` (scale 1 = the
                    PNG's picture)
    mode.png        the fastest mode on the deformed lattice (or the "stable" lattice)
    flutter_mode.png  the fastest flutter mode (real part of its shape; only when there is one)
    contacts.png    states (and forces) along each contact line (only when there is one)

``results.h5`` layout (strings are UTF-8; ``None`` is never stored: absent means unknown):

=================================  ==========================================================
``/`` attributes                   ``format = "meicp-results"``, ``format_version``,
                                   ``meicp_version``, ``title``, ``source``, ``created``,
                                   ``status``, ``success``, ``message``, ``iterations``,
                                   ``residual``, ``analysis`` (instability | modal: a scene
                                   without contact), ``verdict`` (stable | unstable |
                                   undecided | no contact), ``stable`` (1 | 0 | -1 for
                                   undecided), ``evidence``, ``n_modes``, ``ranks``,
                                   ``units_convention``, ``divergence`` and ``flutter``
                                   (1 | 0 | -1 for undecided), ``flutter_evidence``,
                                   ``n_flutter_modes``, ``divergence_tests`` (the test behind
                                   each MEiCP's divergence verdict: enumerate,
                                   rayleigh-inertia, rayleigh-window+condensed-…,
                                   certified-mode, none) and ``divergence_proofs`` (JSON:
                                   test, statement, sigma_window, supports visited)
``/scene``                         the scene as TOML text (the file's own text when known,
                                   else regenerated from the parsed scene)
``/scene_summary``                 attributes nx, ny, n_nodes, n_dofs, spacing, shear,
                                   boundary_<side>, base_friction; ``layers/{name, rows,
                                   stiffness, density}``, ``interfaces/{below, kind,
                                   stiffness, friction}`` (NaN where not applicable)
``/versions``                      attributes: python, numpy, scipy, petsc, slepc, mpi, ...
``/sizes``, ``/timings``           attributes copied from the result (timings in seconds)
``/contact``                       attribute ``codes`` (the per-node code legend)
``/contact/base``                  ``states`` (nx,) S, ``code`` (nx,) i1, ``nodes`` (nx,) i8;
                                   attribute ``friction``
``/contact/interfaces/<below>``    ``states``, ``code``, ``lower_nodes``, ``upper_nodes``;
                                   attributes ``friction``, ``below``
``/static`` (when solved)          ``r_n``, ``r_t``, ``gap``, ``slip``, ``held`` (base, as the
                                   static result holds them), ``interfaces/<below>/r_n``...,
                                   ``u`` (n_dofs,); attributes status, success, message,
                                   equilibrium_residual, guarantees, notes...
``/modes``                         ``sigma`` (m,), ``growth_rate`` (m,), ``frequency`` (m,)
                                   (ω = √−σ of a vibration mode), ``residual`` (m,),
                                   ``display_scale`` (m,), ``x`` (m, n_dofs) natural numbering
``/modes/mode_<k>``                ``support`` (base columns, i8), ``interface_support/<below>``;
                                   attributes sigma, growth_rate, residual, display_scale
``/flutter_modes``                 (docs/flutter.md) ``sigma_real``, ``sigma_imag``,
                                   ``growth_rate`` (Re sqrt(sigma)), ``frequency``
                                   (|Im sqrt(sigma)|), ``residual``, ``radius`` (f,),
                                   ``x_real``, ``x_imag`` (f, n_dofs), ``branch`` (f,) S;
                                   ``mode_<k>/support``, ``mode_<k>/interface_support/<below>``
``/certificates``                  ``mode_residual`` (m,); attributes ``result_residual``,
                                   ``max_mode_residual``, ``eicp_method``, ``eicp_status``,
                                   ``eicp_message``, ``eicp_coverage`` (JSON)
``/critical_friction`` (when       attributes ``value`` (inf: none found), ``found``, and
computed)                          ``lower``, ``upper``, ``exact``, ``evidence`` as far as
                                   known (:func:`critical_friction_record`)
``/overrides``                     attributes: the solver settings given on the command
                                   line (``method``, ``target``, ``nev``), over the scene's
=================================  ==========================================================

Every dataset carries CF-style ``long_name`` and ``units`` attributes; the model is
dimensionless (``units = "1"``, the numbers in the scene's consistent system: see
:mod:`meicp.io.lattice_output`), and the code datasets carry their legend as
``flag_values`` / ``flag_meanings`` / ``legend``.  Later sections are added as groups
beside ``/modes``; readers ignore what they do not know.

Contact state codes (``/contact/*/code`` and the XDMF field ``contact_state``): 0 not a
contact node, 1 stick, 2 slip+, 3 slip-, 4 separated, 5 grazing, -1 contact node whose state
is unknown.  For a frictional interface both nodes of a column carry its code.

Nothing half-written is ever left: the result is checked first (mode lengths, states, ...),
then every file is written into a hidden staging directory inside the output directory and
moved into place only when all of them are complete; on any error the staging directory is
removed (and the output directory too, when this call created it).  Rank 0 writes; the
other ranks of ``comm`` wait for it and return the same paths, or raise the same error.
"""

from __future__ import annotations

import dataclasses
import datetime
import json
import math
import os
import platform
import shutil
from pathlib import Path

import numpy as np
import scipy

from .. import __version__
from ..core.cleanup import on_interrupt, uninterrupted
from ..core.errors import MeicpError, ProblemError
from ..info import collect
from ..lattice.assembly import as_model
from ..petsc.comm import mpi_comm
from ..petsc.stages import stage as log_stage
from ..plotting import lattice as plotting
from ..scene import STATES, Scene
from .lattice_output import UNITS_CONVENTION, coded, write_lattice

FORMAT = "meicp-results"
FORMAT_VERSION = 1
#: contact state → code (0 = not a contact node, -1 = unknown state)
STATE_CODES = {s: k for k, s in enumerate(STATES, start=1)}
CODE_LEGEND = "0 not a contact node, " + ", ".join(f"{k} {s}" for s, k in STATE_CODES.items()) \
    + ", -1 unknown"
#: CF attributes of a contact state code (``/contact/*/code``, the XDMF field ``contact_state``)
STATE_FLAGS = coded(("not_a_contact_node",) + STATES + ("unknown",), [0, *STATE_CODES.values(), -1],
                    long_name="contact state code")
#: CF-style attributes of results.h5's datasets, by (top group, dataset name)
DESCRIPTIONS = {
    ("modes", "sigma"): {"long_name": "sigma = lambda^2 of each mode: a divergence mode grows as exp(sqrt(sigma) t), "
                                      "a vibration mode has sigma = -omega^2 (1/time^2)"},
    ("modes", "growth_rate"): {"long_name": "growth rate lambda = sqrt(sigma), 0 when sigma < 0 (1/time)"},
    ("modes", "frequency"): {"long_name": "angular frequency omega = sqrt(-sigma), 0 when sigma >= 0 (1/time)"},
    ("modes", "residual"): {"long_name": "certificate residual of each mode, relative to the pencil's scale"},
    ("modes", "display_scale"): {"long_name": "factor that scales x to the picture of mode.png"},
    ("modes", "x"): {"long_name": "mode shape in natural DOF numbering (2n: x, 2n+1: y of node n = j*nx + i), "
                                  "unit 2-norm"},
    ("modes", "support"): {"long_name": "columns of the base contacts whose slip is active"},
    ("modes", "interface_support"): {"long_name": "columns of the interface's contacts whose slip is active"},
    ("flutter_modes", "sigma_real"): {"long_name": "real part of sigma = lambda^2 of each flutter mode (1/time^2)"},
    ("flutter_modes", "sigma_imag"): {"long_name": "imaginary part of sigma (> 0: one mode per conjugate pair) "
                                                   "(1/time^2)"},
    ("flutter_modes", "growth_rate"): {"long_name": "growth rate Re sqrt(sigma) > 0 of each flutter mode (1/time)"},
    ("flutter_modes", "frequency"): {"long_name": "angular frequency |Im sqrt(sigma)| of each flutter mode "
                                                  "(1/time)"},
    ("flutter_modes", "residual"): {"long_name": "backward error |Ax - sigma Bx| / ((|A|_1 + |sigma| |B|_1) |x|) "
                                                 "of each flutter mode"},
    ("flutter_modes", "radius"): {"long_name": "how far rounding may move sigma; |Im sigma| exceeds it (1/time^2)"},
    ("flutter_modes", "x_real"): {"long_name": "real part of the complex flutter mode shape, natural DOF "
                                               "numbering, unit 2-norm"},
    ("flutter_modes", "x_imag"): {"long_name": "imaginary part of the complex flutter mode shape (a quarter "
                                               "period after the real part)"},
    ("flutter_modes", "branch"): {"long_name": "grazing branch of each flutter mode (empty: no grazing contact)"},
    ("flutter_modes", "support"): {"long_name": "columns of the base contacts sliding in this flutter mode"},
    ("flutter_modes", "interface_support"): {"long_name": "columns of the interface's contacts sliding in "
                                                          "this flutter mode"},
    ("contact", "states"): {"long_name": "contact state of each column, left to right"},
    ("contact", "code"): STATE_FLAGS,
    ("contact", "nodes"): {"long_name": "node number j*nx + i of each base contact"},
    ("contact", "lower_nodes"): {"long_name": "node number of the lower side of each interface contact"},
    ("contact", "upper_nodes"): {"long_name": "node number of the upper side of each interface contact"},
    ("static", "r_n"): {"long_name": "normal contact reaction r_n >= 0 (force)"},
    ("static", "r_t"): {"long_name": "tangential contact reaction r_t, |r_t| <= mu r_n (force)"},
    ("static", "gap"): {"long_name": "normal gap g >= 0 (length)"},
    ("static", "slip"): {"long_name": "tangential slip (length)"},
    ("static", "held"): {"long_name": "1 where the boundary holds the contact node"},
    ("static", "u"): {"long_name": "static displacement in natural DOF numbering (length)"},
    ("certificates", "mode_residual"): {"long_name": "certificate residual of each mode"},
    ("", "scene"): {"long_name": "scene file (TOML)"},
    ("scene_summary", "name"): {"long_name": "name"},
    ("scene_summary", "rows"): {"long_name": "node rows of each layer"},
    ("scene_summary", "stiffness"): {"long_name": "bond stiffness (force per length)"},
    ("scene_summary", "density"): {"long_name": "density (mass per length^3)"},
    ("scene_summary", "below"): {"long_name": "the layer below each interface"},
    ("scene_summary", "kind"): {"long_name": "interface kind (bonded | frictional)"},
    ("scene_summary", "friction"): {"long_name": "Coulomb friction coefficient mu (NaN: bonded)"},
}
#: CF-style attributes of the XDMF fields results.h5's writer adds to lattice.h5
FIELD_DESCRIPTIONS = {
    "contact_state": STATE_FLAGS,
    "static_u": {"long_name": "static displacement (length)"},
    "r_n": {"long_name": "normal contact reaction r_n >= 0 of the static equilibrium (force), NaN off contacts"},
    "r_t": {"long_name": "tangential contact reaction r_t of the static equilibrium (force), NaN off contacts"},
}
#: file names inside the output directory (keys of the returned dict)
FILES = {"results": "results.h5", "lattice": "lattice.h5", "xdmf": "lattice.xdmf",
         "mode_png": "mode.png", "flutter_png": "flutter_mode.png", "contacts_png": "contacts.png"}
STATIC_FIELDS = ("r_n", "r_t", "gap", "slip")


# --------------------------------------------------------------------------- helpers

def versions() -> dict:
    """Versions worth recording next to a result (:func:`meicp.info.collect` when PETSc is
    importable, else the pure-Python part).  Values are strings or numbers."""
    out = {"meicp": __version__, "python": platform.python_version(), "numpy": np.__version__,
           "scipy": scipy.__version__}
    try:
        out.update(collect())
    except Exception as exc:  # noqa: BLE001 - versions are informative, never fatal
        out["petsc"] = f"unavailable ({type(exc).__name__}: {exc})"
    try:
        import matplotlib

        out["matplotlib"] = matplotlib.__version__
    except ImportError:  # pragma: no cover
        pass
    return {k: (v if isinstance(v, (int, float, str, bool)) else str(v)) for k, v in out.items()}


def critical_friction_record(mu, evidence: str | None = None) -> dict:
    """The critical friction as results.h5 and ``meicp solve --json`` store it: ``value``
    (inf when no μ up to the search's bound gives a mode), ``found``, and ``lower``,
    ``upper``, ``exact``, ``evidence`` as far as the number carries them (a float subclass
    with a certified bracket); ``evidence`` stands in when it carries none.  Unknown: None."""
    value = float(mu)
    record = {"value": value, "found": math.isfinite(value)}
    for name in ("lower", "upper", "exact", "evidence"):
        item = getattr(mu, name, None)
        record[name] = float(item) if isinstance(item, (float, np.floating)) else item
    if record["evidence"] is None:
        record["evidence"] = evidence
    return record


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {v!r} as TOML")


def _fields(obj, skip=()) -> list:
    """(key, value) of a scene dataclass, in declaration order: scene.py names every field
    after its TOML key, so new keys are written without changes here."""
    return [(f.name, getattr(obj, f.name)) for f in dataclasses.fields(obj) if f.name not in skip]


def scene_to_toml(scene: Scene) -> str:
    """A TOML text that :func:`~meicp.io.scene.loads_scene` reads back to an equal scene
    (``source`` aside): the record of a scene built in code, with no file behind it."""
    lines = []

    def table(header, items):
        lines.append("")
        lines.append(header)
        for key, value in items:
            if value is not None:
                lines.append(f"{key} = {_toml_value(value)}")

    if scene.title:
        lines.append(f"title = {_toml_value(scene.title)}")
    table("[lattice]", _fields(scene.lattice))
    for layer in scene.layers:
        table("[[layers]]", _fields(layer))
    for e in scene.embedded:
        table("[[embedded]]", _fields(e))
    table("[boundary]", _fields(scene.boundary))
    for itf in scene.interfaces:
        if not itf.declared:
            continue
        if itf.bonded:
            table("[[interfaces]]", [("below", itf.below), ("kind", itf.kind), ("stiffness", itf.stiffness)])
        else:
            table("[[interfaces]]", [("below", itf.below), ("kind", itf.kind),
                                     ("friction", itf.friction), ("states", itf.states)])
    if scene.contact is not None:
        table("[contact]", _fields(scene.contact))
    if scene.load is not None:
        table("[load]", _fields(scene.load))
    table("[solver]", _fields(scene.solver))
    if len(scene.petsc):
        lines.append("")
        lines.append("[petsc]")
        for key, value in scene.petsc.items():
            lines.append(f"{json.dumps(key)} = {_toml_value(value)}")
    return "\n".join(lines).lstrip("\n") + "\n"


def _scene_text(scene: Scene, scene_text):
    if scene_text:
        return scene_text
    if scene.source and os.path.isfile(scene.source):
        try:
            text = Path(scene.source).read_text(encoding="utf-8")
            if text:
                return text
        except OSError:
            pass
    return scene_to_toml(scene)


def _contact_lines(scene: Scene) -> list:
    """``(key, label, friction, upper nodes, lower nodes or None)`` per contact line: the base
    first, then the frictional interfaces bottom to top."""
    model_rows = np.cumsum([0] + [layer.rows for layer in scene.layers])
    nx = scene.nx
    out = []
    if scene.boundary.bottom == "contact":
        out.append(("base", "rigid base", float(scene.contact.friction), np.arange(nx), None))
    for itf in scene.frictional_interfaces():
        r = int(model_rows[itf.index + 1])
        out.append((itf.below, f"interface above {itf.below!r}", float(itf.friction),
                    np.arange(r * nx, (r + 1) * nx), np.arange((r - 1) * nx, r * nx)))
    return out


def _check_states(name: str, states, nx: int) -> list:
    states = list(states or [])
    if states and len(states) != nx:
        raise ProblemError(f"{name}: {len(states)} contact states for nx = {nx} columns")
    for k, s in enumerate(states):
        if s not in STATE_CODES:
            raise ProblemError(f"{name}[{k}] = {s!r} is not a contact state "
                               f"({', '.join(STATE_CODES)})")
    return states


def _columns(name: str, value, nx: int) -> np.ndarray:
    try:
        arr = np.asarray(value if value is not None else [], dtype=np.int64).ravel()
    except (TypeError, ValueError):
        raise ProblemError(f"{name} must be integer column indices, got {value!r}") from None
    if arr.size and (arr.min() < 0 or arr.max() >= nx):
        raise ProblemError(f"{name} has column {int(arr.max() if arr.max() >= nx else arr.min())} "
                           f"outside 0..{nx - 1}")
    return arr


def _prepare(scene: Scene, result) -> dict:
    """Check the result against the scene and collect every array to write.  Raises
    :class:`ProblemError` before anything touches the disk."""
    if not isinstance(scene, Scene):
        raise ProblemError(f"write_results needs a Scene, got {type(scene).__name__}")
    nx, n_dofs = scene.nx, scene.n_dofs
    lines = _contact_lines(scene)
    keys = [key for key, *_ in lines]
    base_states = _check_states("result.states", getattr(result, "states", None), nx)
    if base_states and "base" not in keys:
        raise ProblemError(f"result.states lists {len(base_states)} base contact states but the "
                           f"scene has no rigid base (boundary.bottom = {scene.boundary.bottom!r})")
    itf_states = dict(getattr(result, "interface_states", None) or {})
    for name in itf_states:
        if name not in keys or name == "base":
            raise ProblemError(f"result.interface_states[{name!r}]: the scene has no frictional "
                               f"interface above a layer {name!r}")
    states = {"base": base_states}
    for name, value in itf_states.items():
        states[name] = _check_states(f"result.interface_states[{name!r}]", value, nx)
    modes = []
    for k, m in enumerate(getattr(result, "modes", None) or []):
        x = np.asarray(m.x, dtype=float).ravel()
        if x.size != n_dofs:
            raise ProblemError(f"mode {k}: x has {x.size} values, the scene has {n_dofs} DOFs")
        if not np.all(np.isfinite(x)):
            raise ProblemError(f"mode {k}: x is not finite")
        sigma = float(m.sigma)
        if not math.isfinite(sigma):
            raise ProblemError(f"mode {k}: sigma = {sigma} is not finite")
        support = _columns(f"mode {k}: support", m.support, nx)
        if support.size and "base" not in keys:
            raise ProblemError(f"mode {k}: support lists base contact nodes but the scene has no "
                               f"rigid base (frictional interfaces go in interface_support)")
        isup = {}
        for name, sup in (getattr(m, "interface_support", None) or {}).items():
            if name not in keys or name == "base":
                raise ProblemError(f"mode {k}: interface_support[{name!r}]: no frictional "
                                   f"interface above a layer {name!r}")
            isup[name] = _columns(f"mode {k}: interface_support[{name!r}]", sup, nx)
        frequency = float(np.sqrt(max(-sigma, 0.0)))
        modes.append({"mode": m, "sigma": sigma, "growth_rate": float(m.growth_rate), "frequency": frequency, "x": x,
                      "support": support, "interface_support": isup,
                      "residual": float(getattr(m, "residual", float("nan")))})
    flutter_modes = []
    for k, m in enumerate(getattr(result, "flutter_modes", None) or []):
        x = np.asarray(m.x, dtype=complex).ravel()
        sigma = complex(m.sigma)
        if x.size != n_dofs or not np.all(np.isfinite(x)) or not np.isfinite(sigma):
            raise ProblemError(f"flutter mode {k}: x must have {n_dofs} finite values and sigma be finite")
        flutter_modes.append({"mode": m, "sigma": sigma, "x": x,
                              "support": _columns(f"flutter mode {k}: support", m.support, nx),
                              "interface_support": {name: _columns(f"flutter mode {k}: interface_support", sup, nx)
                                                    for name, sup in (m.interface_support or {}).items()}})
    static = getattr(result, "static", None)
    forces, iforces, static_u = {}, {}, None
    if static is not None:
        for name in STATIC_FIELDS + ("held",):
            value = getattr(static, name, None)
            if value is not None:
                forces[name] = _numeric(f"result.static.{name}", value)
            for itf, value in (getattr(static, f"interface_{name}", None) or {}).items():
                if value is not None:
                    iforces.setdefault(str(itf), {})[name] = _numeric(
                        f"result.static.interface_{name}[{itf!r}]", value)
        u = getattr(static, "u", None)
        if u is not None:
            static_u = _numeric("result.static.u", u).ravel()
            if static_u.size != n_dofs:
                raise ProblemError(f"result.static.u has {static_u.size} values, the scene has "
                                   f"{n_dofs} DOFs")
    # per-node contact state code, for the XDMF file
    code = np.zeros(scene.n_nodes)
    for key, _, _, upper, lower in lines:
        st = states.get(key) or []
        c = np.array([STATE_CODES[s] for s in st], dtype=float) if st else np.full(nx, -1.0)
        code[upper] = c
        if lower is not None:
            code[lower] = c
    # per-node contact reactions, for the XDMF file: both nodes of an interface column carry it
    node_forces = {}
    for key, _, _, upper, lower in lines:
        src = forces if key == "base" else iforces.get(key, {})
        for name in ("r_n", "r_t"):
            arr = src.get(name)
            if arr is not None and arr.ndim == 1 and arr.size == nx:
                field = node_forces.setdefault(name, np.full(scene.n_nodes, np.nan))
                field[upper] = arr
                if lower is not None:
                    field[lower] = arr
    return {"lines": lines, "states": states, "modes": modes, "flutter_modes": flutter_modes, "static": static, "forces": forces,
            "interface_forces": iforces, "static_u": static_u, "code": code, "node_forces": node_forces}


def _numeric(name: str, value) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ProblemError(f"{name} is not numeric") from None
    return arr


def _line_forces(prep: dict, nx: int) -> dict:
    """key of each contact line → {r_n, r_t, gap, slip} of length nx, as far as known: the
    base from ``static.r_n``..., each interface from ``static.interface_r_n[below]``...
    (arrays of another length are stored in results.h5 but not plotted)."""
    out = {}
    for key, *_ in prep["lines"]:
        src = prep["forces"] if key == "base" else prep["interface_forces"].get(key, {})
        out[key] = {name: arr for name, arr in src.items()
                    if name in STATIC_FIELDS and arr.ndim == 1 and arr.size == nx}
    return out


# --------------------------------------------------------------------------- HDF5

def _attr(value):
    if value is None:
        return None
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value)
    if isinstance(value, str):
        return value.replace("\x00", "").strip()  # MPI's version string ends in NULs
    return json.dumps(value, default=str)


def _set_attrs(obj, items) -> None:
    for k, v in items.items():
        v = _attr(v)
        if v is not None:
            obj.attrs[str(k)] = v


def _strings(values, width: int = 16) -> np.ndarray:
    return np.array([str(v).encode() for v in values], dtype=f"S{width}")


def _describe(f) -> None:
    """CF-style ``units`` and ``long_name`` (and code legends) on every dataset of results.h5."""
    def visit(name, obj):
        if not hasattr(obj, "shape"):
            return
        parts = name.split("/")
        leaf = "interface_support" if "interface_support" in parts else parts[-1]
        attrs = DESCRIPTIONS.get((parts[0] if len(parts) > 1 else "", leaf), {"long_name": leaf})
        for key, value in {"units": "1", **attrs}.items():
            obj.attrs[key] = value
    f.visititems(visit)


def _write_h5(h5py, path: Path, scene: Scene, result, prep: dict, text: str, vers: dict,
              scales: list, ranks: int, mu_c=None, overrides: dict | None = None) -> None:
    stable = getattr(result, "stable", None)
    analysis = getattr(result, "analysis", "instability")
    verdict = "no contact" if analysis == "modal" else {True: "stable", False: "unstable"}.get(stable, "undecided")
    modes = prep["modes"]
    with h5py.File(path, "w") as f:
        _set_attrs(f, {
            "format": FORMAT, "format_version": FORMAT_VERSION, "meicp_version": __version__,
            "title": scene.title, "source": scene.source or "",
            "created": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "status": getattr(result, "status", ""), "success": bool(getattr(result, "success", False)),
            "message": getattr(result, "message", ""), "iterations": getattr(result, "iterations", 0),
            "residual": getattr(result, "residual", float("nan")), "verdict": verdict,
            "stable": {True: 1, False: 0}.get(stable, -1), "evidence": getattr(result, "evidence", ""),
            "n_modes": len(modes), "ranks": ranks, "analysis": analysis, "units_convention": UNITS_CONVENTION,
            **{name: {True: 1, False: 0}.get(getattr(result, name, None), -1) for name in ("divergence", "flutter")},
            "flutter_evidence": getattr(result, "flutter_evidence", ""),
            "divergence_tests": ", ".join(p.get("test") or "none" for p in getattr(result, "proofs", [])),
            "divergence_proofs": json.dumps(result.to_dict().get("proofs", []) if hasattr(result, "to_dict") else []),
            "n_flutter_modes": len(prep["flutter_modes"])})
        f.create_dataset("scene", data=text, dtype=h5py.string_dtype("utf-8"))

        g = f.create_group("scene_summary")
        b = scene.boundary
        _set_attrs(g, {"nx": scene.nx, "ny": scene.ny, "n_nodes": scene.n_nodes,
                       "n_dofs": scene.n_dofs, "spacing": scene.lattice.spacing,
                       "shear": scene.lattice.shear, "title": scene.title,
                       **{f"boundary_{s}": getattr(b, s) for s in ("top", "bottom", "left", "right")},
                       "base_friction": scene.contact.friction if scene.contact else None,
                       "n_embedded": len(scene.embedded)})
        g.create_dataset("layers/name", data=_strings([l.name for l in scene.layers], 64))
        g.create_dataset("layers/rows", data=np.array([l.rows for l in scene.layers], dtype=np.int64))
        g.create_dataset("layers/stiffness", data=np.array([l.stiffness for l in scene.layers]))
        g.create_dataset("layers/density", data=np.array([l.density for l in scene.layers]))
        if scene.interfaces:
            nan = float("nan")
            g.create_dataset("interfaces/below", data=_strings([i.below for i in scene.interfaces], 64))
            g.create_dataset("interfaces/kind", data=_strings([i.kind for i in scene.interfaces]))
            g.create_dataset("interfaces/stiffness", data=np.array(
                [nan if i.stiffness is None else i.stiffness for i in scene.interfaces]))
            g.create_dataset("interfaces/friction", data=np.array(
                [nan if i.friction is None else i.friction for i in scene.interfaces]))

        _set_attrs(f.create_group("versions"), vers)
        _set_attrs(f.create_group("sizes"), dict(getattr(result, "sizes", None) or {}))
        _set_attrs(f.create_group("timings"), {k: float(v) for k, v in
                                               (getattr(result, "timings", None) or {}).items()})

        c = f.create_group("contact")
        c.attrs["codes"] = CODE_LEGEND
        for key, label, mu, upper, lower in prep["lines"]:
            st = prep["states"].get(key) or []
            g = c.create_group("base") if key == "base" else c.create_group(f"interfaces/{key}")
            _set_attrs(g, {"friction": mu, "label": label, "known": bool(st)})
            g.create_dataset("states", data=_strings(st if st else ["unknown"] * scene.nx))
            g.create_dataset("code", data=np.array([STATE_CODES[s] for s in st] if st else
                                                   [-1] * scene.nx, dtype=np.int8))
            if lower is None:
                g.create_dataset("nodes", data=upper.astype(np.int64))
            else:
                g.attrs["below"] = key
                g.create_dataset("lower_nodes", data=lower.astype(np.int64))
                g.create_dataset("upper_nodes", data=upper.astype(np.int64))

        static = prep["static"]
        if static is not None:
            g = f.create_group("static")
            scalars = ("status", "success", "message", "method", "iterations", "residual",
                       "equilibrium_residual", "rigid_modes")
            _set_attrs(g, {name: getattr(static, name, None) for name in scalars
                           if isinstance(getattr(static, name, None), (str, bool, int, float, np.number))})
            for name in ("guarantees", "notes"):
                items = getattr(static, name, None)
                if isinstance(items, (list, tuple)) and items:
                    g.attrs[name] = _attr("\n".join(str(x) for x in items))
            for name, arr in prep["forces"].items():
                g.create_dataset(name, data=arr)
            for itf, arrays in prep["interface_forces"].items():
                for name, arr in arrays.items():
                    g.create_dataset(f"interfaces/{itf}/{name}", data=arr)
            if prep["static_u"] is not None:
                g.create_dataset("u", data=prep["static_u"])

        g = f.create_group("modes")
        n = scene.n_dofs
        g.create_dataset("sigma", data=np.array([m["sigma"] for m in modes], dtype=float))
        g.create_dataset("growth_rate", data=np.array([m["growth_rate"] for m in modes], dtype=float))
        g.create_dataset("frequency", data=np.array([m["frequency"] for m in modes], dtype=float))
        g.create_dataset("residual", data=np.array([m["residual"] for m in modes], dtype=float))
        g.create_dataset("display_scale", data=np.array(scales, dtype=float))
        X = np.stack([m["x"] for m in modes]) if modes else np.zeros((0, n))
        kw = {"chunks": (1, n), "compression": "gzip", "compression_opts": 4} if modes and n > 4096 else {}
        g.create_dataset("x", data=X, **kw)
        for k, m in enumerate(modes):
            mg = g.create_group(f"mode_{k}")
            _set_attrs(mg, {"sigma": m["sigma"], "growth_rate": m["growth_rate"],
                            "residual": m["residual"], "display_scale": scales[k]})
            mg.create_dataset("support", data=m["support"])
            for name, sup in m["interface_support"].items():
                mg.create_dataset(f"interface_support/{name}", data=sup)

        _write_flutter_modes(f.create_group("flutter_modes"), prep["flutter_modes"], scene.n_dofs)

        g = f.create_group("certificates")
        res = np.array([m["residual"] for m in modes], dtype=float)
        g.create_dataset("mode_residual", data=res)
        solves = [e for e in result.eicp if e is not None]  # one per grazing case

        def joined(name):  # one value per MEiCP solved (one per grazing case), " | " between
            values = [getattr(e, name, None) for e in solves]
            return " | ".join(str(v) for v in values) if any(v is not None for v in values) else None

        coverage = [getattr(e, "coverage", None) for e in solves]
        _set_attrs(g, {
            "result_residual": getattr(result, "residual", float("nan")),
            "max_mode_residual": float(np.nanmax(res)) if res.size and np.isfinite(res).any() else None,
            "eicp_solves": len(solves), "eicp_method": joined("method"),
            "eicp_status": joined("status"), "eicp_message": joined("message"),
            "eicp_coverage": (json.dumps(coverage[0] if len(coverage) == 1 else coverage, default=str)
                              if any(coverage) else None)})

        if mu_c is not None:  # a number (perhaps carrying its bracket), or its record already
            record = mu_c if isinstance(mu_c, dict) else critical_friction_record(mu_c)
            _set_attrs(f.create_group("critical_friction"), record)
        if overrides:
            _set_attrs(f.create_group("overrides"), overrides)
        _describe(f)


def _write_flutter_modes(g, modes: list, n: int) -> None:
    """``/flutter_modes``: one row per flutter mode, fastest first (layout in the module docstring)."""
    def column(fn):
        return np.array([fn(m) for m in modes], dtype=float)

    g.create_dataset("sigma_real", data=column(lambda m: m["sigma"].real))
    g.create_dataset("sigma_imag", data=column(lambda m: m["sigma"].imag))
    g.create_dataset("growth_rate", data=column(lambda m: m["mode"].growth_rate))
    g.create_dataset("frequency", data=column(lambda m: m["mode"].frequency))
    g.create_dataset("residual", data=column(lambda m: m["mode"].residual))
    g.create_dataset("radius", data=column(lambda m: m["mode"].radius))
    g.create_dataset("branch", data=_strings([m["mode"].branch for m in modes], 64))
    X = np.stack([m["x"] for m in modes]) if modes else np.zeros((0, n), dtype=complex)
    kw = {"chunks": (1, n), "compression": "gzip", "compression_opts": 4} if modes and n > 4096 else {}
    g.create_dataset("x_real", data=X.real, **kw)
    g.create_dataset("x_imag", data=X.imag, **kw)
    for k, m in enumerate(modes):
        mg = g.create_group(f"mode_{k}")
        mg.create_dataset("support", data=m["support"])
        for name, sup in m["interface_support"].items():
            mg.create_dataset(f"interface_support/{name}", data=sup)


def _flutter_fields(model, modes: list) -> tuple[dict, dict, float]:
    """The XDMF fields of the fastest flutter mode (real and imaginary parts, one display
    scale for both), their attributes, and that scale."""
    if not modes:
        return {}, {}, 0.0
    m = modes[0]
    scale = plotting.display_scale(model, np.abs(m["x"]))
    sigma = m["sigma"]
    head = (f"fastest flutter mode (sigma = {sigma.real:.10g} {sigma.imag:+.6g}i, growth rate "
            f"{m['mode'].growth_rate:.6g}) times its display scale {scale:.6g}")
    fields = {"flutter_0_real": scale * m["x"].real, "flutter_0_imag": scale * m["x"].imag}
    attrs = {"flutter_0_real": {"long_name": f"real part of the {head}"},
             "flutter_0_imag": {"long_name": f"imaginary part (a quarter period later) of the {head}"}}
    return fields, attrs, scale


# --------------------------------------------------------------------------- the whole set

def _write_all(stage: Path, scene: Scene, result, prep: dict, text: str, vers: dict, ranks: int,
               max_xdmf_modes: int, plots: bool, mu_c=None, overrides=None) -> dict:
    import h5py

    model = as_model(scene)
    modes = prep["modes"]
    scales = [plotting.display_scale(model, m["x"]) for m in modes]
    written = {}

    _write_h5(h5py, stage / FILES["results"], scene, result, prep, text, vers, scales, ranks, mu_c, overrides)
    written["results"] = FILES["results"]

    fields = {f"mode_{k}": scales[k] * m["x"] for k, m in enumerate(modes[:max_xdmf_modes])}
    described = {f"mode_{k}": {"long_name": f"shape of mode {k} (sigma = {m['sigma']:.10g}) times its display "
                                            f"scale {scales[k]:.6g}"} for k, m in enumerate(modes[:max_xdmf_modes])}
    flutter_fields, flutter_attrs, flutter_scale = _flutter_fields(model, prep["flutter_modes"])
    fields.update(flutter_fields)
    described.update(flutter_attrs)
    fields["contact_state"] = prep["code"]
    if prep["static_u"] is not None:
        fields["static_u"] = prep["static_u"]
    fields.update(prep["node_forces"])
    described.update(FIELD_DESCRIPTIONS)
    files = write_lattice(stage / FILES["lattice"], model, fields=fields, comm=None, scene_text=text,
                          field_attrs=described)
    written["lattice"], written["xdmf"] = files.h5.name, files.xdmf.name

    if plots:
        fastest = modes[0]["mode"] if modes else None
        # mode.png is about divergence: "stable" there means no divergence mode (flutter has its PNG)
        divergence = getattr(result, "divergence", None)
        no_divergence = getattr(result, "stable", None) if divergence is None else divergence is False
        plotting.plot_mode(model, stage / FILES["mode_png"], fastest, stable=no_divergence,
                  n_modes=len(modes))
        written["mode_png"] = FILES["mode_png"]
        if prep["flutter_modes"]:
            m = prep["flutter_modes"][0]
            shape = dataclasses.replace(m["mode"], x=m["x"].real)
            plotting.plot_mode(model, stage / FILES["flutter_png"], shape, heading=(
                f"fastest flutter mode (real part of x), σ = {m['sigma'].real:.6g} {m['sigma'].imag:+.4g}i, "
                f"growth rate {shape.growth_rate:.4g}, frequency {shape.frequency:.4g}"),
                n_modes=len(prep["flutter_modes"]))
            written["flutter_png"] = FILES["flutter_png"]
        if prep["lines"]:
            per_line = _line_forces(prep, scene.nx)
            u = prep["static_u"]
            u_scale = float(np.abs(u).max()) if u is not None and u.size else None
            lines = []
            for key, label, mu, _, _ in prep["lines"]:
                if fastest is None:
                    sup = None
                elif key == "base":
                    sup = modes[0]["support"]
                else:
                    sup = modes[0]["interface_support"].get(key)
                lines.append(plotting.ContactLine(label=label, friction=mu, states=prep["states"].get(key) or None,
                                         support=sup, scale=u_scale, **per_line[key]))
            plotting.plot_contacts(model, stage / FILES["contacts_png"], lines)
            written["contacts_png"] = FILES["contacts_png"]
    return written


def write_results(directory, scene, result, *, comm=None, scene_text: str | None = None,
                  max_xdmf_modes: int = 16, plots: bool = True, critical_friction=None,
                  overrides: dict | None = None) -> dict:
    """Write the outputs of an instability analysis to ``directory`` (created if missing).

    ``scene``: the :class:`Scene` analysed; ``result``: its
    :class:`~meicp.contact.result.InstabilityResult` (modes as NumPy arrays in natural
    numbering, the same on every rank).  ``scene_text``: the scene file's text (default: read
    from ``scene.source``, else regenerated).  ``max_xdmf_modes``: how many modes become
    XDMF fields (all of them go to ``results.h5``).  ``plots``: write the PNGs.
    ``critical_friction``: μ_c when computed (a float, a float carrying its bracket, or its
    :func:`critical_friction_record`), stored in ``/critical_friction``.  ``overrides``: the
    solver settings the command line gave over the scene's, stored in ``/overrides``.

    Returns ``{"results", "lattice", "xdmf", "mode_png", "contacts_png"}`` → Path (the PNG
    keys only when written).  Collective on ``comm``: rank 0 writes, every rank returns the
    same dict or raises the same error.  Raises :class:`ProblemError` for a result that does
    not fit the scene, before anything is written.
    """
    mcomm = mpi_comm(comm)
    rank, size = (0, 1) if mcomm is None else (mcomm.Get_rank(), mcomm.Get_size())
    directory = Path(directory)
    vers = versions()  # on every rank: importing PETSc may be collective
    outcome = None  # (written names) or (error class name, message)
    error = None
    if rank == 0:
        try:
            with log_stage("write"):
                outcome = ("ok", _write_rank0(directory, scene, result, scene_text, vers, size,
                                              max_xdmf_modes, plots, critical_friction, overrides))
        except BaseException as exc:  # noqa: BLE001 - re-raised below, after telling the others
            error = exc
            outcome = ("ProblemError" if isinstance(exc, ProblemError) else "error",
                       f"{exc}" if isinstance(exc, MeicpError) else f"{type(exc).__name__}: {exc}")
    if mcomm is not None:
        outcome = mcomm.bcast(outcome, root=0)
    if error is not None:
        raise error
    kind, payload = outcome
    if kind == "ProblemError":
        raise ProblemError(payload)
    if kind != "ok":
        raise MeicpError(f"writing the results on rank 0 failed: {payload}")
    return {key: directory / name for key, name in payload.items()}


def _write_rank0(directory: Path, scene, result, scene_text, vers, ranks, max_xdmf_modes, plots,
                 mu_c=None, overrides=None) -> dict:
    prep = _prepare(scene, result)  # every check before the disk is touched
    text = _scene_text(scene, scene_text)
    created = None  # the topmost directory this call creates, removed again on error
    for d in [directory, *directory.parents]:
        if d.exists():
            break
        created = d
    try:
        directory.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ProblemError(f"cannot create output directory {str(directory)!r}: "
                           f"{exc.strerror or exc}") from None
    if not os.access(directory, os.W_OK):
        raise ProblemError(f"output directory {str(directory)!r} is not writable")
    stage = directory / f".meicp-results.{os.getpid()}.tmp"
    moved = False

    def discard():  # on an error, or from the signal watchdog (meicp.core.cleanup)
        shutil.rmtree(stage, ignore_errors=True)
        if created is not None and not moved:
            shutil.rmtree(created, ignore_errors=True)

    try:
        with on_interrupt(discard):
            stage.mkdir()
            written = _write_all(stage, scene, result, prep, text, vers, ranks, max_xdmf_modes, plots, mu_c,
                                 overrides)
            # data first, the XDMF (which points at lattice.h5) after it, results.h5 last; a
            # signal waits for these renames, so the outputs are never half old, half new
            order = [k for k in ("lattice", "xdmf", "mode_png", "flutter_png", "contacts_png", "results")
                     if k in written]
            with uninterrupted():
                for key in order:
                    os.replace(stage / written[key], directory / written[key])
                moved = True
        if plots:  # a stale PNG from an earlier run of another scene would mislead
            for key in ("contacts_png",):
                if key not in written and (directory / FILES[key]).exists():
                    (directory / FILES[key]).unlink()
        return written
    except BaseException:
        discard()
        raise
    finally:
        shutil.rmtree(stage, ignore_errors=True)
