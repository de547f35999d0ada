"""Where the large-scale flutter search's time goes, and what its solver options change
(docs/benchmarks.md, Flutter, session 22).

    mpirun -n 2 .venv/bin/python scripts/profile_flutter.py 1000000 rounds 2
    mpirun -n 2 .venv/bin/python scripts/profile_flutter.py 300000 variants base= off= off=eps_ncv=28 \
        off=st_mat_mumps_cntl_7=1e-8 base=

``rounds N``: N interleaved pairs (one SLEPc eigen-solve of the pencil, as
``bench_flutter.py cost``; then ``pencil_flutter`` as ``analyze`` runs it), *without*
handing freed memory back in between (the benchmark's ``Stage`` does): per stage the
wall time, the PETSc log events (MUMPS analysis, factorisation, solves and their count) and
this rank's page faults and system time — the first round is cold, the next warm.

``variants``: each argument one run in this process: ``base=`` the eigen-solve, ``off=KEY=V,...``
the search at the proxy's target moved off its cluster (as from 2·10⁵ retained DOFs) with
a basis of 32 on the 2n form and the given ``-meicp_flutter_*`` options added.
Scenes: ``bench_flutter.scene_of`` (μ = 2, slip+).  Under ``flock /work/scratch/bench.lock``.
"""
from __future__ import annotations

import resource
import sys
import time

from bench_common import slepc_eigensolve
from bench_flutter import scene_of
from meicp.contact import flutter as fl
from meicp.contact.problem import pencil
from meicp.contact.result import growth_frequency
from meicp.petsc import import_petsc

EVENTS = ["MatLUFactorSym", "MatLUFactorNum", "MatSolve"]


def snapshot(PETSc) -> dict:
    out = {e: PETSc.Log.Event(e).getPerfInfo()["time"] for e in EVENTS}
    out["solves"] = PETSc.Log.Event("MatSolve").getPerfInfo()["count"]
    r = resource.getrusage(resource.RUSAGE_SELF)
    out["faults"], out["sys"] = r.ru_minflt, r.ru_stime
    return out


def main() -> None:
    from mpi4py import MPI

    PETSc = import_petsc()
    PETSc.Log.begin()
    comm = MPI.COMM_WORLD
    dofs, mode, rest = int(sys.argv[1]), sys.argv[2], sys.argv[3:]
    scene = scene_of(dofs)
    with pencil(scene, comm=comm) as pen:
        base = next(cs.states for cs in pen.sets if cs.name == "base")
        tau = fl.off_cluster(complex(fl.proxy_targets(scene, list(base), 1)[0]), 0)
        runs = [r for _ in range(int(rest[0])) for r in ("base=", "search=")] if mode == "rounds" else rest
        for run in runs:
            kind, _, opts = run.partition("=")
            options = dict(kv.split("=") for kv in opts.split(",") if kv)
            s0, t0 = snapshot(PETSc), time.perf_counter()
            if kind == "base":
                slepc_eigensolve(pen.A, pen.B, 4, extra={"st_mat_mumps_icntl_7": 2})
                label = "eigen-solve"
            elif kind == "search":
                res = fl.pencil_flutter(pen, scene, comm)
                label = f"flutter search (analyze's): {res.flutter}"
            else:
                res = fl.pencil_flutter(pen, scene, comm, targets=[tau], options={"eps_ncv": 32, **options},
                                        off_cluster_tries=0)
                found = (f"growth {growth_frequency(res.modes[0][0])[0]:.5f}, backward error {res.modes[0][2]:.1e}, "
                         f"{len(res.modes)} modes" if res.modes else "no certified mode")
                label = f"search at {tau:.4f} {options}: {res.flutter}, {found}"
            wall, s1 = time.perf_counter() - t0, snapshot(PETSc)
            d = {k: s1[k] - s0[k] for k in s0}
            if comm.rank == 0:
                print(f"{wall:7.2f} s  analysis {d['MatLUFactorSym']:.2f}  factor {d['MatLUFactorNum']:.2f}  "
                      f"solves {d['MatSolve']:.2f} ({d['solves']})  faults {d['faults']:,}  sys {d['sys']:.2f}  "
                      f"{label}", flush=True)


if __name__ == "__main__":
    main()
