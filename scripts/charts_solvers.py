"""Charts of the solver benchmarks: the LCP solvers against Siconos (``bench_lcp.py``), the
EiCP solvers (``bench_eicp.py``), speed against accuracy (``bench_tradeoff.py``) and the
failure map (``bench_failure.py``).  Drawn by ``scripts/charts.py NAME CSV``."""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from bench_common import read_rows, save_figure  # noqa: E402


def chart_lcp(path):
    rows = read_rows(path)
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
    save_figure(fig, f"{out}_time.png", dpi=110)
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
    save_figure(fig, f"{out}_siconos.png", dpi=110)
    print(f"wrote {out}_time.png, {out}_siconos.png")


def chart_eicp(path):
    rows = read_rows(path)
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
    save_figure(fig, f"{out}.png", dpi=110)
    print(f"wrote {out}.png")


# --- speed against accuracy (bench_tradeoff.py) ---

def chart_tradeoff(path):
    """Speed against accuracy (scripts/bench_tradeoff.py): per problem family (row) and size
    (column) a log-log panel of wall time against error — LCP ‖x − x_ref‖∞/‖x_ref‖∞, EiCP
    relative λ error — one colour and marker per method (its tolerance sweep joined by a thin
    line), the Pareto front over the solved runs of all methods as a black step line, runs
    that did not solve as hollow markers above the dashed line at the top edge (never dropped),
    and certified "solutions" outside the enumerated set ringed in red (not on the front).  Writes tradeoff_lcp.png, tradeoff_eicp.png and, with the certificate
    residual on the y axis, tradeoff_lcp_residual.png and tradeoff_eicp_residual.png."""
    import numpy as np

    rows = read_rows(path)
    out = Path(path).with_suffix("")
    floor, fail_y, top = 1e-17, 10.0, 80.0
    order = {"lcp": ["lemke", "enumerate", "pgs", "newton", "tao", "auto", "siconos-lemke", "siconos-enum",
                     "siconos-newton-fb", "siconos-pgs"],
             "eicp": ["enumerate", "active-set", "rayleigh", "semismooth", "semismooth-ssls"]}
    titles = {"condensed": "dense contact-like SPD (condensed grid)", "lattice": "sparse SPD (lattice K, y DOFs)",
              "laplacian": "sparse SPD (2-D Laplacian)", "random_sym": "random symmetric mixed",
              "friction": "nonsymmetric friction MEiCP (slip+)"}
    colours = dict(zip(order["lcp"], plt.get_cmap("tab10").colors))
    eicp_colours = dict(zip(order["eicp"], ["C1", "C0", "C4", "C2", "C9"]))

    def style(method, kind):
        marker = "^" if method.startswith("siconos") else ("s" if method.endswith("ssls") else "o")
        return (eicp_colours if kind == "eicp" else colours).get(method, "k"), marker

    def value(r, col):
        try:
            v = float(r[col])
        except (TypeError, ValueError):
            return None
        return max(v, floor) if np.isfinite(v) else None

    for kind in ("lcp", "eicp"):
        sel = [r for r in rows if r["kind"] == kind]
        if not sel:
            continue
        families = [f for f in dict.fromkeys(r["family"] for r in sel)]
        sizes = {f: sorted({(int(r["n"]), r["problem"]) for r in sel if r["family"] == f}) for f in families}
        ncol = max(len(v) for v in sizes.values())
        for ycol, ylabel, suffix in (("error", {"lcp": "‖x − x_ref‖∞ / ‖x_ref‖∞",
                                               "eicp": "relative λ error (max over returned solutions)"}[kind], ""),
                                     ("residual", "certificate residual", "_residual")):
            fig, axes = plt.subplots(len(families), ncol, figsize=(4.3 * ncol, 3.9 * len(families) + 0.9),
                                     squeeze=False)
            seen = {}
            for i, family in enumerate(families):
                for j in range(ncol):
                    ax = axes[i][j]
                    if j >= len(sizes[family]):
                        ax.axis("off")
                        continue
                    n, problem = sizes[family][j]
                    pts = [r for r in sel if r["problem"] == problem and r["wall_s"]]
                    front = []
                    for method in order[kind] + sorted({r["method"] for r in pts} - set(order[kind])):
                        mine = sorted((r for r in pts if r["method"] == method), key=lambda r: -float(r["tol"]))
                        if not mine:
                            continue
                        colour, marker = style(method, kind)
                        ok = [(float(r["wall_s"]), value(r, ycol)) for r in mine
                              if r["status"] == "solved" and value(r, ycol) is not None]
                        bad = [float(r["wall_s"]) for r in mine if r["status"] != "solved"]
                        wrong = [(float(r["wall_s"]), value(r, ycol)) for r in mine
                                 if r["status"] == "solved" and r.get("wrong") not in (None, "", "0")
                                 and value(r, ycol) is not None]
                        if ok:
                            xs, ys = zip(*ok)
                            h, = ax.plot(xs, ys, marker=marker, color=colour, ls="-", lw=0.7, ms=6, alpha=0.85)
                            seen.setdefault(method, h)
                            front += [(x, y) for (x, y), r in zip(ok, [r for r in mine if r["status"] == "solved"
                                                                       and value(r, ycol) is not None])
                                      if r.get("wrong") in (None, "", "0")]
                        if bad:
                            ax.scatter(bad, [fail_y] * len(bad), marker=marker, facecolors="none",
                                       edgecolors=colour, linewidths=1.3, s=42, zorder=3)
                            seen.setdefault(method, matplotlib.lines.Line2D([], [], marker=marker, color=colour,
                                                                            lw=0.7, ms=6))
                        if wrong:
                            ax.scatter(*zip(*wrong), s=140, facecolors="none", edgecolors="red", linewidths=1.2,
                                       zorder=4)
                            seen.setdefault("certified, not in the enumerated set", ax.scatter(
                                [], [], s=140, facecolors="none", edgecolors="red", linewidths=1.2))
                    # Pareto front: non-dominated (time, error) points over all methods
                    front.sort()
                    pareto, best = [], np.inf
                    for x, y in front:
                        if y < best:
                            pareto.append((x, y))
                            best = y
                    if pareto:
                        xs, ys = zip(*pareto)
                        xs, ys = list(xs), list(ys)
                        xmax = max(float(r["wall_s"]) for r in pts) * 3
                        h, = ax.step(xs + [xmax], ys + [ys[-1]], where="post", color="k", lw=1.6, alpha=0.8,
                                     zorder=2)
                        seen.setdefault("Pareto front (solved runs)", h)
                    ax.axhline(3.0, color="0.6", lw=0.8, ls="--")
                    ax.text(0.99, 2.2, "not solved ↑ (hollow)", transform=ax.get_yaxis_transform(), fontsize=7,
                            ha="right", va="top", color="0.4")
                    ax.axhspan(1e-18, 1e-16, color="0.92", zorder=0)
                    ax.set(xscale="log", yscale="log", ylim=(3e-18, top))
                    ax.grid(True, which="major", alpha=0.3)
                    J = next(r["J"] for r in pts) if pts else ""
                    extra = f", |J| = {J}" if kind == "eicp" else ""
                    skipped = sorted({r["method"] for r in sel if r["problem"] == problem and not r["wall_s"]})
                    ax.set_title(f"{titles.get(family, family)}\nn = {n}{extra}", fontsize=9)
                    if skipped:
                        ax.text(0.99, 0.02, "some tols not run: " + ", ".join(skipped), transform=ax.transAxes,
                                fontsize=6.5, ha="right", va="bottom", color="0.35")
                    if i == len(families) - 1 or j >= len(sizes[families[-1]]):
                        ax.set_xlabel("wall time, median [s]")
                    if j == 0:
                        ax.set_ylabel(ylabel + (" (floor 1e-17)" if ycol == "error" else ""), fontsize=8)
            what = {"lcp": "LCP: speed against accuracy", "eicp": "EiCP / MEiCP: speed against accuracy"}[kind]
            fig.suptitle(f"{what} — each method's tolerance sweep 1e-2 … 1e-14; grey band: below 1e-16; "
                         "1 rank, 2-core shared machine", fontsize=10)
            fig.legend(list(seen.values()), list(seen), loc="lower center", ncol=min(6, len(seen)), fontsize=8,
                       frameon=False)
            fig.tight_layout(rect=(0, 0.55 / (3.9 * len(families) + 0.9), 1, 0.97))
            name = f"{out}_{kind}{suffix}.png"
            fig.savefig(name, dpi=100)
            plt.close(fig)
            print(f"wrote {name}")


# --- failure map (bench_failure.py) ---

FAILURE_COLOURS = {"correct": "#2ca02c", "wrong": "#d62728", "failed": "#ff7f0e", "none_reported": "#1f77b4",
                   "na": "#c7c7c7"}
FAILURE_LABELS = {"correct": "correct", "wrong": "wrong answer",
                  "failed": "failure status (a solution exists)",
                  "none_reported": "failure status / no answer (none exists: honest, no proof)",
                  "na": "refused: not applicable (clear error)"}
FAILURE_PANELS = [
    ("mu", "two_layers", "1. friction μ across μ_c = 1.906 (two_layers, every base node slip+)", "μ"),
    ("contrast", "two_layers", "2. stiffness contrast (two_layers, μ = 3)", "k_B / k_A"),
    ("degenerate", "z_family", "3a. Z-family n = 8: δ = 0 gives repeated eigenvalues", "δ"),
    ("degenerate", "twin", "3b. mirror twins: 2nd copy at μ = 3(1 + δ), δ = 0 double σ", "δ"),
    ("flutter", "mode_coupling", "4a. mode coupling: real σ pair turns complex past γ ≈ 0.5", "γ"),
    ("flutter", "sheared", "4b. sheared lattice, stick/slip+/stick: complex σ, no real σ ≥ 0", "μ"),
    ("lcp", "compression", "5a. static slip LCP, compressive load (q < 0)", "μ"),
    ("lcp", "lift", "5b. static slip LCP, lifting load (q > 0)", "μ"),
]


def _failure_family(r):
    if r["sweep"] == "lcp":
        return r["settings"].split("=", 1)[1]
    return r["problem"].split(" ")[0]


def chart_failure(path):
    """Failure map: per sweep a grid of methods × parameter points coloured by outcome, with a
    reference row (what the independent reference says at that point)."""
    from matplotlib.patches import Patch

    rows = read_rows(path)
    out = Path(path).with_suffix("")
    panels = [p for p in FAILURE_PANELS if any(r["sweep"] == p[0] and _failure_family(r) == p[1] for r in rows)]
    if not panels:
        return
    ncols = 2
    nrows = (len(panels) + 1) // 2
    fig, axes = plt.subplots(nrows, ncols, figsize=(17, 3.6 * nrows + 1.0), squeeze=False)
    for ax in axes.flat[len(panels):]:
        ax.axis("off")
    for ax, (sweep, family, title, xlabel) in zip(axes.flat, panels):
        sel = [r for r in rows if r["sweep"] == sweep and _failure_family(r) == family]
        params = sorted({r["param"] for r in sel}, key=float)
        methods = list(dict.fromkeys(r["method"] for r in sel))
        ref = {r["param"]: (r["reference"], r["classes"]) for r in sel}
        ref_settings = {r["param"]: r["settings"] for r in sel}
        grid = {(r["method"], r["param"]): r["outcome"] for r in sel}
        for i, m in enumerate(methods):
            for j, p in enumerate(params):
                o = grid.get((m, p))
                if o is not None:
                    ax.add_patch(plt.Rectangle((j, len(methods) - 1 - i), 0.96, 0.9, color=FAILURE_COLOURS[o]))
        # reference row on top: what exists at this point
        top = len(methods)
        for j, p in enumerate(params):
            text, classes = ref[p]
            if sweep == "lcp":
                label = text.split(" ")[0] + " sol"
                colour = "#f2f2f2" if label.startswith("0") else "#d9f0d3"
                if "P=True" in classes:
                    label += "\nP"
                elif "Q=False" in classes:
                    label += "\nnot Q"
            else:
                exists = not text.startswith("none")
                cplx = "complex" in text or (classes.startswith("max|Im sigma|=")
                                             and float(classes.split("=")[1].split(";")[0]) > 1e-8)
                label = (("σ≥0" if "lam_min=0" in ref_settings[p] else "sol.") if exists else "none") \
                    + ("\ncplx" if cplx else "")
                colour = "#d9f0d3" if exists else ("#e5d8f0" if cplx else "#f2f2f2")
            ax.add_patch(plt.Rectangle((j, top + 0.1), 0.96, 1.1, color=colour))
            ax.text(j + 0.48, top + 0.65, label, ha="center", va="center", fontsize=6.5)
        ax.set_xlim(0, len(params))
        ax.set_ylim(0, top + 1.25)
        ax.set_yticks([i + 0.45 for i in range(len(methods))] + [top + 0.65])
        ax.set_yticklabels(methods[::-1] + ["reference"], fontsize=8)
        ax.set_xticks([j + 0.48 for j in range(len(params))])
        ax.set_xticklabels([f"{float(p):.8g}" for p in params], rotation=45, ha="right", fontsize=7)
        ax.set_xlabel(xlabel + " (one column per point, not to scale)", fontsize=8)
        ax.set_title(title, fontsize=9.5)
        ax.tick_params(length=0)
        for s in ax.spines.values():
            s.set_visible(False)
    handles = [Patch(color=c, label=FAILURE_LABELS[k]) for k, c in FAILURE_COLOURS.items()]
    handles += [Patch(color="#d9f0d3", label="reference: a real σ ≥ 0 mode / LCP solution exists"),
                Patch(color="#e5d8f0", label="reference: no real σ ≥ 0, complex σ (flutter)"),
                Patch(color="#f2f2f2", label="reference: none exists")]
    fig.legend(handles=handles, loc="lower center", ncol=4, fontsize=8.5, frameon=False)
    fig.suptitle("Failure map: each method's outcome against an independent brute-force / analytic reference",
                 fontsize=12)
    save_figure(fig, f"{out}.png", dpi=110, rect=(0, 0.06, 1, 0.97))
    print(f"wrote {out}.png")
