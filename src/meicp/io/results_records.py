"""The small records stored beside a result (:mod:`meicp.io.results`): the versions of the
software, the critical friction as a record, and the scene as TOML text (the file's own text
when known, else regenerated from the parsed scene by :func:`scene_to_toml`).
"""

from __future__ import annotations

import json
import math
import os
import platform
import re
from pathlib import Path

import numpy as np
import scipy

from .._version import __version__
from ..info import collect
from ..scene import Scene


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
    with a certified bracket); ``evidence`` stands in when it carries none.  Unknown: None.
    A :class:`~meicp.contact.critical_friction.CriticalFriction` adds ``first`` and the two
    onsets, ``divergence`` and ``flutter`` (:func:`onset_record`; ``flutter`` None when it was
    not analysed)."""
    value = float(mu)
    record = {"value": value, "found": math.isfinite(value)}
    for name in ("lower", "upper", "exact", "evidence"):
        item = getattr(mu, name, None)
        record[name] = float(item) if isinstance(item, (float, np.floating)) else item
    if record["evidence"] is None:
        record["evidence"] = evidence
    if getattr(mu, "divergence", None) is not None:
        record["first"] = mu.first
        record["divergence"] = onset_record(mu.divergence)
        record["flutter"] = None if mu.flutter is None else onset_record(mu.flutter)
    return record


def onset_record(onset) -> dict:
    """One onset's bracket (:class:`~meicp.contact.critical_friction.result.Onset`) as a
    record: ``value`` (= ``upper``), ``found`` (upper finite), ``lower``, ``upper`` (floats,
    inf included), ``none_at_any_mu`` (lower inf: proved at every μ), ``exact``, ``evidence``,
    and for flutter ``mode``: the certified mode at ``upper`` (σ, growth rate, frequency,
    residual, radius, branch), None without one; for divergence ``floor`` where its lower end is
    about σ = 0 modes alone (no mode of any σ ≥ 0 on [0, floor], proved), absent otherwise."""
    lower, upper = float(onset.lower), float(onset.upper)
    record = {"value": upper, "found": math.isfinite(upper), "lower": lower, "upper": upper,
              "none_at_any_mu": lower == math.inf, "exact": bool(onset.exact), "evidence": onset.evidence}
    if getattr(onset, "floor", None) is not None:
        record["floor"] = float(onset.floor)
    mode = getattr(onset, "mode", None)
    record["mode"] = None if mode is None else {
        "sigma_real": float(mode.sigma.real), "sigma_imag": float(mode.sigma.imag),
        "growth_rate": float(mode.growth_rate), "frequency": float(mode.frequency),
        "residual": float(mode.residual), "radius": float(mode.radius), "branch": mode.branch}
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


def _toml_key(key: str) -> str:
    return key if re.fullmatch(r"[A-Za-z0-9_-]+", key) else json.dumps(key)


def scene_to_toml(scene: Scene) -> str:
    """A TOML text that :func:`~meicp.io.scene.loads_scene` reads back to an equal scene
    (``source`` aside): the record of a scene built in code, with no file behind it —
    :meth:`Scene.to_dict <meicp.scene.Scene.to_dict>` written as TOML."""
    table = scene.to_dict()
    lines = [f"title = {_toml_value(table.pop('title'))}"] if "title" in table else []
    for name, value in table.items():
        entries = value if isinstance(value, list) else [value]  # a list: an array of tables
        for entry in entries:
            lines.append("")
            lines.append(f"[[{name}]]" if isinstance(value, list) else f"[{name}]")
            lines.extend(f"{_toml_key(str(k))} = {_toml_value(v)}" for k, v in entry.items())
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
