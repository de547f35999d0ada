"""MUMPS' fill-reducing orderings on the scaling benchmark's eigen-solve: ``bench_scaling.py
--orderings [NAME ...]`` (see its docstring; CSV ``scaling_ordering.csv``).  One eigen-solve of the
main pencil per ordering, interleaved, after a check of which orderings this MUMPS build has."""

from __future__ import annotations

import statistics
import time

from bench_common import MUMPS_ORDER_NAME, Stage, csv_path, release_memory, write_rows
from bench_scaling import ORDERINGS, Runner, fmt_vals, main_pencil, match_error, slepc_eigs

ORDER_FIELDS = ["problem", "stage", "method", "settings", "ordering", "ordering_used", "ranks", "dofs", "n",
                "repeats", "wall_s", "wall_min_s", "wall_max_s", "setup_s", "iterations", "status", "error",
                "factor_entries", "flops", "peak_rss_mb", "above_base_mb", "cpu_frac", "load1", "lam", "detail"]


def orderings(run, dofs, names, reps):
    """One eigen-solve of the main pencil per MUMPS ordering, interleaved (rep-major,
    the order rotated each repeat) so that every ordering sees the same machine state."""
    comm, args = run.comm, run.args
    nx, ny, A, B = main_pencil(dofs, comm)
    n = A.getSize()[0]
    run.say(f"\norderings on lattice_{nx}x{ny}: n = {n}, {comm.size} rank(s), {reps} repeat(s): {names}")
    res = {k: dict(walls=[], setups=[], cpu=[], load=[], peak=0.0) for k in names}
    info = {}
    for rep in range(reps):
        order = names[rep % len(names):] + names[:rep % len(names)]
        for name in order:
            code = ORDERINGS[name]
            extra = {} if code is None else {"st_mat_mumps_icntl_7": code}
            info[name] = {}
            with Stage(comm) as st:
                vals, its = slepc_eigs(A, B, args.nev, comm, extra=extra, info=info[name])
            d = res[name]
            d["walls"].append(st.wall)
            d["setups"].append(max(comm.allgather(info[name]["setup_s"])))
            d["cpu"].append(st.cpu_frac)
            d["load"].append(st.load1)
            d["peak"] = max(d["peak"], st.peak)
            d["vals"], d["its"] = vals, its
            run.say(f"  rep {rep} {name:<6} {st.wall:8.3f} s (setup {d['setups'][-1]:.3f} s, "
                     f"ordering used {info[name].get('ordering_used')}, cpu {st.cpu_frac:.2f})")
    ref = res[names[0]]["vals"]
    rows = []
    for name in names:
        d, i = res[name], info[name]
        code = ORDERINGS[name]
        used = i.get("ordering_used", "")
        fell = code is not None and MUMPS_ORDER_NAME.get(code) != used
        rows.append(dict(
            problem=f"lattice_{nx}x{ny}", stage="eigensolve", method="slepc-krylovschur+mumps",
            settings=("ICNTL(7) default (7 = automatic choice)" if code is None else f"ICNTL(7)={code}")
            + f" sinvert target=0 nev={args.nev} tol=1e-10", ordering=name, ordering_used=used,
            ranks=comm.size, dofs=2 * nx * ny, n=n, repeats=reps,
            wall_s=f"{statistics.median(d['walls']):.4g}", wall_min_s=f"{min(d['walls']):.4g}",
            wall_max_s=f"{max(d['walls']):.4g}", setup_s=f"{statistics.median(d['setups']):.4g}",
            iterations=d["its"], status="solved (fell back to " + used + ")" if fell else "solved",
            error=f"{max(match_error(ref, d['vals']), match_error(d['vals'], ref)):.3g}",
            factor_entries=i.get("factor_entries", ""), flops=f"{i.get('flops', float('nan')):.4g}",
            peak_rss_mb=f"{d['peak']:.0f}", above_base_mb=f"{d['peak'] - run.base_mb:.0f}",
            cpu_frac=f"{min(d['cpu']):.2f}", load1=f"{max(d['load']):.2f}", lam=fmt_vals(d["vals"]),
            detail=f"error = eigenvalue disagreement with {names[0]}; setup_s = EPSSetUp (analysis + "
                   "factorisation), max over ranks; factor entries INFOG(29), flops RINFOG(3)"))
    for x in (A, B):
        if hasattr(x, "destroy"):
            x.destroy()
    del A, B
    release_memory()
    return rows

def ordering_availability(run):
    """Which of the orderings this MUMPS lacks, on a 10^4-DOF pencil: METIS and SCOTCH
    (ICNTL(7) = 5, 3: MUMPS falls back to its default, seen in INFOG(7)) and, on several
    ranks, the parallel analysis ICNTL(28) = 2 with ICNTL(29) = 1 (PT-Scotch) or 2
    (ParMETIS) (MUMPS stops with INFOG(1) = −38 without the tool)."""
    comm, rows = run.comm, []
    nx, ny, A, B = main_pencil(10_000, comm)
    checks = [("metis", "ICNTL(7)=5", {"st_mat_mumps_icntl_7": 5}),
              ("scotch", "ICNTL(7)=3", {"st_mat_mumps_icntl_7": 3})]
    if comm.size > 1:
        checks += [("pt-scotch", "ICNTL(28)=2 ICNTL(29)=1", {"st_mat_mumps_icntl_28": 2, "st_mat_mumps_icntl_29": 1}),
                   ("parmetis", "ICNTL(28)=2 ICNTL(29)=2", {"st_mat_mumps_icntl_28": 2, "st_mat_mumps_icntl_29": 2})]
    for name, settings, extra in checks:
        info = {}
        t0 = time.perf_counter()
        try:
            slepc_eigs(A, B, run.args.nev, comm, info=info, extra=extra)
            used = info.get("ordering_used", "")
            status = "available" if used.lower() == name else f"not available: fell back to {used}"
        except Exception as e:  # noqa: BLE001
            status = f"not available: MUMPS analysis failed ({str(e).splitlines()[0][:40]})"
        rows.append(dict(problem=f"lattice_{nx}x{ny}", stage="availability", method="slepc-krylovschur+mumps",
                         settings=settings, ordering=name, ordering_used=info.get("ordering_used", ""),
                         ranks=comm.size, dofs=2 * nx * ny, n=A.getSize()[0], repeats=1,
                         wall_s=f"{time.perf_counter() - t0:.4g}", status=status,
                         detail="availability check of the ordering in this MUMPS build"))
        run.say(f"  {name} ({settings}): {status}")
    for x in (A, B):
        if hasattr(x, "destroy"):
            x.destroy()
    return rows


def main(args):
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    names = args.orderings or ["auto", "amd", "amf"]
    dofs = args.dofs or ((10_000,) if args.quick else (300_000, 1_000_000))
    run = Runner(args, comm)
    t0 = time.perf_counter()
    rows = ordering_availability(run)
    for k, d in enumerate(dofs):
        reps = args.ordering_repeats[min(k, len(args.ordering_repeats) - 1)]
        rows += orderings(run, d, names, reps)
    if comm.rank == 0:
        out = csv_path("scaling_ordering")
        mine = str(comm.size)
        write_rows(out, rows, ORDER_FIELDS, keep=lambda r: r["ranks"] != mine)
        print(f"\nwrote {len(rows)} rows ({comm.size} rank(s)) to {out} in {time.perf_counter() - t0:.0f} s")
