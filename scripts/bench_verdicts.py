#!/usr/bin/env python3
"""Divergence verdicts at scale (issue 14): how often ``analyze`` decides (a proof or a
certified mode) on two-layer scenes past the enumeration budget, whether it ever contradicts
enumeration, and what a verdict costs against one SLEPc eigen-solve of the same pencil.

    .venv/bin/python scripts/bench_verdicts.py family            # -> verdicts_family.csv
    .venv/bin/python scripts/bench_verdicts.py family --sizes 1000:10+10 2000:10+10
    .venv/bin/python scripts/bench_verdicts.py check --count 80   # -> verdicts_check.csv
    flock /work/scratch/bench.lock mpirun -n 2 .venv/bin/python scripts/bench_verdicts.py cost \\
        --nx 1000 --rows 250 250 --mu 3 1 --shear 0.5 0           # -> verdicts_cost.csv
    flock /work/scratch/bench.lock mpirun -n 2 .venv/bin/python scripts/bench_verdicts.py cost \\
        --mu 2 --states slip- --shear -0.3 --flutter              # -> verdicts_cost_flutter.csv
    .venv/bin/python scripts/bench_verdicts.py chart
    .venv/bin/python scripts/bench_verdicts.py first      # -> verdicts_first_search.csv

Scenes: ``two_layer_scene`` (k = 1 / 5, ρ = 1 / 2, top fixed, sides free), every base node
in one slip state, |J| = nx sliding contacts; flutter is not part of these timings
(``flutter=False``: issue 15's benchmark covers it), except with ``cost --flutter``: the whole
verdict, divergence and flutter, against the eigen-solve (issue 29's cost).
"""

from __future__ import annotations

import argparse
import os
import time

import meicp  # before NumPy: it sets OpenBLAS's kernel for this CPU (meicp.core.blas_kernel)
import numpy as np

from bench_common import csv_path, git_commit, scatter_verdicts, slepc_eigensolve, write_rows
from meicp.contact import pencil
from meicp.contact.divergence import search, sigma_window, steps
from meicp.core.matrix import is_petsc_mat
from meicp.examples import two_layer_scene
from meicp.petsc.mat import mat_from_scipy

FAMILY = ["nx", "rows", "dofs", "J", "state", "shear", "mu", "divergence", "test", "sigma", "seconds", "evidence"]
CHECK = ["nx", "rows", "J", "state", "shear", "mu", "truth", "window", "agree", "test"]
COST = ["nx", "rows", "dofs", "J", "ranks", "state", "shear", "mu", "divergence", "test", "sigma", "analyze_s",
        "eigensolve_s", "ratio", "load1"]
FIRST = ["family", "nx", "rows", "contrast", "state", "shear", "mu", "theta_positive", "theta", "first_search",
         "first_found", "first_sigma", "first_s", "driver_first", "proxy_shift", "proxy_found", "proxy_sigma", "proxy_s",
         "divergence", "test"]
COST_FLUTTER = COST + ["flutter", "flutter_s", "growth_lower", "growth_upper", "commit", "flutter_evidence"]
MUS = np.geomspace(0.05, 6.0, 8)


def _verdict(scene, comm=None, method=None, flutter=False):
    t0 = time.perf_counter()
    r = meicp.analyze(scene, comm=comm, method=method, flutter=flutter)
    return r, time.perf_counter() - t0


def family(args):
    rows = []
    for size in args.sizes:
        nx, lr = int(size.split(":")[0]), tuple(int(v) for v in size.split(":")[1].split("+"))
        for state in ("slip+", "slip-"):
            for shear in (0.5, -0.5):
                for mu in (MUS if nx <= 200 else MUS[::3]):
                    r, t = _verdict(two_layer_scene(nx, lr, mu=float(mu), states=state, shear=shear))
                    rows.append({"nx": nx, "rows": f"{lr[0]}+{lr[1]}", "dofs": r.sizes.get("dofs"),
                                 "J": r.sizes.get("complementarity"), "state": state, "shear": shear,
                                 "mu": f"{mu:.4g}", "divergence": r.divergence,
                                 "test": r.proofs[0].test if r.proofs else "",
                                 "sigma": f"{r.modes[0].sigma:.10g}" if r.modes else "",
                                 "seconds": f"{t:.3f}", "evidence": r.evidence[:160]})
                    print(rows[-1]["nx"], rows[-1]["rows"], state, shear, rows[-1]["mu"], r.divergence,
                          rows[-1]["test"], rows[-1]["seconds"], flush=True)
    fresh = {_family_key(r) for r in rows}  # a re-run replaces its scenes' rows, others stay
    write_rows(csv_path("verdicts_family"), rows, FAMILY, keep=lambda r: _family_key(r) not in fresh)
    decided = sum(r["divergence"] is not None for r in rows)
    print(f"decided {decided}/{len(rows)} ({100 * decided / len(rows):.1f} %)")


def _family_key(row) -> tuple:
    return tuple(str(row[k]) for k in ("nx", "rows", "state", "shear", "mu"))


def check(args):
    rng = np.random.default_rng(args.seed)
    rows = []
    for _ in range(args.count):
        nx, lo, up = int(rng.integers(4, 17)), int(rng.integers(1, 4)), int(rng.integers(1, 4))
        state, shear = str(rng.choice(["slip+", "slip-"])), float(rng.choice([-0.5, 0.5]))
        mu = float(np.exp(rng.uniform(np.log(0.05), np.log(6.0))))
        scene = two_layer_scene(nx, (lo, up), mu=mu, states=state, shear=shear)
        truth, _ = _verdict(scene, method="enumerate")
        window, _ = _verdict(scene, method="active-set")
        agree = window.divergence is None or window.divergence == truth.divergence
        rows.append({"nx": nx, "rows": f"{lo}+{up}", "J": nx, "state": state, "shear": shear, "mu": f"{mu:.4g}",
                     "truth": truth.divergence, "window": window.divergence, "agree": agree,
                     "test": window.proofs[0].test})
    write_rows(csv_path("verdicts_check"), rows, CHECK, keep=lambda r: False)  # one seeded draw: the whole file
    wrong = sum(not r["agree"] for r in rows)
    decided = sum(r["window"] is not None for r in rows)
    print(f"{len(rows)} scenes (|J| ≤ 16): decided {decided}, wrong {wrong}")


def cost(args):
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    rows = []
    # each shear beside the other, state by state and μ by μ: the sheared lattice and the
    # unsheared one of data/scenes/extensive_contact.toml measured side by side
    for state, mu, shear in ((st, m, sh) for st in args.states for m in args.mu for sh in args.shear):
        scene = two_layer_scene(args.nx, tuple(args.rows), mu=mu, states=state, shear=shear)
        with pencil(scene, comm=comm) as pen:
            comm.Barrier()
            t0 = time.perf_counter()
            A, B = pen.A, pen.B
            if not is_petsc_mat(A):  # one rank: the pencil is SciPy
                A, B = mat_from_scipy(None, A), mat_from_scipy(None, B)
            slepc_eigensolve(A, B, 4)
            comm.Barrier()
            eig = time.perf_counter() - t0
        comm.Barrier()
        r, t = _verdict(scene, comm=comm, flutter=args.flutter)
        if comm.rank == 0:
            rows.append({"nx": args.nx, "rows": f"{args.rows[0]}+{args.rows[1]}", "dofs": r.sizes.get("dofs"),
                         "J": r.sizes.get("complementarity"), "ranks": comm.size, "state": state,
                         "shear": shear, "mu": mu, "divergence": r.divergence,
                         "test": r.proofs[0].test,
                         "sigma": f"{r.modes[0].sigma:.13g}" if r.modes else "", "analyze_s": f"{t:.2f}",
                         "eigensolve_s": f"{eig:.2f}", "ratio": f"{t / eig:.2f}",
                         "load1": f"{os.getloadavg()[0]:.1f}"})
            if args.flutter:
                g = r.flutter_growth
                rows[-1].update(flutter=r.flutter, flutter_s=f"{r.timings.get('flutter', 0.0):.2f}",
                                growth_lower=f"{g.lower:.6g}" if g else "",
                                growth_upper="" if g is None or g.upper is None else f"{g.upper:.6g}",
                                commit=git_commit(), flutter_evidence=r.flutter_evidence[:300])
                print(r.flutter_evidence, flush=True)
            print(rows[-1], flush=True)
            print(r.evidence, flush=True)
    if comm.rank == 0:
        if args.flutter:
            write_rows(csv_path("verdicts_cost_flutter"), rows, COST_FLUTTER)
        else:
            write_rows(csv_path("verdicts_cost"), rows, COST)


def chart(args):
    import csv

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    with csv_path("verdicts_family").open() as f:
        rows = list(csv.DictReader(f))
    if csv_path("verdicts_cost").exists():  # the 10⁶-DOF points, on 2 ranks
        with csv_path("verdicts_cost").open() as f:
            rows += list(csv.DictReader(f))
    fig, ax = plt.subplots(figsize=(8.5, 4.5))
    scatter_verdicts(ax, rows, lambda r: float(r["mu"]), lambda r: int(r["J"]) * (1 + 0.03 * (r["state"] == "slip-")),
                     alpha=0.7)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("friction μ")
    ax.set_ylabel("|J| sliding contacts")
    decided = sum(r["divergence"] != "None" for r in rows)
    ax.set_title(f"analyze's divergence verdict past 16 contacts: {decided}/{len(rows)} decided", fontsize=10)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    fig.tight_layout()
    fig.savefig(csv_path("verdicts_family").with_suffix(".png"), dpi=120)


def first(args):
    """What the first search finds where the short Lanczos run shows no Ritz value above 0
    (docs/benchmarks-notes.md, "first search only above 0"): for every scene whose Rayleigh
    bound at 0 fails, the first search is made whatever θ (the driver makes it only for a
    positive θ) from the window's top, and again from the contact-strip proxy's estimate
    where that is lower (the driver's first shift; docs/benchmarks-notes.md,
    "first search from the proxy"), and the verdict of ``analyze`` is recorded beside it;
    two-layer family and the frictional-interface family (bench_interfaces.py's scenes)."""

    scenes = []
    for size in args.sizes:
        nx, lr = int(size.split(":")[0]), tuple(int(v) for v in size.split(":")[1].split("+"))
        for state in ("slip+", "slip-"):
            for shear in (0.5, -0.5):
                for mu in np.geomspace(0.05, 6.0, 6):
                    scenes.append(({"family": "two-layer", "contrast": "1/5", "shear": shear}, nx, lr, state, mu,
                                   two_layer_scene(nx, lr, mu=float(mu), states=state, shear=shear)))
    for size in args.interface_sizes:
        nx, lr = int(size.split(":")[0]), tuple(int(v) for v in size.split(":")[1].split("+"))
        for contrast, stiffness in (("6/1", (6.0, 1.0)), ("2/1", (2.0, 1.0))):
            for state in ("slip+", "slip-"):
                for mu in np.geomspace(0.05, 20.0, 6):
                    scene = two_layer_scene(nx, lr, bottom="fixed", top="fixed", sides="free", stiffness=stiffness,
                                            density=(1.0, 1.0), interface={"kind": "frictional", "friction": float(mu),
                                                                           "states": state})
                    scenes.append(({"family": "interface", "contrast": contrast, "shear": 0}, nx, lr, state, mu, scene))
    rows = []
    for fixed, nx, lr, state, mu, scene in scenes:
        row = {**fixed, "nx": nx, "rows": f"{lr[0]}+{lr[1]}", "state": state, "mu": f"{mu:.4g}", "first_search": False}
        with pencil(scene) as pen:
            started = time.perf_counter()
            top = sigma_window.probe_top(pen.A, pen.B)
            row.update(theta_positive=top.positive, theta=f"{top.theta:.6g}")
            if steps.bound_at_zero(pen.A, pen.B, top, started)[0] is None:
                settings = search.search_settings(pen, scene, None, 0.0, 1e-10, {}, top.shift, started)
                row.update(first_search=True, **_timed_first(settings, "first"))
                shift, _ = search.first_shift(settings, scene)
                # whether the driver makes a first search: only above 0, and not where the proxy
                # has no real σ above 0 (shift None); from the proxy's estimate when lower
                row.update(driver_first=top.positive and shift is not None)
                if shift is not None and shift != settings.target:
                    row.update(proxy_shift=f"{shift:.6g}", **_timed_first(settings.from_shift(shift), "proxy"))
        r = meicp.analyze(scene, flutter=False)
        row.update(divergence=r.divergence, test=r.proofs[0].test if r.proofs else "")
        rows.append(row)
        print(row, flush=True)
    write_rows(csv_path("verdicts_first_search"), rows, FIRST, keep=lambda r: False)  # one run: the whole file


def _timed_first(settings, name: str) -> dict:
    t0 = time.perf_counter()
    out = search.first_search(settings)
    return {f"{name}_found": out.found, f"{name}_sigma": f"{out.modes.listed[0].sigma:.10g}" if out.found else "",
            f"{name}_s": f"{time.perf_counter() - t0:.2f}"}


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="what", required=True)
    f = sub.add_parser("family")
    f.add_argument("--sizes", nargs="+", default=["20:2+2", "60:2+2", "60:10+10", "200:10+10", "400:50+50"],
                   help="lattices nx:lower+upper (rows appended to the CSV; every μ up to nx = 200, every "
                        "third past it)")
    c = sub.add_parser("check")
    c.add_argument("--count", type=int, default=80)
    c.add_argument("--seed", type=int, default=1)
    k = sub.add_parser("cost")
    k.add_argument("--nx", type=int, default=1000)
    k.add_argument("--rows", type=int, nargs=2, default=(250, 250))
    k.add_argument("--mu", type=float, nargs="+", default=[3.0, 1.0])
    k.add_argument("--states", nargs="+", default=["slip-", "slip+"])
    k.add_argument("--shear", type=float, nargs="+", default=[0.5, 0.0],
                   help="reference shears, each run beside the others (0: the shipped scenes' lattice)")
    k.add_argument("--flutter", action="store_true",
                   help="the whole verdict, flutter included (-> verdicts_cost_flutter.csv; issue 29's cost)")
    sub.add_parser("chart")
    w = sub.add_parser("first")
    w.add_argument("--sizes", nargs="+", default=["400:10+10", "1000:25+25"], help="two-layer lattices nx:lower+upper")
    w.add_argument("--interface-sizes", nargs="+", default=["300:10+10"], help="interface lattices nx:lower+upper")
    args = p.parse_args()
    globals()[args.what](args)


if __name__ == "__main__":
    main()
