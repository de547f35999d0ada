#!/usr/bin/env python3
"""``meicp.critical_friction`` past the enumeration limit (issue 14 part 4): the certified
bracket's width and wall time on the two-layer scene (``two_layer_scene``), base contacts all
slip+ or all slip−, shear ±0.5, |J| = nx contacts.  Targets: |J| = 100 under 60 s, width
≤ 5 % (exact); |J| = 1,000 (10⁶ DOFs, 2 ranks) under 5 minutes, width reported.

    .venv/bin/python scripts/bench_critical_friction.py --nx 100 --rows 25 25 --repeats 3
    flock /work/scratch/bench.lock mpirun -n 2 .venv/bin/python scripts/bench_critical_friction.py \\
        --nx 1000 --rows 250 250 --repeats 1          # -> docs/benchmarks/critical_friction.csv

Each row: the median wall time of ``repeats`` calls (scene built outside the timing), the
bracket, its width, whether it is exact, and the evidence's first words.
"""

from __future__ import annotations

import argparse
import os
import statistics

from bench_common import Stage, csv_path, write_rows
from meicp.contact.critical_friction import critical_friction
from meicp.examples import two_layer_scene

FIELDS = ["nx", "rows", "dofs", "J", "ranks", "states", "shear", "lower", "upper", "width", "exact", "seconds",
          "repeats", "peak_mb", "load1", "evidence"]


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--nx", type=int, nargs="+", default=[100])
    p.add_argument("--rows", type=int, nargs=2, default=[25, 25])
    p.add_argument("--states", nargs="+", default=["slip+", "slip-"])
    p.add_argument("--shear", type=float, nargs="+", default=[0.5, -0.5])
    p.add_argument("--repeats", type=int, default=3)
    args = p.parse_args()
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    out = csv_path("critical_friction")
    rows = []
    for nx in args.nx:
        for states in args.states:
            for shear in args.shear:
                scene = two_layer_scene(nx, tuple(args.rows), mu=1.0, states=states, shear=shear)
                times, mu = [], None
                for _ in range(args.repeats):
                    with Stage(comm) as st:
                        mu = critical_friction(scene, comm=comm)
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
