"""Stability map of a shipped scene for docs/benchmarks.md: ``meicp.sweep`` over μ, plus the
flutter onset by bisection and μ_c.

    .venv/bin/python scripts/stability_map.py [data/scenes/two_layers.toml] [--mu-max 6] [--steps 61]

The sweep (``meicp.sweep``, the same as ``meicp sweep SCENE --mu 0:MU_MAX:STEPS``) gives each
μ's verdicts and growth rates; then both onsets from ``meicp.critical_friction``: μ_c
(divergence) and μ_f, the smallest μ with flutter, a certified bracket (an interval cover from
μ = 0 and a certified mode: docs/critical-friction.md, "The flutter onset").  Writes
``stability_map.csv`` (the sweep's columns) and ``stability_map.png`` into
``docs/benchmarks/`` (``$MEICP_BENCH_DIR`` overrides).
"""

from __future__ import annotations

import argparse
import json

import numpy as np

import meicp
from bench_common import ROOT, csv_path, out_dir




def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", nargs="?", default=str(ROOT / "data" / "scenes" / "two_layers.toml"))
    ap.add_argument("--mu-max", type=float, default=6.0)
    ap.add_argument("--steps", type=int, default=61)
    args = ap.parse_args()
    scene = meicp.load_scene(args.scene)
    result = meicp.sweep(scene, "friction", np.linspace(0.0, args.mu_max, args.steps), progress=False)
    onsets = meicp.critical_friction(scene)
    mu_c, flutter = onsets.divergence.upper, onsets.flutter
    marks = [(float(mu_c), f"μ_c = {mu_c:.4g} (critical_friction)")] if np.isfinite(mu_c) else []
    if flutter is not None and np.isfinite(flutter.upper):
        marks.append((flutter.upper, f"μ_f ∈ [{flutter.lower:.7g}, {flutter.upper:.7g}] (critical_friction)"))
    result.to_csv(csv_path("stability_map"))
    result.plot(out_dir() / "stability_map.png", marks=marks,
                title=f"{args.scene.split('/')[-1]}: stability of steady sliding against μ")
    print(json.dumps({"scene": args.scene.split("/")[-1], "mu_c": float(mu_c) if np.isfinite(mu_c) else None,
                      "flutter_onset": None if flutter is None else
                      {"lower": flutter.lower, "upper": flutter.upper, "exact": flutter.exact},
                      "first": onsets.first}, indent=1))
    print(result.summary())


if __name__ == "__main__":
    main()
