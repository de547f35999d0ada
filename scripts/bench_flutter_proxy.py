#!/usr/bin/env python3
"""How close the flutter search's fastest mode comes to the fastest one, on frictional
interfaces small enough for QZ: the search from the interface-strip proxy's targets against
the search from the λ-line's targets (the only ones before the proxy), as a fraction of QZ's
fastest growth (docs/flutter.md, "Targets").

    .venv/bin/python scripts/bench_flutter_proxy.py          # -> flutter_proxy.csv, .png
    .venv/bin/python scripts/bench_flutter_proxy.py depth    # -> flutter_depth.csv, .png

Scenes: two layers with an unbonded frictional interface (k = 1 under k = 6 or 2, ρ 1 / 2),
bottom and top fixed, every pair in one slip state.  ``depth``: shallow lattices on a rough
base (three layers k 1 / 3 / 1, ρ 1 / 1 / 2, 6 rows each, issue 29's; two layers k 1 / 5),
every base node in one slip state, and the interface scenes above with more than 8 rows: the
search from the strip proxy's targets alone against the search with the whole-depth proxy's
targets too.
"""

from __future__ import annotations

import time

import sys

import meicp  # before NumPy: it sets OpenBLAS's kernel for this CPU (meicp.core.blas_kernel)
import numpy as np

from bench_common import csv_path, save_figure, write_rows
from meicp.contact import flutter as fl
from meicp.contact.problem import pencil
from meicp.contact.result import growth_frequency
from meicp.examples import two_layer_scene
from meicp.io.scene import scene_from_dict

FIELDS = ["nx", "rows", "k_upper", "mu", "state", "retained", "qz_growth", "proxy_growth", "line_growth",
          "proxy_fraction", "line_fraction", "qz_s", "proxy_s", "line_s"]
CASES = [(48, 5, 6, 1.0, "slip+"), (64, 4, 6, 1.0, "slip-"), (64, 6, 2, 2.0, "slip+"), (80, 4, 6, 0.3, "slip+"),
         (40, 8, 6, 1.0, "slip+"), (60, 6, 2, 5.0, "slip-"), (150, 6, 6, 1.0, "slip+")]


DEPTH_FIELDS = ["scene", "nx", "rows", "mu", "state", "shear", "k_upper", "retained", "qz_growth", "strip_growth", "depth_growth",
                "strip_fraction", "depth_fraction", "qz_s", "strip_s", "depth_s"]
#: (label, nx, rows of each layer, μ, state, shear — for an interface, "itf", the upper layer's k)
DEPTH_CASES = [("three", 40, (6, 6, 6), 0.3, "slip-", 0.4), ("three", 48, (6, 6, 6), 0.3, "slip-", 0.4),
               ("three", 64, (6, 6, 6), 0.3, "slip-", 0.4), ("three", 100, (6, 6, 6), 0.3, "slip-", 0.4),
               ("two", 80, (6, 6), 1.0, "slip+", 0.0), ("two", 100, (5, 5), 2.0, "slip-", -0.3),
               ("two", 60, (8, 8), 0.5, "slip+", 0.5), ("three", 80, (4, 6, 4), 1.0, "slip+", 0.0),
               *(("itf", nx, (ny, ny), mu, state, k) for nx, ny, k, mu, state in CASES if 8 < 2 * ny)]


def _shallow(label, nx, rows, mu, state, shear):
    if label == "two":
        return two_layer_scene(nx, rows, mu=mu, states=state, shear=shear)
    if label == "itf":
        return two_layer_scene(nx, rows, bottom="fixed", stiffness=(1.0, float(shear)),
                               interface={"kind": "frictional", "friction": mu, "states": state})
    return scene_from_dict({"lattice": {"nx": nx, "spacing": 1.0, "shear": shear},
                            "layers": [{"name": n, "rows": r, "stiffness": k, "density": d}
                                       for n, r, k, d in zip("ABC", rows, (1.0, 3.0, 1.0), (1.0, 1.0, 2.0))],
                            "boundary": {"top": "fixed", "bottom": "contact", "left": "free", "right": "free"},
                            "contact": {"friction": mu, "states": state}})


def depth():
    rows = []
    for label, nx, layers, mu, state, shear in DEPTH_CASES:
        scene = _shallow(label, nx, layers, mu, state, shear)
        with pencil(scene) as pen:
            out = {}
            strip = fl.proxy_targets(scene, pen.lines, fl.SEARCH_TARGETS, depth=False)
            for name, kw in (("qz", {"dense_max": 10**6}), ("strip", {"dense_max": 0, "targets": strip}),
                             ("depth", {"dense_max": 0})):
                t0 = time.perf_counter()
                out[name] = (_fastest(fl.pencil_flutter(pen, scene, **kw)), time.perf_counter() - t0)
            n = int(pen.maps.retained.size)
        qz = out["qz"][0]
        interface = label == "itf"
        rows.append(dict(scene=label, nx=nx, rows="+".join(map(str, layers)), mu=mu, state=state,
                         shear=0.0 if interface else shear, k_upper=shear if interface else "", retained=n, qz_growth=qz, strip_growth=out["strip"][0], depth_growth=out["depth"][0],
                         strip_fraction=out["strip"][0] / qz, depth_fraction=out["depth"][0] / qz,
                         qz_s=out["qz"][1], strip_s=out["strip"][1], depth_s=out["depth"][1]))
        print(rows[-1], flush=True)
    path = csv_path("flutter_depth")
    write_rows(path, rows, DEPTH_FIELDS, keep=lambda row: False)
    bars(rows, path.with_suffix(".png"), [("strip_fraction", "strip proxy targets (8 rows)"),
                                          ("depth_fraction", "with the whole-depth proxy's targets")],
         lambda r: f"{r['scene']} {r['nx']}×\n{r['rows']}\nμ{r['mu']:g} {r['state']}\n"
                   + (f"k {r['k_upper']:g}" if r["k_upper"] != "" else f"shear {r['shear']:+g}"),
         "flutter search on shallow lattices: fastest found vs the fastest (QZ)")


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
    bars(rows, path, [("proxy_fraction", "interface-strip proxy targets"), ("line_fraction", "λ-line targets")],
         lambda r: f"{r['nx']}×{2 * r['rows']}\nk{r['k_upper']} μ{r['mu']:g} {r['state']}",
         "flutter search on frictional interfaces: fastest found vs the fastest (QZ)")


def bars(rows, path, series, label, title):
    """Two bars per scene: ``series`` = [(column, legend)] × 2, ``label(row)`` the tick."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(1.15 * len(rows) + 1.5, 3.6))
    x = np.arange(len(rows))
    for shift, (column, legend) in zip((-0.2, 0.2), series):
        ax.bar(x + shift, [r[column] for r in rows], 0.4, label=legend)
    ax.set_xticks(x, [label(r) for r in rows], fontsize=7)
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_ylabel("fastest growth found / QZ's")
    ax.set_title(title, fontsize=9)
    ax.set_ylim(0, 1.25)
    ax.legend(fontsize=8, loc="upper left", ncol=2)
    save_figure(fig, path)


if __name__ == "__main__":
    depth() if sys.argv[1:] == ["depth"] else main()
