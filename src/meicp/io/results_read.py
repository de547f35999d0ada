"""results.h5 read back (layout in :mod:`meicp.io.results`): :func:`read_results` gives its
content as plain values — strings, numbers, NumPy arrays, lists and dicts keyed like the
result's attributes — and :func:`meicp.load_results` turns them into the result object
(:mod:`meicp.contact.stored`), so this module needs no class of the analysis.

A file that is not a meicp results file, or one written by a newer format version, is a
ProblemError naming the file; a group or attribute an older writer did not write is simply
absent from the record (None, or empty).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..core.errors import ProblemError
from .results_schema import FORMAT, FORMAT_VERSION, name_of_key


def read_results(path) -> dict:
    """The content of a results.h5 as plain values.

    Keys: ``attrs`` (the root attributes: status, message, evidence, verdict, analysis,
    divergence / flutter / stable as 1, 0, -1...), ``scene`` (its TOML text), ``sizes``,
    ``timings``, ``states`` (the base's, empty when unknown), ``interface_states``,
    ``modes`` and ``flutter_modes`` (one dict per mode: sigma, x, residual, support,
    interface_support, and radius, branch, found_by for flutter), ``proofs`` (dicts, as
    ``DivergenceProof.to_dict`` wrote them), ``eicp`` (method, status, message per MEiCP, or
    None when not recorded), ``static`` (attributes and arrays, or None),
    ``critical_friction`` (its record, or None), ``damping`` (``DampingUsed.to_dict``, or None:
    undamped) and ``overrides``."""
    import h5py

    if not isinstance(path, (str, Path)) and not hasattr(path, "__fspath__"):
        raise ProblemError(f"path must be a str or os.PathLike, got {type(path).__name__}")
    path = Path(path)
    if not path.is_file():
        raise ProblemError(f"cannot read results file {str(path)!r}: no such file")
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        raise ProblemError(f"{path}: not an HDF5 file ({exc})") from None
    with f:
        attrs = _attrs(f)
        if attrs.get("format") != FORMAT:
            raise ProblemError(f"{path}: not a meicp results file (format {attrs.get('format')!r}, "
                               f"expected {FORMAT!r})")
        version = int(attrs.get("format_version", 0))
        if version > FORMAT_VERSION:
            raise ProblemError(f"{path}: format version {version} is newer than this meicp reads "
                               f"({FORMAT_VERSION}); update meicp")
        record = {"attrs": attrs, "scene": _text(f.get("scene")),
                  "sizes": _attrs(f.get("sizes")), "timings": _attrs(f.get("timings")),
                  "overrides": _attrs(f.get("overrides"))}
        record["states"], record["interface_states"] = _states(f.get("contact"))
        record["modes"] = _modes(f.get("modes"))
        record["flutter_modes"] = _flutter_modes(f.get("flutter_modes"))
        record["proofs"] = json.loads(attrs.get("divergence_proofs", "[]"))
        cert = _attrs(f.get("certificates"))
        record["eicp"] = json.loads(cert["eicp_outcomes"]) if "eicp_outcomes" in cert else None
        record["static"] = _static(f.get("static"))
        record["critical_friction"] = _critical_friction(f.get("critical_friction"))
        record["damping"] = _damping(f.get("damping"))
    return record


def _damping(g) -> dict | None:
    """The damping the analysis used (``DampingUsed.to_dict``), or None: undamped."""
    if g is None:
        return None
    return {"viscosity": _attrs(g.get("viscosity")), "interface_viscosity": _attrs(g.get("interface_viscosity")),
            "mass": float(_attrs(g).get("mass", 0.0))}


def _critical_friction(g) -> dict | None:
    """``/critical_friction``'s attributes, with each onset's (``divergence``, ``flutter``, and
    ``flutter["mode"]``) when stored."""
    if g is None:
        return None
    record = _attrs(g)
    for name in ("divergence", "flutter"):
        if name in g:
            record[name] = _attrs(g[name])
            if name == "flutter":
                record[name]["mode"] = _attrs(g[name]["mode"]) if "mode" in g[name] else None
    return record


def _value(v):
    if isinstance(v, bytes):
        return v.decode("utf-8")
    if isinstance(v, np.generic):
        return v.item()
    return v


def _attrs(obj) -> dict:
    return {} if obj is None else {str(k): _value(v) for k, v in obj.attrs.items()}


def _text(dataset) -> str:
    if dataset is None:
        return ""
    return _value(dataset[()])


def _strings(dataset) -> list[str]:
    return [s.decode("utf-8") if isinstance(s, bytes) else str(s) for s in dataset[()]]


def _states(contact) -> tuple[list, dict]:
    if contact is None:
        return [], {}
    base = []
    if "base" in contact and contact["base"].attrs.get("known", False):
        base = _strings(contact["base/states"])
    interfaces = {}
    for name, g in (contact["interfaces"].items() if "interfaces" in contact else ()):
        interfaces[name_of_key(name)] = _strings(g["states"]) if g.attrs.get("known", False) else []
    return base, interfaces


def _supports(g) -> tuple[np.ndarray, dict]:
    support = np.asarray(g["support"][()], dtype=np.int64)
    inner = g.get("interface_support")
    return support, ({} if inner is None else {name_of_key(k): np.asarray(v[()], dtype=np.int64) for k, v in inner.items()})


def _modes(g) -> list[dict]:
    if g is None:
        return []
    sigma, residual, X = g["sigma"][()], g["residual"][()], g["x"]
    out = []
    for k in range(sigma.size):
        support, interface_support = _supports(g[f"mode_{k}"])
        out.append({"sigma": float(sigma[k]), "x": np.asarray(X[k], dtype=float), "residual": float(residual[k]),
                    "support": support, "interface_support": interface_support})
    return out


def _flutter_modes(g) -> list[dict]:
    if g is None:
        return []
    re, im = g["sigma_real"][()], g["sigma_imag"][()]
    residual, radius = g["residual"][()], g["radius"][()]
    branch = _strings(g["branch"])
    found_by = _strings(g["found_by"]) if "found_by" in g else [""] * re.size
    out = []
    for k in range(re.size):
        support, interface_support = _supports(g[f"mode_{k}"])
        out.append({"sigma": complex(re[k], im[k]), "x": g["x_real"][k] + 1j * g["x_imag"][k],
                    "residual": float(residual[k]), "radius": float(radius[k]), "branch": branch[k],
                    "found_by": found_by[k], "support": support, "interface_support": interface_support})
    return out


def _static(g) -> dict | None:
    if g is None:
        return None
    out = {"attrs": _attrs(g), "arrays": {}, "interfaces": {}}
    for name, item in g.items():
        if name == "interfaces":
            out["interfaces"] = {name_of_key(itf): {k: v[()] for k, v in arrays.items()} for itf, arrays in item.items()}
        else:
            out["arrays"][name] = item[()]
    return out
