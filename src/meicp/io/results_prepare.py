"""What results.h5 and lattice.h5 will hold, checked against the scene before anything is
written (:func:`_prepare`): contact lines, states, modes, flutter modes, static forces, and the
per-node fields of the XDMF file.  Raises :class:`~meicp.core.errors.ProblemError` for a
result that does not fit the scene.
"""

from __future__ import annotations

import math

import numpy as np

from ..core.errors import ProblemError
from ..scene import Scene
from .results_schema import STATE_CODES, STATIC_FIELDS


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
