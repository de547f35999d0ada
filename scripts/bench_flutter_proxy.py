#!/usr/bin/env python3
"""How close the flutter search's fastest mode comes to the fastest one, on frictional
interfaces small enough for QZ: the search from the interface-strip proxy's targets against
the search from the λ-line's targets (the only ones before the proxy), as a fraction of QZ's
fastest growth (docs/flutter.md, "Targets").

    .venv/bin/python scripts/bench_flutter_proxy.py          # -> flutter_proxy.csv, .png

Scenes: two layers with an unbonded frictional interface (k = 1 under k = 6 or 2, ρ 1 / 2),
bottom and top fixed, every pair in one slip state.
"""

from __future__ import annotations

import time

import numpy as np

from bench_common import csv_path, save_figure, write_rows
from meicp.contact import flutter as fl
from meicp.contact.problem import pencil
from meicp.contact.result import growth_frequency
from meicp.examples import two_layer_scene

FIELDS = ["nx", "rows", "k_upper", "mu", "state", "retained", "qz_growth", "proxy_growth", "line_growth",
          "proxy_fraction", "line_fraction", "qz_s", "proxy_s", "line_s"]
CASES = [(48, 5, 6, 1.0, "slip+"), (64, 4, 6, 1.0, "slip-"), (64, 6, 2, 2.0, "slip+"), (80, 4, 6, 0.3, "slip+"),
         (40, 8, 6, 1.0, "slip+"), (60, 6, 2, 5.0, "slip-"), (150, 6, 6, 1.0, "slip+")]


def _fastest(found) -> float:
    return max([growth_frequency(m.sigma)[0] for m in found.modes] or [0.0])


def main():
    rows = []
    for nx, ny, k, mu, state in CASES:
        scene = two_layer_scene(nx, (ny, ny), bottom="fixed", stiffness=(1.0, float(k)),
                                interface={"kind": "frictional", "friction": mu, "states": state})
        with pencil(scene) as pen:
            out = {}
            for name, kw in (("qz", {"dense_max": 10**6}), ("proxy", {"dense_max": 0}),
                             ("line", {"dense_max": 0,
                                       "targets": fl.lambda_line_targets(0.05, np.linspace(0.5, 2.5, 3))})):
                t0 = time.perf_counter()
                out[name] = (_fastest(fl.pencil_flutter(pen, scene, **kw)), time.perf_counter() - t0)
            n = int(pen.maps.retained.size)
        qz = out["qz"][0]
        rows.append(dict(nx=nx, rows=ny, k_upper=k, mu=mu, state=state, retained=n, qz_growth=qz,
                         proxy_growth=out["proxy"][0], line_growth=out["line"][0],
                         proxy_fraction=out["proxy"][0] / qz, line_fraction=out["line"][0] / qz,
                         qz_s=out["qz"][1], proxy_s=out["proxy"][1], line_s=out["line"][1]))
        print(rows[-1], flush=True)
    path = csv_path("flutter_proxy")
    write_rows(path, rows, FIELDS, keep=lambda row: False)
    chart(rows, path.with_suffix(".png"))


def chart(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7.5, 3.6))
    x = np.arange(len(rows))
    ax.bar(x - 0.2, [r["proxy_fraction"] for r in rows], 0.4, label="interface-strip proxy targets")
    ax.bar(x + 0.2, [r["line_fraction"] for r in rows], 0.4, label="λ-line targets")
    ax.set_xticks(x, [f"{r['nx']}×{2 * r['rows']}\nk{r['k_upper']} μ{r['mu']:g} {r['state']}" for r in rows],
                  fontsize=7)
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_ylabel("fastest growth found / QZ's")
    ax.set_title("flutter search on frictional interfaces: fastest found vs the fastest (QZ)", fontsize=9)
    ax.legend(fontsize=8)
    save_figure(fig, path)


if __name__ == "__main__":
    main()
