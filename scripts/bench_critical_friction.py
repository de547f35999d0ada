#!/usr/bin/env python3
"""``meicp.critical_friction`` past the enumeration limit (issue 14 part 4): the certified
bracket of the divergence onset μ_c (``critical_friction(..., flutter=False)``; ``--flutter``
brackets the flutter onset too, each call then the time of both, the row's bracket still μ_c's),
its width and wall time on the two-layer scene (``two_layer_scene``), base contacts all
slip+ or all slip−, shear ±0.5, |J| = nx contacts.  Targets: |J| = 100 under 60 s, width
≤ 5 % (exact); |J| = 1,000 (10⁶ DOFs, 2 ranks) under 5 minutes, width reported.

    .venv/bin/python scripts/bench_critical_friction.py --nx 100 --rows 25 25 --repeats 3
    flock /work/scratch/bench.lock mpirun -n 2 .venv/bin/python scripts/bench_critical_friction.py \\
        --nx 1000 --rows 250 250 --repeats 1          # -> docs/benchmarks/critical_friction.csv
    flock /work/scratch/bench.lock mpirun -n 2 .venv/bin/python scripts/bench_critical_friction.py \\
        --scenes data/scenes/extensive_contact.toml   # -> docs/benchmarks/critical_friction_scenes.csv

``--scenes``: shipped scene files instead of the family, one call each, both onsets recorded
(the divergence onset μ_c and the flutter onset μ_f, each a certified bracket, and which
starts first).

Each row: the median wall time of ``repeats`` calls (scene built outside the timing), the
bracket, its width, whether it is exact, and the evidence's first words.
"""

from __future__ import annotations

import argparse
import os
import statistics
from pathlib import Path

from bench_common import Stage, csv_path, git_commit, write_rows
from meicp.contact.critical_friction import critical_friction
from meicp.examples import two_layer_scene
from meicp.io.scene import load_scene

FIELDS = ["nx", "rows", "dofs", "J", "ranks", "states", "shear", "lower", "upper", "width", "exact", "seconds",
          "repeats", "peak_mb", "load1", "evidence"]
SCENE_FIELDS = ["scene", "dofs", "ranks", "divergence_lower", "divergence_upper", "divergence_exact", "flutter_lower",
                "flutter_upper", "flutter_exact", "first", "seconds", "peak_mb", "load1", "commit",
                "divergence_evidence", "flutter_evidence"]


def run_scenes(paths, comm) -> None:
    """Both onsets of each scene file, one call each (``--scenes``)."""
    rows = []
    for path in paths:
        scene = load_scene(path)
        with Stage(comm) as st:
            mu = critical_friction(scene, comm=comm)
        row = {"scene": Path(path).name, "dofs": scene.n_dofs, "ranks": comm.Get_size(),
               "divergence_lower": f"{mu.divergence.lower:.10g}", "divergence_upper": f"{mu.divergence.upper:.10g}",
               "divergence_exact": mu.divergence.exact, "flutter_lower": f"{mu.flutter.lower:.10g}",
               "flutter_upper": f"{mu.flutter.upper:.10g}", "flutter_exact": mu.flutter.exact, "first": mu.first,
               "seconds": round(st.wall, 1), "peak_mb": round(st.peak), "load1": round(st.load1, 1),
               "commit": git_commit(), "divergence_evidence": mu.divergence.evidence,
               "flutter_evidence": mu.flutter.evidence}
        rows.append(row)
        if comm.Get_rank() == 0:
            print({k: row[k] for k in SCENE_FIELDS if "evidence" not in k}, flush=True)
    if comm.Get_rank() == 0:
        write_rows(csv_path("critical_friction_scenes"), rows, SCENE_FIELDS)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--nx", type=int, nargs="+", default=[100])
    p.add_argument("--rows", type=int, nargs=2, default=[25, 25])
    p.add_argument("--states", nargs="+", default=["slip+", "slip-"])
    p.add_argument("--shear", type=float, nargs="+", default=[0.5, -0.5])
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--scenes", nargs="+", default=None, help="scene files instead of the family")
    p.add_argument("--flutter", action="store_true",
                   help="the family: bracket the flutter onset too (the rows keep μ_c's bracket)")
    args = p.parse_args()
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    if args.scenes:
        run_scenes(args.scenes, comm)
        return
    out = csv_path("critical_friction")
    rows = []
    for nx in args.nx:
        for states in args.states:
            for shear in args.shear:
                scene = two_layer_scene(nx, tuple(args.rows), mu=1.0, states=states, shear=shear)
                times, mu = [], None
                for _ in range(args.repeats):
                    with Stage(comm) as st:
                        mu = critical_friction(scene, comm=comm, flutter=args.flutter).divergence
                    times.append(st.wall)
                row = {"nx": nx, "rows": "+".join(map(str, args.rows)), "dofs": scene.n_dofs, "J": nx,
                       "ranks": comm.Get_size(), "states": states, "shear": shear, "lower": f"{mu.lower:.10g}",
                       "upper": f"{mu.upper:.10g}", "width": f"{mu.width:.3g}", "exact": mu.exact,
                       "seconds": round(statistics.median(times), 2), "repeats": len(times),
                       "peak_mb": round(st.peak), "load1": round(st.load1, 1), "evidence": mu.evidence[:160]}
                rows.append(row)
                if comm.Get_rank() == 0:
                    print({k: row[k] for k in FIELDS if k != "evidence"}, flush=True)
    if comm.Get_rank() == 0:
        def keep(r):  # replace the rows this run measured
            return not any(str(r["nx"]) == str(x["nx"]) and r["ranks"] == str(x["ranks"]) and r["states"] == x["states"]
                           and r["shear"] == str(x["shear"]) and r["rows"] == x["rows"] for x in rows)
        write_rows(out, rows, FIELDS, keep)


if __name__ == "__main__":
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    main()
