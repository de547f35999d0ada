"""Charts of the lattice benchmarks: assembly (``bench_assembly.py``), scaling with DOFs and
ranks (``bench_scaling.py``), resolution convergence and scene features
(``bench_resolution.py``) and the critical friction (``bench_critical_friction.py``).  Drawn
by ``scripts/charts.py NAME CSV``."""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from bench_common import read_rows, save_figure  # noqa: E402


def chart_assembly(path):
    """Assembly of K and M (scripts/bench_assembly.py): time vs DOFs, log-log, median and
    min-max of the repeats per (method, ranks), a linear reference line and the 10^6-DOF
    targets; and peak memory during assembly / matrix storage (largest over ranks)."""
    import numpy as np

    rows = [r for r in read_rows(path) if r["status"] == "ok"]
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


# --- scaling with DOFs and ranks, peers in the same run (bench_scaling.py) ---

def _scaling_slope(pts, min_x=9e4):
    """Least-squares slope of log y against log x over the points with x ≥ min_x (all
    points when fewer than two reach it); None with fewer than two points."""
    import numpy as np

    use = [p for p in pts if p[0] >= min_x]
    if len(use) < 2:
        use = pts
    if len(use) < 2:
        return None
    x, y = np.log10([p[0] for p in use]), np.log10([p[1] for p in use])
    return float(np.polyfit(x, y, 1)[0])


def chart_scaling(path):
    """Scaling (scripts/bench_scaling.py): time per stage against DOFs with the peers
    (scaling_time.png), peak memory per rank (scaling_memory.png), speedup and parallel
    efficiency 1 → 2 ranks (scaling_speedup.png), the multi-support family's active-set
    against one eigen-solve (scaling_activeset.png); log-log slopes fitted from 10^5 DOFs up."""
    rows = read_rows(path)
    out = Path(path).with_suffix("")
    ok = [r for r in rows if r["wall_s"] and r["status"].split()[0] in ("ok", "solved")]
    failed = [r for r in rows if r["wall_s"] and r not in ok]
    series = defaultdict(list)  # (stage, method, ranks) -> [(dofs, wall, mem)]
    for r in ok:
        mem = float(r["above_base_mb"]) if r["above_base_mb"] else None
        series[(r["stage"], r["method"], int(r["ranks"]))].append((int(r["dofs"]), float(r["wall_s"]), mem))
    for v in series.values():
        v.sort()
    pipeline = [("assemble", "meicp-scipy", "assembly K, M (SciPy)"), ("assemble", "meicp-petsc", "assembly K, M (PETSc)"),
                ("pencil", "meicp-scipy", "reduced pencil (SciPy)"), ("pencil", "meicp-petsc", "reduced pencil (PETSc)"),
                ("eigensolve", "slepc-krylovschur+mumps", "one eigen-solve, SLEPc + MUMPS"),
                ("meicp", "active-set", "MEiCP active-set (solve_eicp)"),
                ("analyze", "meicp-analyze", "analyze, end to end")]
    colour = {"assemble": "C0", "pencil": "C1", "eigensolve": "C2", "meicp": "C3", "analyze": "C4"}
    main = 1e4 * 0.9  # the lattice family proper starts at 10^4 DOFs; tiny lattices below

    def draw(ax, key, label, c, ls, marker, idx=1, min_x=9e4, lo=main):
        pts = [(p[0], p[idx]) for p in series.get(key, []) if p[0] >= lo and p[idx]]
        if not pts:
            return
        s = _scaling_slope(pts, min_x)
        lab = label + (f" ({key[2]} rank{'s' if key[2] > 1 else ''})") + (f", slope {s:.2f}" if s is not None else "")
        ax.loglog(*zip(*pts), ls=ls, marker=marker, color=c, label=lab, ms=5)

    # 1. time
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(17, 8.5))
    for stage, method, label in pipeline:
        for ranks, ls, mk in ((1, "-", "o"), (2, "--", "s")):
            draw(ax, (stage, method, ranks), label, colour[stage], ls, mk)
    draw(ax, ("eigensolve", "arpack+superlu", 1), "peer: one eigen-solve, SciPy ARPACK + SuperLU", "k", ":", "D")
    for ranks, mk in ((1, "o"), (2, "s")):  # of which: MUMPS analysis + factorisation (EPSSetUp)
        pts = sorted((int(r["dofs"]), float(r["setup_s"])) for r in ok if r.get("setup_s") and r["stage"] == "eigensolve"
                     and r["ranks"] == str(ranks) and int(r["dofs"]) >= main)
        if pts:
            s = _scaling_slope(pts)
            ax.loglog(*zip(*pts), ls=":", marker=mk, mfc="none", color="C2", ms=5,
                      label=f"  of which MUMPS analysis + factorisation ({ranks} rank{'s' if ranks > 1 else ''})"
                            + (f", slope {s:.2f}" if s is not None else ""))
    ax.set(xlabel="DOFs of the lattice", ylabel="wall time, median [s]",
           title="two-layer lattice on a sliding base (μ = 2): time per stage\n"
                 "solid 1 rank, dashed 2 ranks; slopes = log-log fit from 10^5 DOFs up")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7.5, loc="upper center", bbox_to_anchor=(0.5, -0.09), ncol=2)
    # peers of the MEiCP and the LCP
    for ranks, ls, mk in ((1, "-", "o"), (2, "--", "s")):
        draw(bx, ("meicp", "enumerate", ranks), "MEiCP dense enumeration (2^nx supports)", "C5", ls, mk,
             min_x=0, lo=0)
    draw(bx, ("meicp", "active-set", 1), "MEiCP active-set", "C3", "-", "o", lo=0)
    draw(bx, ("static", "meicp-condensed", 1), "static LCP: condensation + Lemke + states (meicp)", "C6", "-", "^",
         min_x=0)
    draw(bx, ("lcp", "meicp-lemke", 1), "static LCP, Lemke: meicp", "C7", "-", "v", min_x=0)
    draw(bx, ("lcp", "siconos-lemke", 1), "static LCP, Lemke: Siconos (peer)", "k", ":", "D", min_x=0)
    for k, r in enumerate(failed):
        bx.loglog(int(r["dofs"]), float(r["wall_s"]), "x", color="red", ms=10, mew=2,
                  label=f"failed: {r['method']} ({r['status']})" if k < 3 else None)
    notrun = sorted({f"{r['method']} at {int(r['dofs']):.0e} DOFs: {r['status']}" for r in rows
                     if r["status"].startswith("not run") and r["ranks"] == "1" and r["method"] != "enumerate"})
    if notrun:
        bx.text(0.99, 0.01, "\n".join(notrun), transform=bx.transAxes, ha="right", va="bottom", fontsize=7,
                bbox=dict(fc="white", ec="0.7"))
    bx.set(xlabel="DOFs of the lattice", ylabel="wall time [s]",
           title="peers: MEiCP enumeration (tiny lattices nx = 6–12; too large from 10^4 DOFs)\n"
                 "vs active-set; static contact LCP, meicp vs Siconos; slopes over all points (active-set: from 10^5)")
    bx.grid(True, which="both", alpha=0.3)
    bx.legend(fontsize=7.5, loc="upper center", bbox_to_anchor=(0.5, -0.09), ncol=2)
    save_figure(fig, f"{out}_time.png", dpi=110)
    # 2. memory
    fig, ax = plt.subplots(figsize=(10, 6.5))
    for stage, method, label in pipeline:
        for ranks, ls, mk in ((1, "-", "o"), (2, "--", "s")):
            draw(ax, (stage, method, ranks), label, colour[stage], ls, mk, idx=2)
    draw(ax, ("eigensolve", "arpack+superlu", 1), "peer: ARPACK + SuperLU", "k", ":", "D", idx=2)
    ax.set(xlabel="DOFs of the lattice", ylabel="peak resident set during the stage, per rank (largest rank),\n"
           "minus the process after imports [MB]",
           title="peak memory per stage (holds what earlier stages keep: K, M, the pencil)\n"
                 "solid 1 rank, dashed 2 ranks; slopes from 10^5 DOFs up")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="upper left")
    save_figure(fig, f"{out}_memory.png", dpi=110)
    # 3. speedup and efficiency 1 -> 2 ranks
    fig, ax = plt.subplots(figsize=(10, 6.5))
    pairs = [("assemble", "meicp-scipy", "meicp-petsc", "assembly (SciPy 1 rank → PETSc 2 ranks)"),
             ("pencil", "meicp-scipy", "meicp-petsc", "reduced pencil (SciPy → PETSc products)"),
             ("eigensolve", "slepc-krylovschur+mumps", None, "one eigen-solve, SLEPc + MUMPS"),
             ("meicp", "active-set", None, "MEiCP active-set"),
             ("analyze", "meicp-analyze", None, "analyze, end to end"),
             ("xy-eigensolve", "slepc-krylovschur+mumps", None, "one eigen-solve, J = xy pencil (GHEP)"),
             ("xy-meicp", "active-set", None, "EiCP active-set, J = xy (3 supports)")]
    colour = dict(colour, **{"xy-eigensolve": "C2", "xy-meicp": "C3"})
    marked = False
    for stage, m1, m2, label in pairs:
        one = {d: t for d, t, _ in series.get((stage, m1, 1), []) if d >= main}
        two = {d: t for d, t, _ in series.get((stage, m2 or m1, 2), []) if d >= main}
        ds = sorted(set(one) & set(two))
        if ds:
            ax.semilogx(ds, [one[d] / two[d] for d in ds], marker="^" if stage.startswith("xy") else "o",
                        ls=":" if stage.startswith("xy") else "-", color=colour[stage], label=label)
            # runs that did not get their cores: CPU time / wall time below 0.9 on some rank
            cpu = {(r["method"], int(r["ranks"]), int(r["dofs"])): r.get("cpu_frac") or "1" for r in ok
                   if r["stage"] == stage}
            bad = [d for d in ds if min(float(cpu.get((m1, 1, d), 1)), float(cpu.get((m2 or m1, 2, d), 1))) < 0.9]
            if bad:
                ax.plot(bad, [one[d] / two[d] for d in bad], "o", ms=13, mfc="none", mec="0.3", mew=1.5,
                        label=None if marked else "descheduled: CPU/wall < 0.9 on a rank")
                marked = True
    ax.axhline(2, color="k", ls=":", lw=1)
    ax.axhline(1, color="0.5", ls="--", lw=1)
    ax.text(1.1e4, 2.03, "ideal on 2 ranks (efficiency 1)", fontsize=8)
    ax.text(1.1e4, 1.03, "no gain (efficiency 0.5)", fontsize=8, color="0.4")
    ax.set(xlabel="DOFs of the lattice", ylabel="speedup  t(1 rank) / t(2 ranks)", ylim=(0, 2.4),
           title="speedup 1 → 2 ranks on the 2-core machine (parallel efficiency = speedup / 2)")
    sec = ax.secondary_yaxis("right", functions=(lambda s: s / 2, lambda e: 2 * e))
    sec.set_ylabel("parallel efficiency")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=3)
    save_figure(fig, f"{out}_speedup.png", dpi=110)
    print(f"wrote {out}_time.png, {out}_memory.png, {out}_speedup.png")
    _chart_scaling_xy(rows, out)


def _chart_scaling_xy(rows, out):
    """scaling_activeset.png: the multi-support family (J = x, y of the lowest free row):
    active-set time and one eigen-solve against DOFs, 1 and 2 ranks, with the supports
    visited; right: active-set time / one eigen-solve."""
    xy = [r for r in rows if r["stage"] in ("xy-eigensolve", "xy-meicp") and r["wall_s"]]
    if not xy:
        return
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(15, 6.5))
    single = {(int(r["ranks"]), int(r["dofs"])): float(r["wall_s"]) for r in xy if r["stage"] == "xy-eigensolve"}
    for ranks, ls, mk in ((1, "-", "o"), (2, "--", "s")):
        rk = f"{ranks} rank{'s' if ranks > 1 else ''}"
        for stage, c, label in (("xy-eigensolve", "C2", "one eigen-solve (GHEP, SLEPc + MUMPS)"),
                                ("xy-meicp", "C3", "EiCP active-set (solve_eicp)")):
            pts = sorted((int(r["dofs"]), float(r["wall_s"]), r) for r in xy if r["stage"] == stage
                         and r["ranks"] == str(ranks))
            if not pts:
                continue
            sl = _scaling_slope([p[:2] for p in pts])
            ax.loglog([p[0] for p in pts], [p[1] for p in pts], ls=ls, marker=mk, color=c, ms=5,
                      label=f"{label}, {rk}" + (f", slope {sl:.2f}" if sl is not None else ""))
            if stage == "xy-meicp":
                for d, t, r in pts:
                    if ranks == 1:
                        ax.annotate(f"{r['supports']} supports,\n{r['eigen_solves']} solves", (d, t),
                                    textcoords="offset points", xytext=(6, -22), ha="left", fontsize=7, color="C3")
                ratio = [(d, t / single[(ranks, d)]) for d, t, _ in pts if (ranks, d) in single]
                if ratio:
                    bx.semilogx(*zip(*ratio), ls=ls, marker=mk, color="C3", label=f"active-set / one eigen-solve, {rk}")
    ax.set(xlabel="DOFs of the lattice", ylabel="wall time, median [s]",
           title="multi-support EiCP (J = x and y DOFs of the lowest free row, |J| = 2·nx):\n"
                 "active-set against one eigen-solve; slopes from 10^5 DOFs up")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    bx.axhline(1, color="0.5", ls=":", lw=1)
    bx.set(xlabel="DOFs of the lattice", ylabel="active-set time / time of one eigen-solve", ylim=(0, None),
           title="cost of the active-set search in units of one eigen-solve\n"
                 "(later solves restart from the last eigenvector, reuse the symbolic LU)")
    bx.grid(True, which="both", alpha=0.3)
    bx.legend(fontsize=8, loc="lower right")
    save_figure(fig, f"{out}_activeset.png", dpi=110)
    print(f"wrote {out}_activeset.png")


# --- resolution convergence and the cost of scene features (bench_resolution.py) ---

def chart_resolution(path):
    """Resolution study (scripts/bench_resolution.py).  resolution.png: μ_c's relative error
    against its Richardson limit vs DOFs (log-log) with the 1e-3 line and the fitted order, the
    growth rate λ vs DOFs (it has no limit), and the time of each computation vs DOFs.
    resolution_features.png: median time (and peak memory) of each scene feature relative to
    the base scene at the same size, measured side by side."""
    import numpy as np

    rows = read_rows(path)
    out = Path(path).with_suffix("")
    conv = [r for r in rows if r["part"] == "convergence"]
    if conv:
        fig, axes = plt.subplots(1, 3, figsize=(18, 5.2))
        ax = axes[0]
        lim = next((r for r in conv if r["quantity"] == "mu_c_limit"), None)
        styles = {"critical_friction-uncondensed": ("s", "C3", 10), "critical_friction": ("o", "C0", 6),
                  "condensed-full-support": ("^", "C2", 6)}
        if lim and lim["status"] == "converges":
            limit, p = float(lim["value"]), float(lim["order"])
            for m, (mk, c, ms) in styles.items():
                pts = sorted((int(r["dofs"]), float(r["error"])) for r in conv
                             if r["quantity"] == "mu_c" and r["method"] == m and r["error"])
                if pts:
                    ax.loglog(*zip(*pts), mk, color=c, ms=ms,
                              mfc="none" if m == "critical_friction-uncondensed" else c,
                              label={"critical_friction-uncondensed": "critical_friction, former uncondensed path",
                                     "critical_friction": "meicp.critical_friction (condensed, all supports: proof)",
                                     "condensed-full-support": "condensed, full support (certified)"}[m])
            fs = sorted((int(r["dofs"]), abs(float(r["value"]) - limit) / abs(limit), int(r["n"])) for r in conv
                        if r["quantity"] == "mu_c" and r["method"] == "condensed-full-support" and r["error"])
            d1, e1, n1 = fs[-1]
            # error ∝ a^p ∝ n^-p; DOFs ∝ n²: error ∝ DOFs^(-p/2); extend the fitted line to 1e-3
            n_need = n1 * (e1 / 1e-3) ** (1 / p)
            d_need = d1 * (n_need / n1) ** 2
            dd = np.geomspace(fs[0][0], max(d_need, d1) * 1.5, 50)
            ax.loglog(dd, e1 * (dd / d1) ** (-p / 2), "--", color="0.4",
                      label=f"observed order p = {p:.2f} in a (error ∝ DOFs^-{p / 2:.2f})")
            ax.axhline(1e-3, color="C3", lw=1)
            ax.text(fs[0][0], 1.15e-3, "1e-3", color="C3")
            ax.axvline(d_need, color="C3", ls=":", lw=1)
            ax.text(d_need, 2e-3, f"1e-3 predicted at\nnx ≈ {n_need + 1:,.0f}\n({d_need:.1e} DOFs) ",
                    color="C3", fontsize=8, ha="right")
            ax.set_title(f"critical friction μ_c: error vs Richardson limit {limit:.5f}")
        ax.set_xlabel("DOFs of the lattice")
        ax.set_ylabel("relative error |μ_c − μ_c,∞| / μ_c,∞")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7.5, loc="lower left")
        # λ: no limit
        ax = axes[1]
        lam = [r for r in conv if r["quantity"] == "lambda" and r["value"]]
        for m, (mk, c) in {"enumerate": ("o", "C0"), "active-set": ("s", "C1")}.items():
            pts = sorted((int(r["dofs"]), float(r["value"])) for r in lam if r["method"] == m)
            if pts:
                ax.loglog(*zip(*pts), mk, color=c, ms=7, label=f"meicp.analyze ({m})")
        refs = sorted((int(r["dofs"]), float(r["reference"])) for r in lam if r.get("reference")
                      and r["reference"] != "none")
        if refs:
            ax.loglog(*zip(*refs), "k+", ms=12, label="dense SciPy eig of the same pencil (check)")
        ll = next((r for r in conv if r["quantity"] == "lambda_limit"), None)
        pts = sorted((int(r["dofs"]), float(r["value"])) for r in lam)
        if pts:
            ax.loglog(*zip(*pts), "-", color="0.7", zorder=0)
        if ll is not None and ll["status"] == "diverges":
            s = float(ll["order"])
            d1, v1 = pts[-1]
            dd = np.array([pts[0][0], d1])
            ax.loglog(dd, v1 * (dd / d1) ** (s / 2), "--", color="C3",
                      label=f"no limit: λ ∝ n^{s:.2f} ≈ 1/a (fit, 3 finest levels)")
        ax.set_xlabel("DOFs of the lattice")
        ax.set_ylabel("growth rate λ = √σ of the fastest mode")
        ax.set_title("divergence growth rate λ: grows without limit (mode at the corner)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7.5, loc="upper left")
        # time
        ax = axes[2]
        series = {("lambda", "enumerate"): ("analyze, enumeration", "o", "C0"),
                  ("lambda", "active-set"): ("analyze, active-set", "s", "C1"),
                  ("mu_c", "critical_friction-uncondensed"): ("critical_friction, former uncondensed path",
                                                              "s", "C3"),
                  ("mu_c", "critical_friction+check"): ("critical_friction with its bisection check", "D", "C4"),
                  ("mu_c", "critical_friction"): ("critical_friction (condensed, no check)", "o", "C9"),
                  ("mu_c", "condensed-full-support"): ("μ_c condensed, full support", "^", "C2")}
        for (q, m), (label, mk, c) in series.items():
            pts = sorted((int(r["dofs"]), max(float(r["wall_s"]), 1e-3)) for r in conv
                         if r["quantity"] == q and r["method"] == m and r["wall_s"])
            if pts:
                ax.loglog(*zip(*pts), mk + "-", color=c, label=label)
        ax.set_xlabel("DOFs of the lattice")
        ax.set_ylabel("wall time, one run [s] (floor 1 ms)")
        ax.set_title("cost per level (1 core)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7.5, loc="upper left")
        fig.suptitle("One physical scene (4×4 two-layer block, free sides, every base node sliding, μ = 3) "
                     "refined: a = 4/n, nx = n + 1", fontsize=11)
        save_figure(fig, f"{out}.png", dpi=110, rect=(0, 0, 1, 0.95))
        print(f"wrote {out}.png")
    feats = [r for r in rows if r["part"] == "features"]
    if feats:
        sizes = sorted({int(r["n"]) for r in feats})
        fig, axes = plt.subplots(1, 2, figsize=(15, 5.5))
        names = list(dict.fromkeys(r["feature"] for r in feats if r["feature"] != "base"))
        width = 0.8 / len(sizes)
        for k, n in enumerate(sizes):
            mine = [r for r in feats if int(r["n"]) == n]
            ok = lambda f: [r for r in mine if r["feature"] == f and r["status"] != "failed"]  # noqa: E731
            base_t = np.median([float(r["wall_s"]) for r in ok("base")])
            base_m = np.median([float(r["peak_rss_mb"]) for r in ok("base")])
            dofs = mine[0]["dofs"]
            for ax, key, base in ((axes[0], "wall_s", base_t), (axes[1], "peak_rss_mb", None)):
                xs, ys, notes = [], [], []
                for i, f in enumerate(["base"] + names):
                    rs = ok(f)
                    if not rs:
                        continue
                    v = np.median([float(r[key]) for r in rs])
                    xs.append(i + (k - (len(sizes) - 1) / 2) * width)
                    ys.append(v / base if base else max(v, 0.05))
                    st = {r["status"] for r in rs}
                    notes.append("" if st == {"solved"} else "/".join(sorted(st)))
                bars = ax.bar(xs, ys, width, label=f"n = {n} ({dofs} DOFs)" +
                              (f", base {base_t:.3f} s" if base else f", base {base_m:.1f} MB"), color=f"C{k}")
                for b, y, note in zip(bars, ys, notes):
                    ax.text(b.get_x() + b.get_width() / 2, y * 1.08, f"{y:.3g}" + ("×" if base else ""),
                            ha="center", fontsize=7.5)
                    if note:
                        ax.text(b.get_x() + b.get_width() / 2, y * 1.5, note, ha="center", fontsize=7,
                                color="C3", rotation=90, va="bottom")
        for ax, label in ((axes[0], "time relative to the base scene at the same size (median)"),
                          (axes[1], "peak resident memory above the start [MB] (median)")):
            ax.set_xticks(range(len(names) + 1), ["base"] + names, rotation=30, ha="right")
            ax.set_yscale("log")
            ax.set_ylabel(label)
            ax.grid(True, axis="y", which="both", alpha=0.3)
            ax.legend(fontsize=8, loc="upper right")
        axes[0].axhline(1, color="k", lw=0.8)
        lo, hi = axes[0].get_ylim()
        axes[0].set_ylim(lo, hi * 8)
        lo, hi = axes[1].get_ylim()
        axes[1].set_ylim(lo, hi * 8)
        fig.suptitle("Cost of each scene feature (fresh process per run, repeats interleaved; red: not 'solved')",
                     fontsize=11)
        save_figure(fig, f"{out}_features.png", dpi=110, rect=(0, 0, 1, 0.95))
        print(f"wrote {out}_features.png")


def chart_critical_friction(path):
    """critical_friction.png (scripts/bench_critical_friction.py): wall time and the bracket's
    relative width against |J|, per rank count; a bracket proved free of modes at every μ
    (lower = upper = inf) is drawn at the bottom of the width axis and labelled."""
    rows = read_rows(path)
    out = Path(path).with_suffix("")
    fig, (ax_t, ax_w) = plt.subplots(1, 2, figsize=(13, 4.8))
    groups = defaultdict(list)
    for r in rows:
        groups[(r["ranks"], r["states"], r["shear"])].append(r)
    floor = 1e-8
    for (ranks, states, shear), rs in sorted(groups.items()):
        rs.sort(key=lambda r: int(r["J"]))
        J = [int(r["J"]) for r in rs]
        label = f"{states}, shear {shear}, {ranks} rank(s)"
        marker = "o" if ranks == "1" else "s"
        ax_t.loglog(J, [float(r["seconds"]) for r in rs], marker=marker, label=label)
        w = [max(float(r["width"]), floor) for r in rs]
        ax_w.loglog(J, w, marker=marker, label=label)
        for j, r in zip(J, rs):
            if r["upper"] == "inf":
                ax_w.annotate("no mode at any μ (proved)" if r["lower"] == "inf" else "no mode found", (j, floor),
                              fontsize=7, rotation=30)
    ax_t.axhline(60, color="grey", ls=":")
    ax_t.axhline(300, color="grey", ls="--")
    ax_t.set(xlabel="|J| (contacts)", ylabel="wall time (s, median)", title="critical_friction: time")
    ax_w.axhline(0.05, color="grey", ls="--")
    ax_w.axhline(1e-5, color="grey", ls=":")
    ax_w.set(xlabel="|J| (contacts)", ylabel="(upper − lower)/upper", title="width of the certified bracket "
             "(dotted: 'exact')")
    ax_t.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(f"{out}.png", dpi=110)
