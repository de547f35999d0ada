#!/usr/bin/env python3
"""LCP benchmark: meicp's methods against Siconos (Lemke, enumeration, Newton-FB, PGS).

Families:
- ``siconos``: the Siconos test set vendored in ``tests/data/siconos-lcp`` (dense, n ≤ 40);
- ``condensed``: dense SPD contact-like LCPs — a 2-D grid Laplacian condensed (Schur
  complement) onto its bottom row, the contact DOFs; q pushes half the contacts in;
- ``laplacian``: sparse SPD 2-D Laplacian + 0.05 I with random q, n = 10² … 10⁵;
- ``lattice``: the elastic two-layer lattice's stiffness (``meicp.assemble``, top row held)
  restricted to the vertical DOFs of every other node — every node a potential contact —
  sparse SPD, with random q, n = 10² … 10⁵.

Each (problem, method) runs ``--repeat`` times; the CSV row holds the median wall time.
Under ``mpirun -n 2`` only the distributed PETSc methods run (newton, tao) on the
``laplacian`` family, with the matrix distributed from per-rank rows.

    .venv/bin/python scripts/bench_lcp.py --out docs/benchmarks/lcp.csv
    mpirun -n 2 .venv/bin/python scripts/bench_lcp.py --out docs/benchmarks/lcp.csv --append
    .venv/bin/python scripts/charts.py lcp docs/benchmarks/lcp.csv
"""

from __future__ import annotations

import argparse
import sys

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import meicp
from bench_common import ROOT, csv_path, timed, write_rows
from meicp.examples import two_layer_scene
from meicp.io.problem_files import read_siconos_lcp
from meicp.lcp.siconos import siconos_solve
from meicp.lcp.solve import solve_lcp
from meicp.petsc.mat import mat_from_local_csr, ownership
from meicp.petsc.selfcheck import laplacian_rows

FIELDS = ["family", "problem", "n", "method", "settings", "ranks", "wall_s", "iterations",
          "status", "residual", "error"]


def laplacian(m: int):
    n = m * m
    M = (laplacian_rows(m, m, 0, n) + 0.05 * sp.eye(n)).tocsr()
    q = np.random.default_rng(m).standard_normal(n)
    return M, q


def lattice(nx: int):
    """The two-layer lattice K restricted to the y DOFs of its free nodes (sparse SPD)."""
    ny = max(2, nx // 2)
    scene = two_layer_scene(nx, (ny - ny // 2, ny // 2), bottom="free")
    K, _ = meicp.assemble(scene)
    y = 2 * np.arange(nx * (ny - 1)) + 1  # y DOFs below the held top row
    M = K[y][:, y].tocsr()
    q = np.random.default_rng(nx).standard_normal(y.size)
    return M, q


def condensed(n_contacts: int, height: int = 20):
    """Schur complement of an n × height grid Laplacian onto its bottom row (dense SPD)."""
    m = n_contacts
    K = laplacian_rows(m, height, 0, m * height).tocsc()
    c = np.arange(m)
    i = np.arange(m, m * height)
    Kii = K[i][:, i].tocsc()
    Kic = K[i][:, c].toarray()
    S = K[c][:, c].toarray() - K[c][:, i] @ spla.splu(Kii).solve(Kic)
    S = 0.5 * (S + S.T)
    rng = np.random.default_rng(n_contacts)
    q = np.where(np.arange(m) % 2 == 0, -1.0, 0.5) * (1 + 0.1 * rng.random(m))
    return S, q


def row(family, problem, n, method, settings, ranks, wall, r, ref):
    err = ""
    if r.x is not None and ref is not None:
        err = float(np.max(np.abs(r.x - ref)) / max(np.max(np.abs(ref)), 1e-300))
    return dict(family=family, problem=problem, n=n, method=method, settings=settings, ranks=ranks,
                wall_s=f"{wall:.6g}", iterations=r.iterations, status=r.status,
                residual=f"{r.residual:.3g}" if np.isfinite(r.residual) else "", error=err if err == "" else f"{err:.3g}")


def serial_runs(args):
    rows = []
    problems = []
    if "siconos" in args.families:
        for path in sorted((ROOT / "tests" / "data" / "siconos-lcp").glob("*.dat")):
            M, q, _ = read_siconos_lcp(path)
            problems.append(("siconos", path.stem, M, q))
    if "condensed" in args.families:
        for n in args.condensed_sizes:
            M, q = condensed(n)
            problems.append(("condensed", f"condensed_{n}", M, q))
    if "laplacian" in args.families:
        for m in args.laplacian_sides:
            M, q = laplacian(m)
            problems.append(("laplacian", f"laplacian_{m * m}", M, q))
    if "lattice" in args.families:
        for nx in args.lattice_sides:
            M, q = lattice(nx)
            problems.append(("lattice", f"lattice_{len(q)}", M, q))
    for family, name, M, q in problems:
        n = len(q)
        dense_ok = n <= args.dense_limit
        ours = ["auto", "lemke", "newton", "tao", "pgs"] + (["enumerate"] if n <= 12 else [])
        theirs = (["lemke", "newton-fb", "pgs"] + (["enum"] if n <= 12 else [])) if dense_ok else []
        ref = None
        results = []
        for method in ours:
            if method == "lemke" and not dense_ok:
                continue
            if method == "pgs" and (family == "siconos"):
                continue  # PGS needs symmetric positive-diagonal M, which most of the set is not
            try:
                kw = {"max_iter": args.pgs_sweeps} if method == "pgs" else {}
                wall, _, r = timed(lambda: solve_lcp(M, q, method=method, **kw), repeats=args.repeat)
            except Exception as exc:  # noqa: BLE001 - a benchmark records failures
                print(f"{name} {method}: {type(exc).__name__}: {exc}", file=sys.stderr)
                continue
            results.append(("meicp-" + method, wall, r))
            if r.success and ref is None:
                ref = r.x
        for solver in theirs:
            wall, _, r = timed(lambda: siconos_solve(M, q, solver), repeats=args.repeat if n < 500 else 1)
            results.append(("siconos-" + solver, wall, r))
        for method, wall, r in results:
            rows.append(row(family, name, n, method, "tol=1e-10", 1, wall, r, ref))
            print(f"{name:40s} {method:20s} {wall:9.4f}s {r.status:18s} res={r.residual:.2e}", flush=True)
    return rows


def distributed_runs(args, comm):
    rows = []
    for m in args.laplacian_sides:
        n = m * m
        lo, hi = ownership(n, comm.rank, comm.size)
        local = (laplacian_rows(m, m, lo, hi) + 0.05 * sp.eye(n, format="csr")[lo:hi]).tocsr()
        A = mat_from_local_csr(comm, local, n)
        q = np.random.default_rng(m).standard_normal(n)
        for method in ("newton", "tao"):
            comm.Barrier()
            wall, _, r = timed(lambda: solve_lcp(A, q, method=method), repeats=args.repeat)
            wall = max(comm.allgather(wall))
            rows.append(row("laplacian", f"laplacian_{n}", n, "meicp-" + method, "tol=1e-10",
                            comm.size, wall, r, None))
            if comm.rank == 0:
                print(f"laplacian_{n:<30d} {method:20s} {wall:9.4f}s {r.status} res={r.residual:.2e}", flush=True)
        A.destroy()
    return rows


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", default=str(csv_path("lcp")))
    p.add_argument("--append", action="store_true")
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--families", nargs="+", default=["siconos", "condensed", "laplacian", "lattice"])
    p.add_argument("--condensed-sizes", nargs="+", type=int, default=[10, 30, 100, 300, 1000])
    p.add_argument("--laplacian-sides", nargs="+", type=int, default=[4, 10, 32, 100, 316])
    p.add_argument("--lattice-sides", nargs="+", type=int, default=[15, 45, 142, 448],
                   help="nx of the lattice family (n ≈ nx²/2 unknowns)")
    p.add_argument("--dense-limit", type=int, default=1000, help="largest n for dense methods and Siconos")
    p.add_argument("--pgs-sweeps", type=int, default=5000, help="PGS sweep limit (it fails beyond)")
    p.add_argument("--quick", action="store_true", help="small sizes only, one repeat")
    args = p.parse_args()
    if args.quick:
        args.repeat, args.condensed_sizes, args.laplacian_sides = 1, [10, 100], [4, 10, 32]
        args.lattice_sides = [15, 45]
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    rows = serial_runs(args) if comm.size == 1 else distributed_runs(args, comm)
    if comm.rank == 0:
        write_rows(args.out, rows, FIELDS, keep=lambda r: args.append)
        print(f"wrote {len(rows)} rows to {args.out}")


if __name__ == "__main__":
    main()
