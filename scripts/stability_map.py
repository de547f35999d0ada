"""Stability map of a shipped scene for docs/benchmarks.md: ``meicp.sweep`` over μ, plus the
flutter onset by bisection and μ_c.

    .venv/bin/python scripts/stability_map.py [data/scenes/two_layers.toml] [--mu-max 6] [--steps 61]

The sweep (``meicp.sweep``, the same as ``meicp sweep SCENE --mu 0:MU_MAX:STEPS``) gives each
μ's verdicts and growth rates; then the smallest μ with flutter by bisection on the flutter
verdict between the grid's last flutter-free value and its first fluttering one (stopping,
and saying so, where a verdict is undecided; a bisection on the verdict alone is no proof
that flutter does not start and stop below), and μ_c from ``meicp.critical_friction``.
Writes ``stability_map.csv`` (the sweep's columns) and ``stability_map.png`` into
``docs/benchmarks/`` (``$MEICP_BENCH_DIR`` overrides).
"""

from __future__ import annotations

import argparse
import json

import numpy as np

import meicp
from bench_common import ROOT, csv_path, out_dir
from meicp.study import scene_with


def smallest_flutter_mu(scene, lo: float, hi: float, rel_tol: float = 1e-6) -> dict:
    """Bisection on analyze's flutter verdict in [lo, hi] (no flutter, a proof, at lo; flutter
    at hi).  An undecided verdict ends it: the bracket is reported as it stands."""
    while hi - lo > rel_tol * hi:
        mid = 0.5 * (lo + hi)
        f = meicp.analyze(scene_with(scene, "friction", mid)).flutter
        if f is None:
            return {"lower": lo, "upper": hi, "note": f"undecided at μ = {mid:.8g} (a collision of eigenvalues "
                                                      "at rounding level): the bisection stops there"}
        lo, hi = (lo, mid) if f else (mid, hi)
    return {"lower": lo, "upper": hi, "note": "flutter verdict False (a proof) at lower, True at upper"}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", nargs="?", default=str(ROOT / "data" / "scenes" / "two_layers.toml"))
    ap.add_argument("--mu-max", type=float, default=6.0)
    ap.add_argument("--steps", type=int, default=61)
    args = ap.parse_args()
    scene = meicp.load_scene(args.scene)
    result = meicp.sweep(scene, "friction", np.linspace(0.0, args.mu_max, args.steps), progress=False)
    onset = result.flutter_onset
    bracket = (smallest_flutter_mu(scene, onset.lower, onset.upper)
               if onset.lower is not None and onset.upper is not None else None)
    mu_c = meicp.critical_friction(scene)
    marks = [(float(mu_c), f"μ_c = {mu_c:.4g} (critical_friction)")] if np.isfinite(mu_c) else []
    if bracket:
        marks.append((bracket["upper"], f"flutter from μ ≈ {bracket['upper']:.4g} (bisection)"))
    result.to_csv(csv_path("stability_map"))
    result.plot(out_dir() / "stability_map.png", marks=marks,
                title=f"{args.scene.split('/')[-1]}: stability of steady sliding against μ")
    print(json.dumps({"scene": args.scene.split("/")[-1], "mu_c": float(mu_c) if np.isfinite(mu_c) else None,
                      "flutter_bracket": bracket}, indent=1))
    print(result.summary())


if __name__ == "__main__":
    main()
