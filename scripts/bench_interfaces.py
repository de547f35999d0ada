#!/usr/bin/env python3
"""Divergence decided on frictional interfaces at scale (issue 33, deliverable 1): how often
``analyze`` decides on two layers with an unbonded frictional interface, and what it costs.

    .venv/bin/python scripts/bench_interfaces.py family      # -> interfaces_family.csv
    .venv/bin/python scripts/bench_interfaces.py family --sizes 100:25+25 300:25+25 1000:25+25
    flock /work/scratch/s30/heavy.lock mpirun -n 2 .venv/bin/python scripts/bench_interfaces.py \\
        family --sizes 1000:250+250 --cases 6:slip-:1 6:slip+:20 --reference   # 10⁶ DOFs, 2 ranks
    PYTHONPATH=OTHER/src .venv/bin/python scripts/bench_interfaces.py named --code main  # before
    .venv/bin/python scripts/bench_interfaces.py named --code branch                     # after
    .venv/bin/python scripts/bench_interfaces.py check --count 8 --pairs 13 16   # -> interfaces_check.csv
    .venv/bin/python scripts/bench_interfaces.py chart

Family: ``two_layer_scene`` with the bottom and top rows fixed, sides free, the interface
between the two layers frictional (every pair in the prescribed state slip+ or slip−), no
base contact; two contrasts (stiff k 6 under soft k 1, and k 2 under k 1; ρ = 1 everywhere);
μ geometric from 0.05 to 20.  ``named``: the issue's three cases (``interfaces_named.csv``),
run on whichever meicp PYTHONPATH picks (``--code`` labels it).  ``--reference`` adds one
SLEPc eigen-solve of the same pencil (the project's unit of cost).  Flutter is not timed
(``flutter=False``): the deliverable is the divergence verdict.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from bench_common import csv_path, read_rows, save_figure, scatter_verdicts, slepc_eigensolve, write_rows
import meicp
from meicp.contact import pencil
from meicp.core.matrix import is_petsc_mat
from meicp.examples import two_layer_scene
from meicp.petsc.mat import mat_from_scipy

FAMILY = ["nx", "rows", "dofs", "pairs", "ranks", "contrast", "state", "mu", "divergence", "test", "sigma",
          "seconds", "eigensolve_s", "ratio", "load1", "evidence"]
CHECK = ["seed", "nx", "rows", "sides", "contrast", "state", "mu", "truth", "window", "agree", "test",
         "enumerate_s", "window_s"]
NAMED = ["case", "code", "nx", "rows", "dofs", "contrast", "state", "mu", "divergence", "test", "sigma", "seconds",
         "load1", "evidence"]
MUS = np.geomspace(0.05, 20.0, 6)
CONTRASTS = {"6/1": (6.0, 1.0), "2/1": (2.0, 1.0)}
#: the issue's cases: (name, nx, rows, contrast, state, μ)
CASES = [("k6/k1 4+4, 120 pairs, mu 1, slip-", 120, (4, 4), "6/1", "slip-", 1.0),
         ("k2/k1 6+6, 300 pairs, mu 2, slip+", 300, (6, 6), "2/1", "slip+", 2.0),
         ("k2/k1 3+3, 300 pairs, mu 20, slip+", 300, (3, 3), "2/1", "slip+", 20.0)]


def interface_scene(nx: int, rows: tuple[int, int], contrast: str, state: str, mu: float):
    """Two layers, bottom and top fixed, sides free, an unbonded frictional interface."""
    return two_layer_scene(nx, rows, bottom="fixed", top="fixed", sides="free", stiffness=CONTRASTS[contrast],
                           density=(1.0, 1.0), interface={"kind": "frictional", "friction": float(mu),
                                                          "states": state})


def _comm():
    from mpi4py import MPI

    return MPI.COMM_WORLD


def _verdict(scene, comm):
    comm.Barrier()
    t0 = time.perf_counter()
    r = meicp.analyze(scene, comm=comm, flutter=False)
    comm.Barrier()
    return r, time.perf_counter() - t0


def _eigensolve(scene, comm) -> float:
    """Wall time of one SLEPc eigen-solve (4 eigenvalues nearest 0) of the scene's pencil."""
    with pencil(scene, comm=comm) as pen:
        comm.Barrier()
        t0 = time.perf_counter()
        A, B = pen.A, pen.B
        if not is_petsc_mat(A):
            A, B = mat_from_scipy(None, A), mat_from_scipy(None, B)
        slepc_eigensolve(A, B, 4)
        comm.Barrier()
        return time.perf_counter() - t0


def _cases(args):
    if args.cases:
        for c in args.cases:
            contrast, state, mu = c.split(":")
            yield f"{contrast}/1" if "/" not in contrast else contrast, state, float(mu)
        return
    for contrast in CONTRASTS:
        for state in ("slip+", "slip-"):
            for mu in MUS:
                yield contrast, state, float(mu)


def family(args):
    comm = _comm()
    rows = []
    for size in args.sizes:
        nx, lr = int(size.split(":")[0]), tuple(int(v) for v in size.split(":")[1].split("+"))
        eig = None
        for contrast, state, mu in _cases(args):
            scene = interface_scene(nx, lr, contrast, state, mu)
            if args.reference and eig is None:
                eig = _eigensolve(scene, comm)
            r, t = _verdict(scene, comm)
            rows.append({"nx": nx, "rows": f"{lr[0]}+{lr[1]}", "dofs": r.sizes.get("dofs"), "pairs": nx,
                         "ranks": comm.size, "contrast": contrast, "state": state, "mu": f"{mu:.4g}",
                         "divergence": r.divergence, "test": r.proofs[0].test if r.proofs else "",
                         "sigma": f"{r.modes[0].sigma:.10g}" if r.modes else "", "seconds": f"{t:.2f}",
                         "eigensolve_s": "" if eig is None else f"{eig:.2f}",
                         "ratio": "" if eig is None else f"{t / eig:.2f}",
                         "load1": f"{os.getloadavg()[0]:.1f}", "evidence": r.evidence[:200]})
            if comm.rank == 0:
                print(*(rows[-1][k] for k in FAMILY[:-1]), flush=True)
    if comm.rank == 0:
        fresh = {_key(r) for r in rows}  # a re-run replaces its scenes' rows, others stay
        write_rows(csv_path("interfaces_family"), rows, FAMILY, keep=lambda r: _key(r) not in fresh)
        decided = sum(r["divergence"] is not None for r in rows)
        print(f"decided {decided}/{len(rows)} ({100 * decided / len(rows):.1f} %)")


def _key(row) -> tuple:
    return tuple(str(row[k]) for k in ("nx", "rows", "ranks", "contrast", "state", "mu"))


def named(args):
    comm = _comm()
    rows = []
    for name, nx, lr, contrast, state, mu in CASES:
        r, t = _verdict(interface_scene(nx, lr, contrast, state, mu), comm)
        rows.append({"case": name, "code": args.code, "nx": nx, "rows": f"{lr[0]}+{lr[1]}",
                     "dofs": r.sizes.get("dofs"), "contrast": contrast, "state": state, "mu": mu,
                     "divergence": r.divergence, "test": r.proofs[0].test if r.proofs else "",
                     "sigma": f"{r.modes[0].sigma:.10g}" if r.modes else "", "seconds": f"{t:.2f}",
                     "load1": f"{os.getloadavg()[0]:.1f}", "evidence": r.evidence[:300]})
        if comm.rank == 0:
            print(*(rows[-1][k] for k in NAMED), flush=True)
    if comm.rank == 0:
        write_rows(csv_path("interfaces_named"), rows, NAMED, keep=lambda r: r["code"] != args.code)


def chart(args):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = read_rows(csv_path("interfaces_family"))
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.3))
    scatter_verdicts(left, rows, lambda r: float(r["mu"]) * (1.06 if r["state"] == "slip-" else 1.0),
                     lambda r: int(r["dofs"]) * (1.15 if r["contrast"] == "2/1" else 1.0), alpha=0.75)
    left.set_xscale("log")
    left.set_yscale("log")
    left.set_xlabel("friction μ (slip− shifted right)")
    left.set_ylabel("DOFs (contrast 2/1 shifted up)")
    decided = sum(r["divergence"] != "None" for r in rows)
    left.set_title(f"verdicts: {decided}/{len(rows)} decided", fontsize=10)
    left.legend(fontsize=8, loc="lower left")
    for contrast, color in (("6/1", "tab:blue"), ("2/1", "tab:orange")):
        sel = [r for r in rows if r["contrast"] == contrast]
        right.scatter([int(r["dofs"]) for r in sel], [float(r["seconds"]) for r in sel], color=color, alpha=0.6,
                      label=f"k {contrast}")
    right.set_xscale("log")
    right.set_yscale("log")
    right.set_xlabel("DOFs")
    right.set_ylabel("analyze (divergence), s")
    right.set_title("time per verdict (1 rank; 10⁶ DOFs: 2 ranks)", fontsize=10)
    right.legend(fontsize=8)
    save_figure(fig, csv_path("interfaces_family").with_suffix(".png"))


def check(args):
    """The window procedure against enumeration past the test suite's 10 pairs (the suite's
    property test draws 3–10): random interfaces of ``--pairs`` pairs, 1–2 rows per layer."""
    rng = np.random.default_rng(args.seed)
    rows = []
    for k in range(args.count):
        nx = int(rng.integers(args.pairs[0], args.pairs[1] + 1))
        lr = (int(rng.integers(1, 3)), int(rng.integers(1, 3)))
        sides = str(rng.choice(["free", "fixed"]))
        contrast, state = str(rng.choice(list(CONTRASTS))), str(rng.choice(["slip+", "slip-"]))
        mu = float(np.exp(rng.uniform(np.log(0.05), np.log(20.0))))
        scene = two_layer_scene(nx, lr, bottom="fixed", sides=sides, stiffness=CONTRASTS[contrast],
                                density=(1.0, 2.0), interface={"kind": "frictional", "friction": mu, "states": state})
        t0 = time.perf_counter()
        truth = meicp.analyze(scene, method="enumerate", flutter=False)
        t1 = time.perf_counter()
        window = meicp.analyze(scene, method="active-set", flutter=False)
        t2 = time.perf_counter()
        if window.divergence is None:
            agree = "undecided"
        elif window.divergence is True:
            agree = str(truth.divergence is True and any(np.isclose(window.modes[0].sigma, m.sigma, rtol=1e-8,
                                                                   atol=1e-12) for m in truth.modes))
        else:
            agree = str(truth.divergence is False)
        rows.append(dict(seed=args.seed, nx=nx, rows=f"{lr[0]}+{lr[1]}", sides=sides, contrast=contrast, state=state,
                         mu=f"{mu:.6g}", truth=truth.divergence, window=window.divergence, agree=agree,
                         test=window.proofs[0].test if window.proofs else "", enumerate_s=f"{t1 - t0:.2f}",
                         window_s=f"{t2 - t1:.2f}"))
        print(rows[-1], flush=True)
        write_rows(csv_path("interfaces_check"), rows[-1:], CHECK)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="what", required=True)
    f = sub.add_parser("family")
    f.add_argument("--sizes", nargs="+", default=["100:25+25", "300:25+25", "1000:25+25"],
                   help="lattices nx:lower+upper (nx = interface pairs)")
    f.add_argument("--cases", nargs="+", help="contrast:state:mu, e.g. 6:slip-:1 (default: the whole grid)")
    f.add_argument("--reference", action="store_true", help="time one SLEPc eigen-solve per lattice")
    n = sub.add_parser("named")
    n.add_argument("--code", default="branch", help="label of the meicp being measured (main, branch)")
    c = sub.add_parser("check")
    c.add_argument("--count", type=int, default=8)
    c.add_argument("--pairs", type=int, nargs=2, default=[13, 16])
    c.add_argument("--seed", type=int, default=33)
    sub.add_parser("chart")
    args = p.parse_args()
    globals()[args.what](args)


if __name__ == "__main__":
    main()
