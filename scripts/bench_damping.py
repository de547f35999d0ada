#!/usr/bin/env python3
"""Growth rate against friction with and without damping (issue 31, docs/damping.md): the
fastest divergence and flutter growth of two small scenes for η = 0 and two viscosities, on
one chart — the damping that raises a flutter threshold (base contact) and the damping that
lowers it (frictional interface: the destabilisation paradox).

    .venv/bin/python scripts/bench_damping.py run      # -> damping_growth.csv
    .venv/bin/python scripts/bench_damping.py onsets   # -> damping_onsets.csv
    .venv/bin/python scripts/bench_damping.py chart    # -> damping_growth.png
    .venv/bin/python scripts/bench_damping.py scale --lock LOCK   # -> damping_scale.csv, .png
    mpirun -n 2 .venv/bin/python scripts/bench_damping.py floor   # -> damping_floor.csv, .png

Scenes (the dense damped references, where every answer is a proof or a certified mode):
``data/scenes/two_layers.toml`` (every base node slip+) and the 6 × 4 frictional interface
of tests/test_damping.py (k 2 under k 1, ρ 1, every pair slip+).  At each μ of the grid:
the divergence verdict and λ of its fastest certified mode; the flutter verdict and its
growth bracket (exact on the dense path).  Growth 0 where a verdict is proved absent; an
undecided verdict leaves a gap.  ``onsets``: ``meicp.critical_friction`` of each scene and
viscosity — the flutter onset μ_f (an interval cover of the companion form from μ = 0 and a
certified damped flutter mode, docs/critical-friction.md) and the divergence onset μ_c, each a
certified bracket — drawn on the chart as vertical lines (solid: an exact onset, its bracket
narrower than 10⁻⁶·μ; a shaded band: a bracket that is not).

``free``: the damped flutter-free proof at 10⁵ and 10⁶ DOFs (docs/damping.md, "damped
flutter-free proof"): a shallow two-layer lattice with mass damping at small μ, where
STABLE — both verdicts proved — is possible past the dense limit (damping_free.csv, .png).

``floor``: the damped divergence onset's lower end where the quadratic cross-check does not
run (docs/critical-friction.md, "With damping"): the λ = 0 onset μ_c, what the damped
Rayleigh bound proves, and how far the condensed λ-windows carried over μ take it, on
frictional interfaces and base contacts from 22 pairs to 10⁵ DOFs, on the ranks it runs on.

``scale --relaxation τ``: the same with η = τ·k in every layer — damping proportional to
stiffness, where the damped divergence is the undamped MEiCP's (docs/damping.md,
"Proportional damping").

``scale``: the damped verdict at 10⁶ DOFs on ``--ranks`` ranks (issue 31, deliverable 5): each
shipped 10⁶-DOF scene file of ``--scenes`` (``stem@μ``: at friction μ) with viscosity
``--eta`` in every layer and its ``[solver]`` table left out (written to a temporary directory), ``meicp solve --json`` on it and, side by side under the same
lock, one SLEPc eigen-solve of the *undamped* pencil of the same lattice
(``bench_scenes.py eigensolve``) — the issue's reference.  Past the dense enumeration the
damped divergence is the damped Rayleigh bound's (a proof), a followed undamped mode's (a
certified mode) or undecided; the row says that, what the damped flutter search at scale
(docs/damping.md) found, and what it cost.
"""

from __future__ import annotations

import argparse

import numpy as np

from bench_common import ROOT, csv_path, git_commit, read_rows, row_identity, rows_before, save_figure, write_rows
import meicp
from meicp.contact.damped_proportional import proportional_damping
from meicp.examples import two_layer_scene
from meicp.lattice.model import LatticeModel
from meicp.io.scene import scene_from_dict

SCALE_FIELDS = ["scene", "eta", "friction", "dofs", "retained", "contacts", "ranks", "verdict", "divergence", "divergence_test", "flutter",
                "flutter_lower", "modes", "solve_s", "flutter_s", "static_s", "eigensolve_s", "ratio", "flutter_ratio",
                "peak_mb", "load1", "date", "commit", "flutter_evidence"]
FIELDS = ["scene", "eta", "mu", "divergence", "divergence_growth", "flutter", "flutter_lower", "flutter_upper",
          "flutter_exact", "seconds"]
#: viscosities of the two layers: none, equal, a viscous base layer under a less viscous one
ETAS = {"0": (0.0, 0.0), "0.02 / 0.02": (0.02, 0.02), "0.1 / 0.01": (0.1, 0.01)}
FLOOR_FIELDS = ["scene", "dofs", "pairs", "eta", "mu_c", "rayleigh_floor", "lower", "gap", "seconds", "ranks", "date",
                "commit"]
#: (label, scene, η of the two layers) of ``floor``
FLOOR_SCENES = [
    ("22 × 4 interface", dict(nx=22, rows=(2, 2), bottom="fixed", stiffness=(2.0, 1.0), density=(1.0, 1.0),
                              interface={"kind": "frictional", "friction": 1.0, "states": "slip+"}), (0.1, 0.01)),
    ("100 × 8 interface", dict(nx=100, rows=(4, 4), bottom="fixed", stiffness=(1.0, 4.0), density=(1.0, 2.0),
                               interface={"kind": "frictional", "friction": 1.0, "states": "slip+"}), (0.02, 0.02)),
    ("100 × 50 base", dict(nx=100, rows=(25, 25), mu=1.0, states="slip+", shear=0.3), (0.02, 0.02)),
    ("316 × 158 base", dict(nx=316, rows=(79, 79), mu=1.0, states="slip+", shear=0.3), (0.02, 0.02)),
]
ONSET_FIELDS = ["scene", "eta", "flutter_lower", "flutter_upper", "flutter_exact", "divergence_lower",
                "divergence_upper", "divergence_exact", "first", "seconds", "commit"]


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


def onsets(args) -> None:
    import time

    import bench_scenes as bs

    rows = []
    for name, scene in scenes().items():
        for label, eta in ETAS.items():
            t0 = time.perf_counter()
            mu = meicp.critical_friction(with_viscosity(scene, eta))
            f, d = mu.flutter, mu.divergence
            rows.append({"scene": name, "eta": label, "flutter_lower": f"{f.lower:.10g}",
                         "flutter_upper": f"{f.upper:.10g}", "flutter_exact": f.exact,
                         "divergence_lower": f"{d.lower:.10g}", "divergence_upper": f"{d.upper:.10g}",
                         "divergence_exact": d.exact, "first": mu.first or "",
                         "seconds": f"{time.perf_counter() - t0:.2f}", "commit": git_commit()})
            print(rows[-1], flush=True)
    write_rows(csv_path("damping_onsets"), rows, ONSET_FIELDS, keep=lambda row: False)


def floor(args) -> None:
    import re
    import time
    from datetime import date

    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    rows = []
    for label, kw, eta in FLOOR_SCENES:
        scene = with_viscosity(two_layer_scene(**kw), eta)
        t0 = time.perf_counter()
        d = meicp.critical_friction(scene, flutter=False, comm=comm).divergence
        seconds = time.perf_counter() - t0
        rayleigh = re.search(r"\[0, ([0-9.e+-]+)\] by the damped Rayleigh bound", d.evidence)
        model = LatticeModel(scene)
        rows.append({"scene": label, "dofs": model.n_dofs, "pairs": kw["nx"], "eta": " / ".join(map(str, eta)),
                     "mu_c": f"{d.upper:.10g}", "rayleigh_floor": rayleigh.group(1) if rayleigh else "",
                     "lower": f"{d.lower:.10g}", "gap": f"{(d.upper - d.lower) / d.upper:.4f}",
                     "seconds": f"{seconds:.1f}", "ranks": comm.Get_size(), "date": date.today().isoformat(),
                     "commit": git_commit()})
        if comm.Get_rank() == 0:
            print(rows[-1], flush=True)
    if comm.Get_rank() == 0:
        path = csv_path("damping_floor")
        write_rows(path, rows, FLOOR_FIELDS, keep=lambda row: False)
        floor_chart(rows, path.with_suffix(".png"))


def floor_chart(rows, path=None) -> None:
    """``rows`` of ``floor`` (an argparse namespace: read them from damping_floor.csv)."""
    import matplotlib.pyplot as plt

    if not isinstance(rows, list):
        rows = read_rows(csv_path("damping_floor"))
    path = path or csv_path("damping_floor").with_suffix(".png")
    fig, ax = plt.subplots(figsize=(7.5, 3.6))
    y = np.arange(len(rows))
    ax.barh(y + 0.2, [float(r["lower"]) for r in rows], 0.4, label="proved with the λ-windows over μ")
    ax.barh(y - 0.2, [float(r["rayleigh_floor"] or 0) for r in rows], 0.4, label="by the damped Rayleigh bound alone")
    finite = [(k, float(r["mu_c"])) for k, r in enumerate(rows) if np.isfinite(float(r["mu_c"]))]
    ax.plot([m for _, m in finite], [k for k, _ in finite], "k|", ms=22, mew=2,
            label="λ = 0 onset μ_c (the upper end; none found on the last)")
    ax.set_yticks(y, [f"{r['scene']}\n{int(r['dofs']):,} DOFs, η {r['eta']}" for r in rows], fontsize=7)
    ax.set_xlabel("μ: no damped divergence mode of any λ ≥ 0 below the bar's end (a proof)")
    ax.set_title("damped divergence onset past the enumeration: the proved lower end", fontsize=9)
    ax.legend(fontsize=7, loc="upper right")
    save_figure(fig, path)


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
    onset = {(r["scene"], r["eta"]): r for r in read_rows(csv_path("damping_onsets"))}
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
            o = onset.get((name, label))
            if o is not None:
                lo, up = float(o["flutter_lower"]), float(o["flutter_upper"])
                if o["flutter_exact"] == "True":
                    ax.axvline(up, color=colours[label], ls="-", lw=0.8, alpha=0.7)
                    ax.annotate(f"μ_f = {up:.4f}", (up, 0), xytext=(2, 4 + 10 * list(ETAS).index(label)),
                                textcoords="offset points", fontsize=6, color=colours[label], rotation=90)
                elif np.isfinite(up):
                    ax.axvspan(lo, up, color=colours[label], alpha=0.08)
        mu_c = [float(o["divergence_upper"]) for (n, _), o in onset.items() if n == name]
        if mu_c and np.isfinite(mu_c[0]) and mu_c[0] <= max(float(r["mu"]) for r in rows):
            ax.axvline(mu_c[0], color="gray", ls="--", lw=0.8)
        ax.set_title(f"{name}: fastest growth Re λ against μ\nlines: proved flutter onset μ_f per η; shaded: "
                     "its bracket, not exact; grey dashed: μ_c", fontsize=8)
        ax.set_xlabel("friction coefficient μ")
        ax.set_ylabel("growth rate Re λ (0: proved absent)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    save_figure(fig, csv_path("damping_growth").with_suffix(".png"))


def solve_row(args, doc: dict, eig: dict, peaks, timed_out: bool, load1: float, solve_s: float) -> dict:
    """The CSV fields of one ``meicp solve --json`` run (``doc``) and the eigen-solve beside it
    (``eig``; :func:`bench_scenes.side_by_side`'s answers) that ``scale`` and ``free`` share."""
    import datetime

    import bench_scenes as bs

    seconds = eig.get("seconds")
    return {"retained": doc.get("sizes", {}).get("retained", ""),
            "contacts": doc.get("sizes", {}).get("complementarity", ""), "ranks": args.ranks,
            "verdict": "TIMEOUT" if timed_out else doc.get("verdict", "ERROR"),
            "divergence": doc.get("divergence"), "flutter": doc.get("flutter"),
            "divergence_test": ((doc.get("proofs") or [{}])[0] or {}).get("test", ""),
            "solve_s": f"{solve_s:.2f}", "flutter_s": f"{doc.get('timings', {}).get('flutter', float('nan')):.2f}",
            "eigensolve_s": f"{seconds:.3f}" if seconds else "",
            "ratio": f"{solve_s / seconds:.2f}" if seconds else "",
            "peak_mb": "/".join(f"{p:.0f}" for p in peaks), "load1": f"{load1:.1f}",
            "date": datetime.date.today().isoformat(), "commit": git_commit(),
            "flutter_evidence": (doc.get("flutter_evidence") or "")[:300]}


def scale(args) -> None:
    import tempfile
    from pathlib import Path

    import bench_scenes as bs
    from meicp.io.results_records import scene_to_toml

    path = csv_path("damping_scale")
    before = rows_before(path)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for stem in args.scenes:
            # the damped divergence is decided by its own path: a scene's [solver] method (e.g.
            # "active-set") is not one of its methods and is left out
            stem, _, mu = stem.partition("@")  # "scene@μ": every contact line at friction μ
            data = meicp.load_scene(ROOT / "data" / "scenes" / f"{stem}.toml").to_dict()
            data.pop("solver", None)
            if args.relaxation is None:
                scene, eta = with_viscosity(scene_from_dict(data), (args.eta,) * 99), args.eta
            else:  # η = τ·k in every layer: damping proportional to stiffness (docs/damping.md)
                for layer in data["layers"]:
                    layer["viscosity"] = args.relaxation * layer["stiffness"]
                scene, eta = scene_from_dict(data), f"{args.relaxation:g}·k"
                if proportional_damping(LatticeModel(scene)) is None:
                    raise SystemExit(f"{stem}: η = {args.relaxation:g}·k per layer is not proportional damping "
                                     "(an interface or band with its own stiffness)")
            if mu:
                scene = scene.with_friction(float(mu))
            damped = Path(tmp) / f"{stem}_damped.toml"
            damped.write_text(scene_to_toml(scene))
            doc, eig, peaks, _, _, timed_out, load1, solve_s = bs.side_by_side(
                args, args.ranks, str(damped), ["-q", *(["--no-flutter"] if args.no_flutter else [])], args.lock)
            timings = doc.get("timings", {})
            growth = doc.get("flutter_growth") or {}
            seconds = eig.get("seconds")
            row = {"scene": f"{stem}.toml", "eta": eta, "friction": mu, "dofs": 2 * scene.nx * scene.ny,
                   **solve_row(args, doc, eig, peaks, timed_out, load1, solve_s),
                   "flutter_lower": growth.get("lower", ""), "modes": len(doc.get("flutter_modes") or []),
                   "static_s": f"{timings.get('static', 0.0):.2f}",
                   "flutter_ratio": f"{timings.get('flutter', float('nan')) / seconds:.2f}" if seconds else ""}
            rows.append(row)
            print({k: row[k] for k in SCALE_FIELDS[:18]}, flush=True)
            write_rows(path, rows, SCALE_FIELDS, keep=lambda r: row_identity(r) in before)
    scale_chart(args)


def scale_chart(args) -> None:
    """Each scene's latest damped run: its time split against the undamped eigen-solve."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    latest = {(r["scene"], r["friction"], r["eta"]): r for r in read_rows(csv_path("damping_scale"))}
    rows = list(latest.values())
    fig, ax = plt.subplots(figsize=(10, 1.6 + 0.8 * len(rows)))
    for k, r in enumerate(rows):
        eig = float(r["eigensolve_s"]) if r["eigensolve_s"] else float("nan")
        static, flutter, total = float(r["static_s"]), float(r["flutter_s"]), float(r["solve_s"])
        ax.barh(k, static, color="tab:gray", label="static equilibrium" if k == 0 else None)
        ax.barh(k, flutter, left=static, color="tab:orange", label="damped flutter search" if k == 0 else None)
        ax.barh(k, total - static - flutter, left=static + flutter, color="tab:blue",
                label="the rest (the divergence verdict, assembly, reduction)" if k == 0 else None)
        ax.plot([5 * eig], [k], "k|", ms=22, label="5 × one undamped eigen-solve" if k == 0 else None)
        found = (f"flutter growth ≥ {float(r['flutter_lower']):.3g}" if r["flutter"] == "True"
                 else "flutter not analysed" if not r["flutter_lower"] else f"flutter {r['flutter'] or 'undecided'}")
        ax.text(total, k, f"  {total:.0f} s = {total / eig:.1f}× eigen-solve ({r['verdict']}: divergence "
                          f"{ {'True': 'found', 'False': 'proved absent'}.get(r['divergence'], 'undecided')}, {found})",
                va="center", fontsize=7)
    ax.set_yticks(range(len(rows)), [f"{r['scene']}" + (f" at μ = {r['friction']}" if r["friction"] else "")
                                     + f"\nη = {r['eta']}, {int(r['dofs']):,} DOFs, {r['ranks']} ranks"
                                     for r in rows], fontsize=7)
    ax.set_xlabel("wall seconds (meicp solve)")
    ax.set_title("Damped verdict at scale: damped Rayleigh bound, followed divergence modes, proportional damping "
                 "(η = τ·k: the undamped verdict), flutter search",
                 fontsize=9)
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.25), ncol=2)
    ax.set_xlim(0, 2.2 * max(float(r["solve_s"]) for r in rows))
    save_figure(fig, csv_path("damping_scale").with_suffix(".png"))


FREE_FIELDS = ["scene", "dofs", "retained", "contacts", "mu", "eta", "mass", "ranks", "verdict", "divergence",
               "divergence_test", "flutter", "solve_s", "flutter_s", "eigensolve_s", "ratio", "peak_mb", "load1",
               "date", "commit", "flutter_evidence"]


def free(args) -> None:
    """The damped flutter-free proof at scale: a two-layer lattice of ``--rows`` node rows per
    layer (k 1 / 5, top held, every base contact slip+) widened to each of ``--dofs``, at each
    μ of ``--mu``, with ``[damping] mass = --mass`` and viscosity ``--eta`` per layer;
    ``meicp solve --json`` beside one SLEPc eigen-solve of the undamped pencil."""
    import tempfile
    from pathlib import Path

    import bench_scenes as bs
    from meicp.io.results_records import scene_to_toml

    path = csv_path("damping_free")
    before = rows_before(path)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for dofs in args.dofs:
            nx = max(dofs // (4 * args.rows), 2)
            for mu in args.mu:
                scene = with_viscosity(two_layer_scene(nx, (args.rows, args.rows), mu=mu, states="slip+"),
                                       (args.eta, args.eta))
                data = scene.to_dict()
                data["damping"] = {"mass": args.mass}
                scene = scene_from_dict(data)
                file = Path(tmp) / f"free_{nx}_{mu}.toml"
                file.write_text(scene_to_toml(scene))
                doc, eig, peaks, _, _, timed_out, load1, solve_s = bs.side_by_side(args, args.ranks, str(file), ["-q"],
                                                                                   args.lock)
                row = {"scene": f"two_layer_scene({nx}, ({args.rows}, {args.rows}))", "dofs": 2 * scene.nx * scene.ny,
                       "mu": mu, "eta": args.eta, "mass": args.mass,
                       **solve_row(args, doc, eig, peaks, timed_out, load1, solve_s)}
                rows.append(row)
                print({k: row[k] for k in FREE_FIELDS[:16]}, flush=True)
                write_rows(path, rows, FREE_FIELDS, keep=lambda r: row_identity(r) in before)
    free_chart(args)


def free_chart(args) -> None:
    """Each run of ``free``: meicp solve's seconds by DOFs, marked by verdict, and the eigen-solve
    beside it where it finished within the timeout."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = read_rows(csv_path("damping_free"))
    fig, ax = plt.subplots(figsize=(7, 4.2))
    for verdict, marker in (("STABLE", "o"), ("UNDECIDED", "x"), ("UNSTABLE", "s")):
        pick = [r for r in rows if r["verdict"] == verdict]
        if pick:
            ax.scatter([int(r["dofs"]) for r in pick], [float(r["solve_s"]) for r in pick], marker=marker,
                       label=f"meicp solve: {verdict}", s=36)
            for r in pick:
                ax.annotate(f"μ = {r['mu']}", (int(r["dofs"]), float(r["solve_s"])), fontsize=6,
                            xytext=(4, 2), textcoords="offset points")
    timed = [r for r in rows if r["eigensolve_s"]]
    if timed:
        ax.scatter([int(r["dofs"]) for r in timed], [float(r["eigensolve_s"]) for r in timed], marker="_", s=200,
                   color="k", label="one undamped eigen-solve (4 pairs)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    # the labels say what the rows hold (one value each, or the values measured)
    def values(key: str) -> str:
        return ", ".join(sorted({r[key] for r in rows if r.get(key)}, key=lambda v: float(v)))

    scenes = sorted({r["scene"] for r in rows})
    ax.set_xlabel("DOFs (" + "; ".join(scenes) + ", every base contact sliding)", fontsize=8)
    ax.set_ylabel("wall seconds, " + values("ranks") + " rank(s)")
    ax.set_title(f"Damped flutter-free proof at scale (mass damping {values('mass')}, η {values('eta')}): "
                 "STABLE proves both verdicts", fontsize=9)
    ax.legend(fontsize=7)
    save_figure(fig, csv_path("damping_free").with_suffix(".png"))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="what", required=True)
    r = sub.add_parser("run")
    r.add_argument("--mu-min", type=float, default=0.05)
    r.add_argument("--mu-max", type=float, default=3.0)
    r.add_argument("--points", type=int, default=60)
    sub.add_parser("onsets")
    sub.add_parser("floor")
    sub.add_parser("floor_chart")
    sub.add_parser("chart")
    c = sub.add_parser("scale")
    c.add_argument("--scenes", nargs="+", default=["extensive_interface", "extensive_contact"],
                   help="shipped scene file stems, each optionally @μ (every contact line at friction μ)")
    c.add_argument("--eta", type=float, default=0.02, help="viscosity of every layer")
    c.add_argument("--relaxation", type=float, help="viscosity = this × stiffness in every layer (proportional "
                                                    "damping) instead of --eta")
    c.add_argument("--ranks", type=int, default=2)
    c.add_argument("--lock", help="flock this file around both commands")
    c.add_argument("--timeout", type=float, default=1800.0, help="seconds per command")
    c.add_argument("--no-flutter", action="store_true", help="the divergence verdict only (meicp solve --no-flutter)")
    sub.add_parser("scale_chart")
    f = sub.add_parser("free")
    f.add_argument("--dofs", type=int, nargs="+", default=[100_000, 1_000_000])
    f.add_argument("--rows", type=int, default=3, help="node rows of each of the two layers")
    f.add_argument("--mu", type=float, nargs="+", default=[0.005, 0.01, 0.05])
    f.add_argument("--mass", type=float, default=0.1, help="[damping] mass")
    f.add_argument("--eta", type=float, default=0.0, help="viscosity of both layers")
    f.add_argument("--ranks", type=int, default=2)
    f.add_argument("--lock", help="flock this file around both commands")
    f.add_argument("--timeout", type=float, default=1800.0, help="seconds per command")
    sub.add_parser("free_chart")
    args = p.parse_args()
    globals()[args.what](args)


if __name__ == "__main__":
    main()
