#!/usr/bin/env python3
"""Charts from the benchmark CSVs (DESIGN §7).  One function per benchmark:

    .venv/bin/python scripts/charts.py lcp docs/benchmarks/lcp.csv
"""

from __future__ import annotations

import csv
import sys
from collections import defaultdict
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def chart_lcp(path):
    rows = read(path)
    out = Path(path).with_suffix("")
    # 1. time against n for the two scalable families, 1 and 2 ranks
    fig, axes = plt.subplots(1, 2, figsize=(13, 5))
    for ax, family in zip(axes, ("condensed", "laplacian")):
        series = defaultdict(list)
        for r in rows:
            if r["family"] == family and r["status"] == "solved":
                label = r["method"] + (f" ({r['ranks']} ranks)" if r["ranks"] != "1" else "")
                series[label].append((int(r["n"]), float(r["wall_s"])))
        colours = plt.get_cmap("tab20").colors
        for k, (label, pts) in enumerate(sorted(series.items())):
            pts.sort()
            style = "--" if label.startswith("siconos") else "-"
            ax.loglog(*zip(*pts), style, marker="o", label=label, color=colours[k % len(colours)])
        ax.set_xlabel("n (LCP size)")
        ax.set_ylabel("wall time, median [s]")
        ax.set_title({"condensed": "dense contact-like (condensed grid), SPD",
                      "laplacian": "sparse SPD (2-D Laplacian + 0.05 I)"}[family])
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(f"{out}_time.png", dpi=110)
    plt.close(fig)
    # 2. outcome per problem and method on the Siconos set
    sic = [r for r in rows if r["family"] == "siconos"]
    problems = sorted({r["problem"] for r in sic})
    methods = sorted({r["method"] for r in sic})
    code = {"solved": 2, "infeasible": 1}
    grid = [[-1] * len(methods) for _ in problems]
    for r in sic:
        grid[problems.index(r["problem"])][methods.index(r["method"])] = code.get(r["status"], 0)
    fig, ax = plt.subplots(figsize=(1.0 + 0.9 * len(methods), 0.35 * len(problems) + 1.5))
    cmap = matplotlib.colors.ListedColormap(["#eeeeee", "#d62728", "#1f77b4", "#2ca02c"])
    ax.imshow(grid, cmap=cmap, vmin=-1.5, vmax=2.5, aspect="auto")
    ax.set_xticks(range(len(methods)), methods, rotation=45, ha="right", fontsize=8)
    ax.set_yticks(range(len(problems)), problems, fontsize=8)
    ax.set_title("Siconos LCP set: green solved (certified), blue proved unsolvable, red failed, grey not run",
                 fontsize=8)
    fig.tight_layout()
    fig.savefig(f"{out}_siconos.png", dpi=110)
    plt.close(fig)
    print(f"wrote {out}_time.png, {out}_siconos.png")


CHARTS = {"lcp": chart_lcp}

if __name__ == "__main__":
    if len(sys.argv) != 3 or sys.argv[1] not in CHARTS:
        sys.exit(f"usage: charts.py {{{','.join(CHARTS)}}} CSV")
    CHARTS[sys.argv[1]](sys.argv[2])
