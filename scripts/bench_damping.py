#!/usr/bin/env python3
"""Growth rate against friction with and without damping (issue 31, docs/damping.md): the
fastest divergence and flutter growth of two small scenes for η = 0 and two viscosities, on
one chart — the damping that raises a flutter threshold (base contact) and the damping that
lowers it (frictional interface: the destabilisation paradox).

    .venv/bin/python scripts/bench_damping.py run      # -> damping_growth.csv
    .venv/bin/python scripts/bench_damping.py chart    # -> damping_growth.png

Scenes (the dense damped references, where every answer is a proof or a certified mode):
``data/scenes/two_layers.toml`` (every base node slip+) and the 6 × 4 frictional interface
of tests/test_damping.py (k 2 under k 1, ρ 1, every pair slip+).  At each μ of the grid:
the divergence verdict and λ of its fastest certified mode; the flutter verdict and its
growth bracket (exact on the dense path).  Growth 0 where a verdict is proved absent; an
undecided verdict leaves a gap.  The grid's first μ with certified flutter is a measured
threshold, not a proved onset (the damped critical friction is not built).
"""

from __future__ import annotations

import argparse

import numpy as np

from bench_common import ROOT, csv_path, read_rows, save_figure, write_rows
import meicp
from meicp.examples import two_layer_scene
from meicp.io.scene import scene_from_dict

FIELDS = ["scene", "eta", "mu", "divergence", "divergence_growth", "flutter", "flutter_lower", "flutter_upper",
          "flutter_exact", "seconds"]
#: viscosities of the two layers: none, equal, a viscous base layer under a less viscous one
ETAS = {"0": (0.0, 0.0), "0.02 / 0.02": (0.02, 0.02), "0.1 / 0.01": (0.1, 0.01)}


def scenes() -> dict:
    interface = two_layer_scene(6, (2, 2), bottom="fixed", stiffness=(2.0, 1.0), density=(1.0, 1.0),
                                interface={"kind": "frictional", "friction": 1.0, "states": "slip+"})
    return {"two_layers.toml": meicp.load_scene(ROOT / "data" / "scenes" / "two_layers.toml"),
            "6 × 4 frictional interface": interface}


def with_viscosity(scene, eta):
    """The scene with viscosity ``eta`` (one per layer; zeros: the undamped scene itself)."""
    if not any(eta):
        return scene
    data = scene.to_dict()
    for layer, value in zip(data["layers"], eta):
        layer["viscosity"] = value
    return scene_from_dict(data)


def run(args) -> None:
    import time

    rows = []
    for name, scene in scenes().items():
        for label, eta in ETAS.items():
            base = with_viscosity(scene, eta)
            for mu in np.linspace(args.mu_min, args.mu_max, args.points):
                t0 = time.perf_counter()
                r = meicp.analyze(base.with_friction(float(mu)))
                g = r.flutter_growth
                rows.append({"scene": name, "eta": label, "mu": f"{mu:.4f}", "divergence": r.divergence,
                             "divergence_growth": f"{r.modes[0].growth_rate:.8g}" if r.modes else "",
                             "flutter": r.flutter, "flutter_lower": "" if g is None else f"{g.lower:.8g}",
                             "flutter_upper": "" if g is None or g.upper is None else f"{g.upper:.8g}",
                             "flutter_exact": bool(g is not None and g.exact),
                             "seconds": f"{time.perf_counter() - t0:.3f}"})
            print(name, label, "done", flush=True)
    write_rows(csv_path("damping_growth"), rows, FIELDS, keep=lambda row: False)


def _growth(rows, verdict: str, value: str) -> np.ndarray:
    """Growth per row: the certified value, 0 where proved absent, NaN where undecided."""
    out = []
    for row in rows:
        flag = row[verdict]
        out.append(0.0 if flag == "False" else float(row[value]) if flag == "True" and row[value] else np.nan)
    return np.array(out)


def chart(args) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = read_rows(csv_path("damping_growth"))
    names = list(dict.fromkeys(r["scene"] for r in rows))
    fig, axes = plt.subplots(1, len(names), figsize=(6.2 * len(names), 4.6), squeeze=False)
    colours = dict(zip(ETAS, ("black", "tab:blue", "tab:orange")))
    for ax, name in zip(axes[0], names):
        for label in ETAS:
            part = [r for r in rows if r["scene"] == name and r["eta"] == label]
            mu = np.array([float(r["mu"]) for r in part])
            ax.plot(mu, _growth(part, "flutter", "flutter_lower"), "-", color=colours[label],
                    label=f"flutter, η = {label}")
            ax.plot(mu, _growth(part, "divergence", "divergence_growth"), "--", color=colours[label],
                    label=f"divergence, η = {label}")
            flutters = [float(r["mu"]) for r in part if r["flutter"] == "True"]
            if flutters:
                ax.axvline(min(flutters), color=colours[label], ls=":", lw=1)
        ax.set_title(f"{name}: fastest growth Re λ against μ\n(dotted: first μ of the grid with certified flutter)",
                     fontsize=9)
        ax.set_xlabel("friction coefficient μ")
        ax.set_ylabel("growth rate Re λ (0: proved absent)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    save_figure(fig, csv_path("damping_growth").with_suffix(".png"))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="what", required=True)
    r = sub.add_parser("run")
    r.add_argument("--mu-min", type=float, default=0.05)
    r.add_argument("--mu-max", type=float, default=3.0)
    r.add_argument("--points", type=int, default=60)
    sub.add_parser("chart")
    args = p.parse_args()
    globals()[args.what](args)


if __name__ == "__main__":
    main()
