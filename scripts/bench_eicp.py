#!/usr/bin/env python3
"""EiCP benchmark (issue 5): enumeration of the Z-family, active-set on a lattice pencil
against a single SLEPc solve of the same pencil, accuracy against the dense reference.

    .venv/bin/python scripts/bench_eicp.py enumerate --sizes 12 14 16
    mpirun -n 2 .venv/bin/python scripts/bench_eicp.py enumerate --sizes 16 18 20
    .venv/bin/python scripts/bench_eicp.py lattice --nx 1000          # 10^6 DOFs
    mpirun -n 2 .venv/bin/python scripts/bench_eicp.py lattice --nx 1000
    .venv/bin/python scripts/bench_eicp.py accuracy
    .venv/bin/python scripts/charts.py eicp docs/benchmarks/eicp.csv

Rows are appended to ``docs/benchmarks/eicp.csv`` (written to a temporary name, renamed).

Lattice pencil: a two-layer lattice (bottom and top rows fixed) with nx columns and
nx/2 rows, A = −K and B = M on the free DOFs; the complementarity set J is the vertical
(default) or horizontal DOFs of the lowest free row (nx ≥ 500 of them).  The single solve is one shift-and-invert
Krylov–Schur solve (MUMPS) of the full pencil with the same options, from scratch.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
import scipy.linalg

import meicp
from bench_common import csv_path, halves, peak_rss_bytes, slepc_eigensolve, write_rows
from meicp.examples import two_layer_scene
from meicp.lattice.model import LatticeModel
from meicp.petsc.assembly import principal_submatrix

OUT = csv_path("eicp")
FIELDS = ["experiment", "problem", "n", "J", "method", "settings", "ranks", "wall_s", "iterations",
          "status", "solutions", "residual", "error", "peak_rss_mb"]


def peak_mb(comm) -> float:
    """The largest peak resident set of the ranks so far, MB."""
    return max(comm.allgather(peak_rss_bytes() / 2**20))


def append_rows(rows, comm):
    if comm.rank != 0 or not rows:
        return
    write_rows(OUT, rows, FIELDS)
    print(f"appended {len(rows)} rows to {OUT}")


def z_family(n, seed=0):
    rng = np.random.default_rng(seed)
    A = -rng.uniform(0.1, 1.0, (n, n))
    np.fill_diagonal(A, rng.standard_normal(n))
    return A, np.diag(rng.uniform(0.5, 2.0, n))


def bench_enumerate(args, comm):
    rows = []
    for n in args.sizes:
        A, B = z_family(n)
        comm.Barrier()
        t0 = time.perf_counter()
        r = meicp.solve_eicp(A, B, method="enumerate", comm=comm if comm.size > 1 else None)
        wall = max(comm.allgather(time.perf_counter() - t0))
        ok = len(r.solutions) == 2 ** n - 1
        res = max(s.residual for s in r.solutions)
        rows.append(dict(experiment="enumerate", problem=f"z_family_{n}", n=n, J=n, method="enumerate",
                         settings="", ranks=comm.size, wall_s=f"{wall:.4g}", iterations=r.iterations,
                         status=r.status if ok else "wrong_count", solutions=len(r.solutions),
                         residual=f"{res:.3g}", error="", peak_rss_mb=f"{peak_mb(comm):.0f}"))
        if comm.rank == 0:
            print(f"z_family n={n}: {len(r.solutions)} solutions (expected {2 ** n - 1}) in {wall:.2f} s "
                  f"on {comm.size} rank(s), max residual {res:.1e}", flush=True)
    append_rows(rows, comm)


def lattice_pencil(nx, comm, dofs="y"):
    """(A = −K_ff, B = M_ff, J) as PETSc Mats on comm; J in reduced numbering."""
    ny = nx // 2
    scene = two_layer_scene(nx, halves(ny), bottom="fixed")
    model = LatticeModel(scene)
    K, M = meicp.assemble(model, comm)
    free = model.free_dofs()
    Kf, Mf = principal_submatrix(K, free), principal_submatrix(M, free)
    K.destroy()
    M.destroy()
    Kf.scale(-1.0)
    row1 = 2 * (nx + np.arange(nx))  # DOFs of nodes (i, 1): x at 2n, y at 2n + 1
    wanted = np.sort(np.concatenate([row1 + (c == "y") for c in dofs]))
    J = np.searchsorted(free, wanted)
    assert np.array_equal(free[J], wanted)
    return Kf, Mf, J


def bench_lattice(args, comm):
    rows = []
    t0 = time.perf_counter()
    A, B, J = lattice_pencil(args.nx, comm, args.dofs)
    t_build = max(comm.allgather(time.perf_counter() - t0))
    n = A.getSize()[0]
    if comm.rank == 0:
        print(f"lattice pencil: n = {n}, |J| = {J.size}, built in {t_build:.2f} s", flush=True)
    single, active = [], []
    for rep in range(args.repeat):
        comm.Barrier()
        t0 = time.perf_counter()
        vals, _ = slepc_eigensolve(A, B, args.nev, hermitian=True)
        nconv = vals.size
        lam0 = vals[0].real if nconv else float("nan")
        single.append(max(comm.allgather(time.perf_counter() - t0)))
        comm.Barrier()
        t0 = time.perf_counter()
        r = meicp.solve_eicp(A, B, J=J, method="active-set", target=0.0, nev=args.nev)
        active.append(max(comm.allgather(time.perf_counter() - t0)))
        if comm.rank == 0:
            print(f"  repeat {rep}: single solve {single[-1]:.2f} s (λ0 = {lam0:.6e}, {nconv} converged); "
                  f"active-set {active[-1]:.2f} s, {r.status}, λ = {r.lam}, "
                  f"{r.coverage.get('eigen_solves')} eigen-solves, "
                  f"{r.coverage.get('supports_visited')} supports", flush=True)
    mem = peak_mb(comm)
    res = r.solutions[0].residual if r.solutions else float("nan")
    common = dict(experiment="lattice", problem=f"lattice_nx{args.nx}", n=n, J=J.size, ranks=comm.size,
                  settings=f"J={args.dofs} nev={args.nev} target=0 sinvert+mumps", peak_rss_mb=f"{mem:.0f}")
    rows.append(dict(common, method="single-slepc-solve", wall_s=f"{statistics.median(single):.4g}",
                     iterations=1, status="solved", solutions="", residual="", error=""))
    rows.append(dict(common, method="active-set", wall_s=f"{statistics.median(active):.4g}",
                     iterations=r.coverage.get("eigen_solves"), status=r.status, solutions=len(r.solutions),
                     residual=f"{res:.3g}", error=""))
    if comm.rank == 0:
        print(f"median single {statistics.median(single):.2f} s, active-set {statistics.median(active):.2f} s, "
              f"ratio {statistics.median(active) / statistics.median(single):.2f}, peak RSS {mem:.0f} MB/rank")
    A.destroy()
    B.destroy()
    append_rows(rows, comm)


def bench_accuracy(args, comm):
    """Active-set and enumeration λ against a dense reference (eigvals of the certified
    support's pencil in extended care: numpy on the support), on random mixed problems."""
    rows = []
    rng = np.random.default_rng(7)
    for k in range(args.cases):
        n = int(rng.integers(8, 40))
        Jn = int(rng.integers(3, min(n, 12)))
        A = rng.standard_normal((n, n))
        A = A + A.T
        B = np.diag(rng.uniform(0.5, 2.0, n))
        J = np.sort(rng.choice(n, Jn, replace=False))
        for method in ("enumerate", "active-set"):
            t0 = time.perf_counter()
            r = meicp.solve_eicp(A, B, J=J, method=method, target=float(np.abs(A).sum(axis=1).max()))
            wall = time.perf_counter() - t0
            err = ""
            if r.solutions:
                errs = []
                for s in r.solutions:
                    F = np.setdiff1d(np.arange(n), J)
                    R = np.union1d(F, s.support)
                    ref = scipy.linalg.eigvalsh(A[np.ix_(R, R)], B[np.ix_(R, R)])
                    errs.append(np.min(np.abs(ref - s.lam)) / max(1.0, abs(s.lam)))
                err = f"{max(errs):.3g}"
            rows.append(dict(experiment="accuracy", problem=f"random_sym_{k}", n=n, J=Jn, method=method,
                             settings="", ranks=1, wall_s=f"{wall:.4g}", iterations=r.iterations,
                             status=r.status, solutions=len(r.solutions),
                             residual=f"{max((s.residual for s in r.solutions), default=float('nan')):.3g}",
                             error=err, peak_rss_mb=""))
    if comm.rank == 0:
        for method in ("enumerate", "active-set"):
            sel = [r for r in rows if r["method"] == method]
            ok = [r for r in sel if r["status"] == "solved"]
            print(f"{method}: {len(ok)}/{len(sel)} solved, max λ error "
                  f"{max(float(r['error']) for r in ok):.1e}, max residual {max(float(r['residual']) for r in ok):.1e}")
    append_rows(rows, comm)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="what", required=True)
    e = sub.add_parser("enumerate")
    e.add_argument("--sizes", nargs="+", type=int, default=[12, 14, 16])
    la = sub.add_parser("lattice")
    la.add_argument("--nx", type=int, default=1000)
    la.add_argument("--nev", type=int, default=4)
    la.add_argument("--dofs", default="y", choices=["x", "y", "xy"],
                    help="which DOFs of the lowest free row form J (x: the lowest mode is already feasible)")
    la.add_argument("--repeat", type=int, default=1)
    a = sub.add_parser("accuracy")
    a.add_argument("--cases", type=int, default=30)
    args = p.parse_args()
    from mpi4py import MPI

    {"enumerate": bench_enumerate, "lattice": bench_lattice, "accuracy": bench_accuracy}[args.what](args, MPI.COMM_WORLD)


if __name__ == "__main__":
    main()
