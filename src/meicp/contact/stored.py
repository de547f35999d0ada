"""A stored result made whole again: :func:`result_from_record` turns what
:func:`meicp.io.results_read.read_results` read from a results.h5 into the
:class:`~meicp.contact.result.InstabilityResult` that was written (``meicp.load_results``).

Everything results.h5 holds comes back: verdicts, evidence, modes and flutter modes with
their shapes and supports, the proofs, contact states, sizes and timings, the critical
friction when it was computed, and the static equilibrium's status, reactions and
displacement.  What it does not hold stays empty: ``eicp`` holds each MEiCP's method, status
and message but no solutions or candidates, ``static`` has no LCP, matrix classes or layout.
"""

from __future__ import annotations

import numpy as np

from ..core.json_values import restore_infinities
from ..eicp.problem import EiCPResult
from .critical_friction.result import CriticalFriction, CriticalFrictionFailed, Onset
from .damped import DampingUsed
from .divergence.verdict import DivergenceProof
from .flutter_growth import FlutterGrowth
from .result import FlutterMode, InstabilityResult, Mode
from .static.result import StaticResult

#: results.h5 stores a three-way verdict as 1 / 0 / -1
_VERDICT = {1: True, 0: False, -1: None}
#: the static equilibrium's attributes that results.h5 stores
_STATIC_SCALARS = ("status", "message", "iterations", "residual", "equilibrium_residual", "rigid_modes")


def result_from_record(record: dict) -> InstabilityResult:
    """The :class:`InstabilityResult` of a results.h5 record (module docstring)."""
    a = record["attrs"]
    r = InstabilityResult(status=a.get("status", "not_run"), message=a.get("message", ""),
                          iterations=int(a.get("iterations", 0)), residual=float(a.get("residual", np.nan)),
                          timings={k: float(v) for k, v in record["timings"].items()})
    r.analysis = a.get("analysis", "instability")
    r.stable = _VERDICT.get(a.get("stable", -1))
    r.divergence = _VERDICT.get(a.get("divergence", -1))
    r.flutter = _VERDICT.get(a.get("flutter", -1))
    r.evidence, r.flutter_evidence = a.get("evidence", ""), a.get("flutter_evidence", "")
    if "flutter_growth_lower" in a:
        upper = float(a["flutter_growth_upper"])
        r.flutter_growth = FlutterGrowth(float(a["flutter_growth_lower"]), None if np.isnan(upper) else upper,
                                         a.get("flutter_growth_evidence", ""),
                                         loose=bool(a.get("flutter_growth_upper_loose", 0)))
    r.modes = [Mode(sigma=m["sigma"], x=m["x"], support=m["support"], residual=m["residual"],
                    interface_support=m["interface_support"]) for m in record["modes"]]
    r.flutter_modes = [FlutterMode(sigma=m["sigma"], x=m["x"], residual=m["residual"], support=m["support"],
                                   interface_support=m["interface_support"], radius=m["radius"],
                                   branch=m["branch"], found_by=m["found_by"]) for m in record["flutter_modes"]]
    r.states, r.interface_states = list(record["states"]), dict(record["interface_states"])
    r.sizes = {k: int(v) for k, v in record["sizes"].items()}
    r.proofs = [proof_from_dict(p) for p in record["proofs"]]
    r.eicp = [None if e is None else EiCPResult(method=e["method"], status=e["status"], message=e["message"])
              for e in (record["eicp"] or [])]
    r.static = _static(record["static"], r)
    r.critical_friction = _critical_friction(record["critical_friction"])
    damping = record.get("damping")
    r.damping = None if damping is None else DampingUsed(damping["viscosity"], damping["interface_viscosity"],
                                                         damping["mass"])
    return r


def proof_from_dict(data: dict) -> DivergenceProof:
    """A :class:`DivergenceProof` from its ``to_dict()`` as JSON stored it (an infinite end
    of the σ-window as null with a ``sigma_window_infinite`` flag, format 2, or as the string
    "inf", format 1; an unknown one as null)."""
    d = restore_infinities(dict(data))
    if d.get("sigma_window") is not None:
        d["sigma_window"] = tuple(_number(v) for v in d["sigma_window"])
    for name in ("margin", "stable_friction_scale"):
        if d.get(name) is not None:
            d[name] = _number(d[name])
    if d.get("stable_friction") is not None:
        d["stable_friction"] = {k: _number(v) for k, v in d["stable_friction"].items()}
    return DivergenceProof(**d)


def _number(v) -> float:
    return np.nan if v is None else float(v)  # float("inf") reads "inf"


def _static(record: dict | None, result: InstabilityResult) -> StaticResult | None:
    if record is None:
        return None
    a, arrays, interfaces = record["attrs"], record["arrays"], record["interfaces"]
    static = StaticResult(**{k: a[k] for k in _STATIC_SCALARS if k in a})
    static.guarantees = a["guarantees"].split("\n") if a.get("guarantees") else []
    static.notes = a["notes"].split("\n") if a.get("notes") else []
    for name in ("r_n", "r_t", "gap", "slip", "held", "u"):
        if name in arrays:
            setattr(static, name, arrays[name].astype(bool) if name == "held" else arrays[name])
    for itf, fields in interfaces.items():
        for name, value in fields.items():
            getattr(static, f"interface_{name}")[itf] = value.astype(bool) if name == "held" else value
    if static.success:  # the states the analysis used are the equilibrium's
        static.states, static.interface_states = list(result.states), dict(result.interface_states)
    return static


def _critical_friction(record: dict | None):
    if record is None:
        return None
    if record.get("error"):
        return CriticalFrictionFailed(str(record["error"]))
    if all(record.get(k) is not None for k in ("lower", "upper", "exact")):
        divergence, flutter = (_onset(record.get(name)) for name in ("divergence", "flutter"))
        return CriticalFriction(record["upper"], record["lower"], bool(record["exact"]), record.get("evidence") or "",
                                divergence=divergence, flutter=flutter)
    return float(record["value"])


def _onset(record: dict | None) -> Onset | None:
    if not record:
        return None
    mode = record.get("mode")
    if mode:
        mode = FlutterMode(sigma=complex(mode["sigma_real"], mode["sigma_imag"]), x=np.zeros(0),
                           residual=float(mode["residual"]), radius=float(mode["radius"]),
                           branch=mode.get("branch", ""))
    floor = record.get("floor")
    return Onset(float(record["lower"]), float(record["upper"]), bool(record["exact"]), record.get("evidence", ""),
                 mode or None, None if floor is None else float(floor))
