#!/usr/bin/env python3
"""Benchmark: assembly of K and M of a two-layer lattice, 10^4 .. 10^6 DOFs.

Run serially (SciPy CSR and PETSc on 1 rank) and under ``mpirun -n 2`` (PETSc on 2 ranks)::

    OMP_NUM_THREADS=1 .venv/bin/python scripts/bench_assembly.py
    OMP_NUM_THREADS=1 mpirun -n 2 --oversubscribe .venv/bin/python scripts/bench_assembly.py
    .venv/bin/python scripts/charts.py assembly docs/benchmarks/assembly.csv   # -> assembly.png

Each run replaces, in ``docs/benchmarks/assembly.csv``, the rows of its own (method, ranks)
and appends one row per repeat: problem, method, settings, ranks, dofs, repeat, wall time
(barrier to barrier), peak memory during the assembly above the memory before it
(``rss_peak_mb``: the kernel's peak resident set, summed over ranks; ``rank_ratio``: the
largest per-rank peak / that rank's matrix storage), the tracemalloc peak of the Python-side
temporaries (one extra, untimed repeat), nnz, matrix bytes (values + column indices + row
starts of K and M) and status (``ok`` when nnz equals 4·nodes + 8·bonds).
"""

from __future__ import annotations

import argparse
import resource
import sys
import tracemalloc
from pathlib import Path

import numpy as np

import meicp
from bench_common import Stage, csv_path, halves, lattice_shape, release_memory, write_rows
from meicp.examples import two_layer_scene
from meicp.petsc import import_petsc
from meicp.petsc.mat import nonzeros, storage_bytes

CSV = csv_path("assembly")
FIELDS = ["problem", "method", "settings", "ranks", "dofs", "repeat", "wall_s", "rss_peak_mb",
          "rank_ratio", "ru_maxrss_mb", "tracemalloc_peak_mb", "nnz", "matrix_mb", "status"]
TARGET_DOFS = (10_000, 30_000, 100_000, 300_000, 1_000_000)


def scene_of(dofs: int):
    """The two-layer lattice of about ``dofs`` DOFs, bottom and top rows fixed."""
    nx, ny = lattice_shape(dofs)
    return two_layer_scene(nx, halves(ny), bottom="fixed")


def expected_nnz(nx: int, ny: int) -> int:
    bonds = (nx - 1) * ny + nx * (ny - 1) + 2 * (nx - 1) * (ny - 1)
    return 4 * nx * ny + 8 * bonds + 2 * nx * ny  # K, then the diagonal M


def matrix_bytes(K, M, method) -> int:
    if method == "scipy":
        return sum(A.data.nbytes + A.indices.nbytes + A.indptr.nbytes for A in (K, M))
    return storage_bytes(K) + storage_bytes(M)


def nnz_of(K, M, method) -> int:
    if method == "scipy":
        return K.nnz + M.nnz
    return sum(nonzeros(A, total=False)["nz_used"] for A in (K, M))


def run_once(scene, method, comm, *, trace=False):
    """One assembly; returns (wall seconds, peak RSS delta bytes, tracemalloc peak, nnz, bytes)."""
    if trace:
        tracemalloc.start()
    with Stage(comm) as mem:
        K, M = meicp.assemble(scene, None if method == "scipy" else comm)
    tm_peak = 0
    if trace:
        tm_peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    nnz, nbytes = nnz_of(K, M, method), matrix_bytes(K, M, method)
    if method != "scipy":
        K.destroy()
        M.destroy()
    del K, M
    release_memory()
    return mem.wall, mem.delta, tm_peak, nnz, nbytes


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dofs", type=int, nargs="+", default=list(TARGET_DOFS))
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--methods", nargs="+", default=None,
                        help="scipy and/or petsc (default: both on 1 rank, petsc on several)")
    parser.add_argument("--csv", type=Path, default=CSV)
    args = parser.parse_args(argv)

    from mpi4py import MPI

    import_petsc()
    comm = MPI.COMM_WORLD
    rank, size = comm.Get_rank(), comm.Get_size()
    methods = args.methods or (["scipy", "petsc"] if size == 1 else ["petsc"])
    if size > 1 and "scipy" in methods:
        raise SystemExit("scipy assembly is serial: run it without mpirun")
    run_once(scene_of(10_000), methods[0], comm)  # warm-up: imports, first-touch
    rows = []
    for dofs in sorted(args.dofs):
        scene = scene_of(dofs)
        problem = f"two-layer {scene.nx}x{scene.ny}"
        want = expected_nnz(scene.nx, scene.ny)
        for method in methods:
            ru0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
            _, _, tm_peak, _, _ = run_once(scene, method, comm, trace=True)
            tm_total = comm.allreduce(tm_peak)
            for rep in range(args.repeats):
                wall, delta, _, nnz, nbytes = run_once(scene, method, comm)
                ru = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
                deltas, sizes_b = comm.allgather(delta), comm.allgather(nbytes)
                nnz_total = comm.allreduce(nnz)
                status = "ok" if nnz_total == want else f"nnz {nnz_total} != {want}"
                rows.append({
                    "problem": problem, "method": method,
                    "settings": f"nx={scene.nx};ny={scene.ny};layers=2",
                    "ranks": size, "dofs": scene.n_dofs, "repeat": rep, "wall_s": f"{wall:.4f}",
                    "rss_peak_mb": f"{sum(deltas) / 2**20:.1f}",
                    "rank_ratio": f"{max(d / b for d, b in zip(deltas, sizes_b)):.3f}",
                    "ru_maxrss_mb": f"{comm.allreduce(ru - ru0) / 1024:.1f}",
                    "tracemalloc_peak_mb": f"{tm_total / 2**20:.1f}",
                    "nnz": nnz_total, "matrix_mb": f"{sum(sizes_b) / 2**20:.1f}", "status": status})
            if rank == 0:
                mine = [r for r in rows if r["method"] == method and r["dofs"] == scene.n_dofs]
                med = float(np.median([float(r["wall_s"]) for r in mine]))
                print(f"{problem:>22} {method:>5} {size} rank(s): median {med:.3f} s, "
                      f"peak {mine[-1]['rss_peak_mb']} MB over {mine[-1]['matrix_mb']} MB of matrices "
                      f"(max rank ratio {mine[-1]['rank_ratio']}), {mine[-1]['status']}", flush=True)
    if rank == 0:
        write_rows(args.csv, rows, FIELDS,
                             keep=lambda r: not (int(r["ranks"]) == size and r["method"] in methods))
        print(f"wrote {args.csv}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
