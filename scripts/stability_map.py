"""Stability map of a shipped scene: growth rates of divergence and of flutter against μ.

    .venv/bin/python scripts/stability_map.py [data/scenes/two_layers.toml] [--mu-max 6] [--steps 61]

For each μ (the base's and every frictional interface's friction set to μ, states as the
scene says) one ``meicp.analyze``: the divergence verdict and the growth rate √σ of the
fastest divergence mode, the flutter verdict and the growth rate Re √σ (and frequency) of
the fastest flutter mode (docs/flutter.md).  Then both onsets from ``meicp.critical_friction``:
μ_c (divergence) and μ_f, the smallest μ with flutter, a certified bracket (an interval cover
from μ = 0 and a certified mode: docs/critical-friction.md, "The flutter onset").  Writes ``stability_map.csv`` and ``stability_map.png``
into ``docs/benchmarks/`` (``$MEICP_BENCH_DIR`` overrides).
"""

from __future__ import annotations

import argparse
import json

import numpy as np

import meicp
from bench_common import ROOT, csv_path, out_dir, write_rows
from meicp.examples import with_friction

FIELDS = ["mu", "divergence", "divergence_growth", "flutter", "flutter_growth", "flutter_frequency",
          "flutter_sigma_real", "flutter_sigma_imag", "flutter_modes", "stable"]


def point(scene, mu: float) -> dict:
    r = meicp.analyze(with_friction(scene, mu))
    fast = r.flutter_modes[0] if r.flutter_modes else None
    return {"mu": f"{mu:.6g}", "divergence": r.divergence, "divergence_growth": r.modes[0].growth_rate if r.modes else 0.0,
            "flutter": r.flutter, "flutter_growth": fast.growth_rate if fast else 0.0,
            "flutter_frequency": fast.frequency if fast else "", "flutter_sigma_real": fast.sigma.real if fast else "",
            "flutter_sigma_imag": fast.sigma.imag if fast else "", "flutter_modes": len(r.flutter_modes),
            "stable": r.stable}


def chart(rows: list, extra: dict, path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    mu = np.array([float(r["mu"]) for r in rows])
    div = np.array([float(r["divergence_growth"]) for r in rows])
    flu = np.array([float(r["flutter_growth"]) for r in rows])
    fig, ax = plt.subplots(figsize=(8, 4.8))
    ax.plot(mu, div, "o-", ms=3, label="divergence: growth rate √σ of the fastest mode (real σ ≥ 0)")
    ax.plot(mu, flu, "s-", ms=3, label="flutter: growth rate Re √σ of the fastest mode (complex σ)")
    undecided = [float(r["mu"]) for r in rows if r["flutter"] is None or r["divergence"] is None]
    if undecided:
        ax.plot(undecided, np.zeros(len(undecided)), "kx", label="a verdict undecided")
    if extra.get("mu_c") is not None:
        ax.axvline(extra["mu_c"], color="C0", ls=":", lw=1, label=f"μ_c = {extra['mu_c']:.4g} (critical_friction)")
    if extra.get("mu_flutter") is not None:
        ax.axvline(extra["mu_flutter"], color="C1", ls=":", lw=1, label=f"flutter from μ_f ≈ {extra['mu_flutter']:.4g} "
                                                                          "(critical_friction)")
    ax.set_xlabel("friction coefficient μ")
    ax.set_ylabel("growth rate (1/time)")
    ax.set_title(f"{extra['scene']}: stability of steady sliding against μ", fontsize=10)
    ax.legend(fontsize=8, loc="upper left")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=130)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", nargs="?", default=str(ROOT / "data" / "scenes" / "two_layers.toml"))
    ap.add_argument("--mu-max", type=float, default=6.0)
    ap.add_argument("--steps", type=int, default=61)
    args = ap.parse_args()
    scene = meicp.load_scene(args.scene)
    rows = [point(scene, float(mu)) for mu in np.linspace(0.0, args.mu_max, args.steps)]
    onsets = meicp.critical_friction(scene)
    mu_c, flutter = onsets.divergence.upper, onsets.flutter
    bracket = {"lower": flutter.lower, "upper": flutter.upper, "exact": flutter.exact, "note": flutter.evidence}
    extra = {"scene": args.scene.split("/")[-1], "mu_c": mu_c if np.isfinite(mu_c) else None,
             "mu_flutter": flutter.upper if np.isfinite(flutter.upper) else None, "bracket": bracket,
             "first": onsets.first}
    write_rows(csv_path("stability_map"), rows, FIELDS, keep=lambda r: False)
    chart(rows, extra, out_dir() / "stability_map.png")
    print(json.dumps(extra, indent=1))
    for r in rows[::5]:
        print(r)


if __name__ == "__main__":
    main()
