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
    fig, axes = plt.subplots(1, 3, figsize=(19, 5))
    for ax, family in zip(axes, ("condensed", "laplacian", "lattice")):
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
                      "laplacian": "sparse SPD (2-D Laplacian + 0.05 I)",
                      "lattice": "elastic lattice K on vertical DOFs, sparse SPD"}[family])
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


def chart_assembly(path):
    """Assembly of K and M (scripts/bench_assembly.py): time vs DOFs, log-log, median and
    min-max of the repeats per (method, ranks), a linear reference line and the 10^6-DOF
    targets; and peak memory during assembly / matrix storage (largest over ranks)."""
    import numpy as np

    rows = [r for r in read(path) if r["status"] == "ok"]
    times, ratio = defaultdict(lambda: defaultdict(list)), defaultdict(dict)
    for r in rows:
        key, d = (r["method"], int(r["ranks"])), int(r["dofs"])
        times[key][d].append(float(r["wall_s"]))
        ratio[key][d] = max(ratio[key].get(d, 0.0), float(r["rank_ratio"]))
    styles = {("scipy", 1): ("C0", "o", "SciPy CSR, 1 rank"), ("petsc", 1): ("C1", "s", "PETSc AIJ, 1 rank"),
              ("petsc", 2): ("C2", "^", "PETSc MPIAIJ, 2 ranks")}
    fig, (ax, mx) = plt.subplots(1, 2, figsize=(12, 4.8))
    for key in sorted(times, key=lambda k: (k[1], k[0])):
        colour, marker, label = styles.get(key, ("C3", "x", f"{key[0]}, {key[1]} ranks"))
        dofs = np.array(sorted(times[key]))
        t = [np.array(times[key][d]) for d in dofs]
        med = np.array([np.median(x) for x in t])
        err = [med - [x.min() for x in t], [x.max() for x in t] - med]
        ax.errorbar(dofs, med, yerr=err, color=colour, marker=marker, capsize=3, label=label)
        mx.plot(dofs, [ratio[key][d] for d in dofs], color=colour, marker=marker, label=label)
    ref = ("petsc", 1) if ("petsc", 1) in times else next(iter(times))
    d_ref = max(times[ref])
    t_ref = float(np.median(times[ref][d_ref]))
    xs = np.array([8e3, 1.3e6])
    ax.plot(xs, t_ref * xs / d_ref, color="0.5", ls="--", lw=1, label="linear in DOFs (through PETSc 1 rank, 10^6)")
    for level, colour, text, dy in ((5, "C1", "target 1 rank: 5 s", 1.08), (3, "C2", "target 2 ranks: 3 s", 0.75)):
        ax.plot([6e5, 1.6e6], [level, level], color=colour, lw=2, ls=":")
        ax.text(6e5, level * dy, text, color=colour, fontsize=8)
    ax.set(xscale="log", yscale="log", xlabel="DOFs", ylabel="wall time of K and M [s] (median, min-max)",
           title="Assembly time, two-layer lattice")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    mx.axhline(2.0, color="k", ls=":", lw=1.5, label="target: 2x matrix storage")
    top = max(max(v.values()) for v in ratio.values())
    mx.set(xscale="log", ylim=(0, max(2.5, 1.1 * top)), xlabel="DOFs",
           ylabel="peak RSS above start / matrix storage", title="Assembly memory (largest over ranks)")
    mx.grid(True, which="both", alpha=0.3)
    mx.legend(fontsize=8)
    fig.tight_layout()
    out = Path(path).with_suffix(".png")
    fig.savefig(out, dpi=120)
    plt.close(fig)
    print(f"wrote {out}")


def chart_eicp(path):
    rows = read(path)
    out = Path(path).with_suffix("")
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.8))
    # 1. enumeration of the Z-family: all 2^n − 1 solutions
    ax = axes[0]
    for ranks in ("1", "2"):
        pts = sorted((int(r["n"]), float(r["wall_s"])) for r in rows
                     if r["experiment"] == "enumerate" and r["ranks"] == ranks)
        if pts:
            ax.semilogy(*zip(*pts), marker="o", label=f"{ranks} rank(s)")
    ax.axhline(10, ls=":", c="grey")
    ax.axhline(120, ls="--", c="grey")
    ax.set_xlabel("n (Z-family, 2^n − 1 solutions)")
    ax.set_ylabel("wall time [s]")
    ax.set_title("enumeration of every solution (targets: 10 s at 16, 2 min at 20)", fontsize=9)
    ax.legend()
    ax.grid(True, which="both", alpha=0.3)
    # 2. active-set against one SLEPc solve of the same 10^6-DOF pencil
    ax = axes[1]
    lat = [r for r in rows if r["experiment"] == "lattice"]
    labels, single, active = [], [], []
    for key in sorted({(r["settings"].split()[0], r["ranks"]) for r in lat}):
        pick = {r["method"]: float(r["wall_s"]) for r in lat if (r["settings"].split()[0], r["ranks"]) == key}
        if {"single-slepc-solve", "active-set"} <= set(pick):
            labels.append(f"{key[0]}\n{key[1]} rank(s)")
            single.append(pick["single-slepc-solve"])
            active.append(pick["active-set"])
    x = range(len(labels))
    ax.bar([i - 0.2 for i in x], single, 0.4, label="one SLEPc solve")
    ax.bar([i + 0.2 for i in x], active, 0.4, label="active-set (whole MEiCP)")
    for i in x:
        ax.text(i + 0.2, active[i], f"{active[i] / single[i]:.2f}×", ha="center", va="bottom", fontsize=8)
    ax.set_xticks(list(x), labels, fontsize=8)
    ax.set_ylabel("wall time [s]")
    ax.set_title("10^6-DOF lattice pencil: MEiCP vs one eigen-solve", fontsize=9)
    ax.legend(fontsize=8)
    # 3. accuracy: eigenvalue error against the dense reference
    ax = axes[2]
    for method, marker in (("enumerate", "o"), ("active-set", "s")):
        pts = [(float(r["wall_s"]), max(float(r["error"]), 1e-17)) for r in rows
               if r["experiment"] == "accuracy" and r["method"] == method and r["error"]]
        if pts:
            ax.loglog(*zip(*pts), marker, label=method, alpha=0.7)
    ax.axhline(1e-10, ls="--", c="grey")
    ax.set_xlabel("wall time [s]")
    ax.set_ylabel("relative λ error vs dense reference")
    ax.set_title("time against accuracy, random mixed symmetric problems", fontsize=9)
    ax.legend()
    fig.tight_layout()
    fig.savefig(f"{out}.png", dpi=110)
    plt.close(fig)
    print(f"wrote {out}.png")


CHARTS = {"lcp": chart_lcp, "assembly": chart_assembly, "eicp": chart_eicp}

if __name__ == "__main__":
    if len(sys.argv) != 3 or sys.argv[1] not in CHARTS:
        sys.exit(f"usage: charts.py {{{','.join(CHARTS)}}} CSV")
    CHARTS[sys.argv[1]](sys.argv[2])
