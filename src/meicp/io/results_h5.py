"""The HDF5 writer of results.h5 (:func:`_write_h5`; layout in :mod:`meicp.io.results`):
attributes, datasets and their CF-style descriptions, from what
:func:`~meicp.io.results_prepare._prepare` collected.
"""

from __future__ import annotations

import datetime
import json
from pathlib import Path

import numpy as np

from .._version import __version__
from ..scene import Scene
from .lattice_output import UNITS_CONVENTION
from .results_records import critical_friction_record
from .results_schema import CODE_LEGEND, DESCRIPTIONS, FORMAT, FORMAT_VERSION, STATE_CODES, group_key


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


def _set_record(group, record: dict) -> None:
    """A record's values as attributes of ``group``, each nested record (dict) as a subgroup
    of its own (None: nothing written)."""
    _set_attrs(group, {k: v for k, v in record.items() if not isinstance(v, dict)})
    for k, v in record.items():
        if isinstance(v, dict):
            _set_record(group.create_group(str(k)), v)


#: h5py's variable-length UTF-8 string (``h5py.string_dtype("utf-8")``, without importing h5py here)
UTF8 = np.dtype("O", metadata={"vlen": str})


def _strings(values) -> np.ndarray:
    """Variable-length UTF-8: a layer's name or a branch label of any length stored whole (a
    fixed width cut them, mid-character for a non-ASCII name)."""
    return np.array([str(v) for v in values], dtype=UTF8)


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
            "divergence_failure": getattr(result, "divergence_failure", None),
            "divergence_tests": ", ".join(p.test or "none" for p in getattr(result, "proofs", [])),
            "divergence_proofs": json.dumps(result.to_dict().get("proofs", []) if hasattr(result, "to_dict") else []),
            "n_flutter_modes": len(prep["flutter_modes"]),
            **_growth_attrs(getattr(result, "flutter_growth", None))})
        f.create_dataset("scene", data=text, dtype=UTF8)

        g = f.create_group("scene_summary")
        b = scene.boundary
        _set_attrs(g, {"nx": scene.nx, "ny": scene.ny, "n_nodes": scene.n_nodes,
                       "n_dofs": scene.n_dofs, "spacing": scene.lattice.spacing,
                       "shear": scene.lattice.shear, "title": scene.title,
                       **{f"boundary_{s}": getattr(b, s) for s in ("top", "bottom", "left", "right")},
                       "base_friction": scene.contact.friction if scene.contact else None,
                       "n_embedded": len(scene.embedded)})
        g.create_dataset("layers/name", data=_strings([l.name for l in scene.layers]))
        g.create_dataset("layers/rows", data=np.array([l.rows for l in scene.layers], dtype=np.int64))
        g.create_dataset("layers/stiffness", data=np.array([l.stiffness for l in scene.layers]))
        g.create_dataset("layers/density", data=np.array([l.density for l in scene.layers]))
        if getattr(result, "damping", None) is not None:  # what the analysis used (docs/damping.md)
            g.create_dataset("layers/viscosity", data=np.array([l.viscosity or 0.0 for l in scene.layers]))
            _set_record(f.create_group("damping"), result.damping.to_dict())
        if scene.interfaces:
            nan = float("nan")
            g.create_dataset("interfaces/below", data=_strings([i.below for i in scene.interfaces]))
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
            g = c.create_group("base") if key == "base" else c.create_group(f"interfaces/{group_key(key)}")
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
                    g.create_dataset(f"interfaces/{group_key(itf)}/{name}", data=arr)
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
                mg.create_dataset(f"interface_support/{group_key(name)}", data=sup)

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
            # one entry per grazing case, null where every DOF was held: meicp.load_results reads them back
            "eicp_outcomes": json.dumps([None if e is None else {name: getattr(e, name, "")
                                                                 for name in ("method", "status", "message")}
                                         for e in result.eicp], default=str),
            "eicp_status": joined("status"), "eicp_message": joined("message"),
            "eicp_coverage": (json.dumps(coverage[0] if len(coverage) == 1 else coverage, default=str)
                              if any(coverage) else None)})

        if mu_c is not None:  # a number (perhaps carrying its bracket), or its record already
            record = mu_c if isinstance(mu_c, dict) else critical_friction_record(mu_c)
            _set_record(f.create_group("critical_friction"), record)
        if overrides:
            _set_attrs(f.create_group("overrides"), overrides)
        _describe(f)


def _growth_attrs(growth) -> dict:
    """``flutter_growth_lower`` / ``_upper`` (NaN: no bound proved) / ``_exact`` / ``_evidence``
    (all absent when flutter was not analysed)."""
    if growth is None:
        return {}
    return {"flutter_growth_lower": float(growth.lower),
            "flutter_growth_upper": float("nan") if growth.upper is None else float(growth.upper),
            "flutter_growth_exact": int(growth.exact), "flutter_growth_upper_loose": int(growth.loose),
            "flutter_growth_evidence": growth.evidence}


def _write_flutter_modes(g, modes: list, n: int) -> None:
    """``/flutter_modes``: one row per flutter mode, fastest first (layout in :mod:`meicp.io.results`)."""
    def column(fn):
        return np.array([fn(m) for m in modes], dtype=float)

    g.create_dataset("sigma_real", data=column(lambda m: m["sigma"].real))
    g.create_dataset("sigma_imag", data=column(lambda m: m["sigma"].imag))
    g.create_dataset("growth_rate", data=column(lambda m: m["mode"].growth_rate))
    g.create_dataset("frequency", data=column(lambda m: m["mode"].frequency))
    g.create_dataset("residual", data=column(lambda m: m["mode"].residual))
    g.create_dataset("radius", data=column(lambda m: m["mode"].radius))
    g.create_dataset("branch", data=_strings([m["mode"].branch for m in modes]))
    g.create_dataset("found_by", data=_strings([m["mode"].found_by for m in modes]))
    X = np.stack([m["x"] for m in modes]) if modes else np.zeros((0, n), dtype=complex)
    kw = {"chunks": (1, n), "compression": "gzip", "compression_opts": 4} if modes and n > 4096 else {}
    g.create_dataset("x_real", data=X.real, **kw)
    g.create_dataset("x_imag", data=X.imag, **kw)
    for k, m in enumerate(modes):
        mg = g.create_group(f"mode_{k}")
        mg.create_dataset("support", data=m["support"])
        for name, sup in m["interface_support"].items():
            mg.create_dataset(f"interface_support/{group_key(name)}", data=sup)
