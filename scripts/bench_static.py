"""Static frictional equilibrium at scale: time and peak memory per rank of
``static_equilibrium`` (formulations ``schur`` and ``mixed``) against one SLEPc eigen-solve
(:func:`bench_common.slepc_eigensolve`) of the same lattice, on the family of
data/scenes/extensive_interface.toml: a soft layer under a stiff one (k 1 / 4, ρ 1 / 2), their
frictional interface (μ = 0.5) under shear and compression (top row (0.05, −0.05)), the base
fixed; nx = 2·ny, 10⁶ DOFs = 1000 × 500 (1000 interface pairs).

    mpirun -n 2 .venv/bin/python scripts/bench_static.py run --dofs 10000 100000 1000000
    .venv/bin/python scripts/bench_static.py chart

The eigen-solve is that of the verdict path's pencil with every pair sticking (4 eigenvalues
nearest 0, MUMPS LU shift-and-invert); its stage holds the pencil, the static stage builds
everything it needs (the serial K of every rank included).  Rows go to
docs/benchmarks/static.csv (the rows of the sizes and formulations re-measured replace the
old ones), the chart to docs/benchmarks/static.png.
"""
from __future__ import annotations

import argparse
import os

from bench_common import Stage, csv_path, halves, lattice_shape, read_rows, save_figure, slepc_eigensolve, write_rows
from meicp.contact import pencil
from meicp.contact.static import static_equilibrium
from meicp.io.scene import scene_from_dict
from meicp.petsc.mat import mat_from_scipy

FIELDS = ["dofs", "nx", "ny", "contacts", "ranks", "formulation", "static_s", "static_peak_mb", "eigensolve_s",
          "eigensolve_peak_mb", "time_ratio", "memory_ratio", "slip_fraction", "stick", "slip", "separated",
          "certificate", "equilibrium_residual", "factor_s", "lcp_s", "sweeps", "polish", "status", "load1"]
MU, LOAD = 0.5, [0.05, -0.05]


def family(dofs: int, states: str = "solve"):
    nx, ny = lattice_shape(dofs)
    lo, up = halves(ny)
    return scene_from_dict({
        "lattice": {"nx": nx},
        "layers": [{"name": "lower", "rows": lo, "stiffness": 1.0, "density": 1.0},
                   {"name": "upper", "rows": up, "stiffness": 4.0, "density": 2.0}],
        "boundary": {"top": "fixed", "bottom": "fixed"},
        "interfaces": [{"below": "lower", "kind": "frictional", "friction": MU, "states": states}],
        "load": {"top_displacement": LOAD}}), nx, ny


def eigensolve(dofs: int, comm) -> Stage:
    scene, _, _ = family(dofs, states="stick")
    pen = pencil(scene, comm=comm)
    A, B = pen.A, pen.B
    if not pen.distributed:
        A, B = mat_from_scipy(comm, A), mat_from_scipy(comm, B)
    with Stage(comm) as st:
        slepc_eigensolve(A, B, 4)
    pen.lattice.destroy()
    for X in (A, B):
        X.destroy()
    return st


def run(args):
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    rows = []
    for dofs in args.dofs:
        eig = eigensolve(dofs, comm)
        scene, nx, ny = family(dofs)
        for formulation in args.formulations:
            with Stage(comm) as st:
                r = static_equilibrium(scene, comm=comm, formulation=formulation)
            states = r.interface_states.get("lower", [])
            slip = sum(s.startswith("slip") for s in states)
            row = {"dofs": scene.n_dofs, "nx": nx, "ny": ny, "contacts": nx, "ranks": comm.size,
                   "formulation": formulation, "static_s": f"{st.wall:.2f}", "static_peak_mb": f"{st.peak:.0f}",
                   "eigensolve_s": f"{eig.wall:.2f}", "eigensolve_peak_mb": f"{eig.peak:.0f}",
                   "time_ratio": f"{st.wall / eig.wall:.2f}", "memory_ratio": f"{st.peak / eig.peak:.2f}",
                   "slip_fraction": f"{slip / max(len(states), 1):.3f}", "stick": states.count("stick"),
                   "slip": slip, "separated": states.count("separated"),
                   "certificate": f"{r.residual:.1e}", "equilibrium_residual": f"{r.equilibrium_residual:.1e}",
                   "factor_s": f"{r.timings.get('factor', float('nan')):.2f}",
                   "lcp_s": f"{r.timings.get('lcp', float('nan')):.2f}",
                   "sweeps": r.layout.get("sweeps", ""), "polish": r.layout.get("polish_iterations", ""),
                   "status": r.status, "load1": f"{eig.load1:.1f}"}
            if comm.rank == 0:
                print(row, flush=True)
            rows.append(row)
    if comm.rank == 0:
        done = {(str(r["dofs"]), r["formulation"]) for r in rows}
        write_rows(csv_path("static"), rows, FIELDS, keep=lambda r: (r["dofs"], r["formulation"]) not in done)


def chart(args):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = read_rows(csv_path("static"))
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for formulation, style in (("schur", "o-"), ("mixed", "s--")):
        sel = sorted((r for r in rows if r["formulation"] == formulation), key=lambda r: int(r["dofs"]))
        if not sel:
            continue
        x = [int(r["dofs"]) for r in sel]
        timed = [r for r in sel if r["time_ratio"]]  # a run stopped before the end has no time
        axes[0].plot([int(r["dofs"]) for r in timed], [float(r["time_ratio"]) for r in timed], style, label=formulation)
        axes[1].plot(x, [float(r["memory_ratio"]) for r in sel], style, label=formulation)
    for ax, what, target in ((axes[0], "static time / one eigen-solve", 1.5),
                             (axes[1], "static peak memory / eigen-solve's (per rank)", 1.0)):
        ax.axhline(target, color="grey", lw=0.8, ls=":", label=f"target {target:g}")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("DOFs (2 ranks)")
        ax.set_ylabel(what)
        ax.legend()
    fig.suptitle("static equilibrium, frictional interface family (μ = 0.5, shear + compression)")
    save_figure(fig, csv_path("static").with_suffix(".png"), rect=(0, 0, 1, 0.95))


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("--dofs", type=int, nargs="+", default=[10_000, 100_000])
    r.add_argument("--formulations", nargs="+", default=["schur", "mixed"], choices=["schur", "mixed"])
    sub.add_parser("chart")
    args = p.parse_args()
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    (run if args.cmd == "run" else chart)(args)


if __name__ == "__main__":
    main()
