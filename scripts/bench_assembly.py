#!/usr/bin/env python3
"""Benchmark: assembly of K and M of a two-layer lattice, 10^4 .. 10^6 DOFs.

Run serially (SciPy CSR and PETSc on 1 rank) and under ``mpirun -n 2`` (PETSc on 2 ranks)::

    OMP_NUM_THREADS=1 .venv/bin/python scripts/bench_assembly.py
    OMP_NUM_THREADS=1 mpirun -n 2 --oversubscribe .venv/bin/python scripts/bench_assembly.py
    .venv/bin/python scripts/charts.py assembly docs/benchmarks/assembly.csv   # -> assembly.png

Each run replaces, in ``docs/benchmarks/assembly.csv``, the rows of its own (method, ranks)
and appends one row per repeat: problem, method, settings, ranks, dofs, repeat, wall time
(barrier to barrier), peak memory during the assembly above the memory before it
(``rss_peak_mb``: sampled resident set, summed over ranks; ``rank_ratio``: the largest
per-rank peak / that rank's matrix storage), the tracemalloc peak of the Python-side
temporaries (one extra, untimed repeat), nnz, matrix bytes (values + column indices + row
starts of K and M) and status (``ok`` when nnz equals 4·nodes + 8·bonds).
"""

from __future__ import annotations

import argparse
import gc
import math
import os
import resource
import sys
import threading
import time
import tracemalloc
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
sys.path.insert(0, str(ROOT / "scripts"))

import bench_csv  # noqa: E402
from meicp.io.scene import scene_from_dict  # noqa: E402
from meicp.lattice.assembly import assemble  # noqa: E402

CSV = bench_csv.csv_path("assembly")
FIELDS = ["problem", "method", "settings", "ranks", "dofs", "repeat", "wall_s", "rss_peak_mb",
          "rank_ratio", "ru_maxrss_mb", "tracemalloc_peak_mb", "nnz", "matrix_mb", "status"]
TARGET_DOFS = (10_000, 30_000, 100_000, 300_000, 1_000_000)
PAGE = os.sysconf("SC_PAGE_SIZE")


def two_layer_scene(dofs: int):
    """A two-layer lattice, nx = 2·ny, about ``dofs`` DOFs (10^6 exactly is data/scenes/extensive.toml)."""
    ny = max(2, 2 * round(math.sqrt(dofs / 4) / 2))
    nx = 2 * ny
    if dofs == 1_000_000:
        nx, ny = 1000, 500
    scene = scene_from_dict({
        "lattice": {"nx": nx, "spacing": 1.0},
        "layers": [{"name": "A", "rows": ny // 2, "stiffness": 1.0, "density": 1.0},
                   {"name": "B", "rows": ny - ny // 2, "stiffness": 5.0, "density": 2.0}],
        "boundary": {"top": "fixed", "bottom": "fixed"}})
    return scene


def expected_nnz(nx: int, ny: int) -> int:
    bonds = (nx - 1) * ny + nx * (ny - 1) + 2 * (nx - 1) * (ny - 1)
    return 4 * nx * ny + 8 * bonds + 2 * nx * ny  # K, then the diagonal M


def release_freed_memory() -> None:
    """Give freed heap pages back to the OS (glibc keeps them resident for reuse otherwise,
    which would hide the next run's peak)."""
    gc.collect()
    try:
        import ctypes

        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):
        pass


def rss_bytes() -> int:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * PAGE


class PeakRSS:
    """Peak resident set size while the block runs, sampled every 0.2 ms by a thread."""

    def __enter__(self):
        self.start = self.peak = rss_bytes()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()
        return self

    def _run(self):
        while not self._stop.is_set():
            self.peak = max(self.peak, rss_bytes())
            time.sleep(0.0002)

    def __exit__(self, *exc):
        self.peak = max(self.peak, rss_bytes())
        self._stop.set()
        self._thread.join()

    @property
    def delta(self) -> int:
        return self.peak - self.start


def matrix_bytes(K, M, method) -> int:
    if method == "scipy":
        return sum(A.data.nbytes + A.indices.nbytes + A.indptr.nbytes for A in (K, M))
    from meicp.petsc.assembly import storage_bytes

    return storage_bytes(K) + storage_bytes(M)


def nnz_of(K, M, method) -> int:
    if method == "scipy":
        return K.nnz + M.nnz
    return sum(int(A.getInfo(A.InfoType.LOCAL)["nz_used"]) for A in (K, M))


def run_once(scene, method, comm, *, trace=False):
    """One assembly; returns (wall seconds, peak RSS delta bytes, tracemalloc peak, nnz, bytes)."""
    release_freed_memory()
    comm.Barrier()
    if trace:
        tracemalloc.start()
    with PeakRSS() as mem:
        t0 = time.perf_counter()
        K, M = assemble(scene, None if method == "scipy" else comm)
        comm.Barrier()
        wall = time.perf_counter() - t0
    tm_peak = 0
    if trace:
        tm_peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    nnz, nbytes = nnz_of(K, M, method), matrix_bytes(K, M, method)
    if method != "scipy":
        K.destroy()
        M.destroy()
    del K, M
    release_freed_memory()
    return wall, mem.delta, tm_peak, nnz, nbytes


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dofs", type=int, nargs="+", default=list(TARGET_DOFS))
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--methods", nargs="+", default=None,
                        help="scipy and/or petsc (default: both on 1 rank, petsc on several)")
    parser.add_argument("--csv", type=Path, default=CSV)
    args = parser.parse_args(argv)

    from mpi4py import MPI

    from meicp.petsc import import_petsc

    import_petsc()
    comm = MPI.COMM_WORLD
    rank, size = comm.Get_rank(), comm.Get_size()
    methods = args.methods or (["scipy", "petsc"] if size == 1 else ["petsc"])
    if size > 1 and "scipy" in methods:
        raise SystemExit("scipy assembly is serial: run it without mpirun")
    run_once(two_layer_scene(10_000), methods[0], comm)  # warm-up: imports, first-touch
    rows = []
    for dofs in sorted(args.dofs):
        scene = two_layer_scene(dofs)
        problem = f"two-layer {scene.nx}x{scene.ny}"
        want = expected_nnz(scene.nx, scene.ny)
        for method in methods:
            ru0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
            _, _, tm_peak, _, _ = run_once(scene, method, comm, trace=True)
            tm_total = comm.allreduce(tm_peak)
            for rep in range(args.repeats):
                wall, delta, _, nnz, nbytes = run_once(scene, method, comm)
                ru = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
                wall = comm.allreduce(wall, op=MPI.MAX)
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
        bench_csv.write_rows(args.csv, rows, FIELDS,
                             keep=lambda r: not (int(r["ranks"]) == size and r["method"] in methods))
        print(f"wrote {args.csv}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
