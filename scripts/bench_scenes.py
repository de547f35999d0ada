#!/usr/bin/env python3
"""The shipped scenes, run as shipped (issue 33): ``meicp solve`` on every scene file of
data/scenes with contact — found in the directory, so a scene shipped later is run too —
its verdicts (divergence and flutter) with their evidence, the wall time of the command,
the peak resident set of each rank, and one SLEPc eigen-solve of the same lattice beside it.

    .venv/bin/python scripts/bench_scenes.py run --lock /work/scratch/s30/heavy.lock
    .venv/bin/python scripts/bench_scenes.py run --only two_layers extensive_contact
    .venv/bin/python scripts/bench_scenes.py chart          # -> scenes.png

Scenes up to ``--large`` DOFs (default 2·10⁵) run serially on one rank; larger ones on
``--ranks`` ranks (default 2) under ``mpirun``, holding ``flock LOCK`` for both commands of
the scene when ``--lock`` is given (the shared machine's lock for heavy runs).  Each scene: the command
``meicp solve SCENE --no-output --json`` under ``/usr/bin/time`` (one per rank: its peak
resident set), then, in a fresh process on as many ranks, one shift-and-invert eigen-solve
of the scene's pencil (``bench_common.slepc_eigensolve``, 4 eigenvalues nearest 0): where a
contact line's states come from the static equilibrium (``states = "solve"``) that line is
held (``stick``) for this reference, whose states are not known before the run.  A re-run
appends its rows to ``scenes.csv`` (oldest first); the chart shows each scene's latest.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path

from bench_common import ROOT, csv_path, git_commit, read_rows, row_identity, rows_before, save_figure, write_rows
from meicp.core.blas_kernel import choose_openblas_kernel

SCENES = ROOT / "data" / "scenes"
FIELDS = ["scene", "dofs", "retained", "contacts", "ranks", "verdict", "divergence", "test", "sigma",
          "flutter", "status", "command_s", "solve_s", "analyze_s", "eigensolve_s", "ratio", "peak_mb", "eigensolve_peak_mb",
          "load1", "date", "commit", "evidence", "flutter_evidence"]
PEAK = re.compile(r"^bench-scenes-peak-kb (\d+)$", re.M)


def solve_scenes(only=None) -> list[Path]:
    """The scene files ``meicp solve`` decides: every data/scenes/*.toml with contact (a
    rough base or a frictional interface), by name."""
    import meicp
    from meicp.contact.modal import has_contact

    paths = sorted(SCENES.glob("*.toml"))
    if only:
        paths = [p for p in paths if p.stem in only]
    return [p for p in paths if has_contact(meicp.load_scene(p))]


def _command(args, ranks: int, tail: list[str]) -> list[str]:
    """``tail`` (a Python command line) on ``ranks`` ranks, each under /usr/bin/time."""
    timed = ["/usr/bin/time", "-f", "bench-scenes-peak-kb %M", sys.executable, *tail]
    return timed if ranks == 1 else ["mpirun", "-n", str(ranks), "--oversubscribe", *timed]


class _Lock:
    """``flock`` on ``path`` (exclusive, waiting) for the block; no path: nothing."""

    def __init__(self, path):
        self.path, self.file = path, None

    def __enter__(self):
        if self.path:
            import fcntl

            self.file = open(self.path, "a")
            fcntl.flock(self.file, fcntl.LOCK_EX)
        return self

    def __exit__(self, *exc):
        if self.file is not None:
            self.file.close()  # releases the lock


def _run(cmd: list[str], timeout: float, log: Path | None = None) -> tuple[str, list[float], float, bool]:
    """stdout, each rank's peak resident set (MB), wall seconds of the whole command
    (interpreter and MPI start included) and whether it timed out; stderr (meicp's progress
    lines) goes to ``log`` when given."""
    env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
           "PYTHONPATH": os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")])}
    choose_openblas_kernel(env)  # the same OpenBLAS kernel for meicp and the eigen-solve beside it
    t0 = time.perf_counter()
    try:
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env)
    except subprocess.TimeoutExpired as exc:
        out = exc.stdout.decode() if isinstance(exc.stdout, bytes) else (exc.stdout or "")
        if log is not None:
            err = exc.stderr.decode() if isinstance(exc.stderr, bytes) else (exc.stderr or "")
            log.write_text(err)
        return out, [], time.perf_counter() - t0, True
    if log is not None:
        log.write_text(done.stderr)
    peaks = [int(kb) / 1024 for kb in PEAK.findall(done.stderr)]
    if done.returncode != 0:
        print(done.stderr[-2000:], file=sys.stderr)
    return done.stdout, peaks, time.perf_counter() - t0, False


def run(args) -> None:
    import meicp

    rows = []
    before = rows_before(csv_path("scenes"))
    for path in solve_scenes(args.only):
        scene = meicp.load_scene(path)
        dofs = 2 * scene.nx * scene.ny
        ranks = args.ranks if dofs > args.large else 1
        if dofs > args.large and args.skip_large:
            continue
        rel = str(path.relative_to(ROOT))
        print(f"{path.stem}: {dofs:,} DOFs on {ranks} rank(s)", flush=True)
        log = Path(args.logs) / f"{path.stem}.log" if args.logs else None
        if log is not None:
            log.parent.mkdir(parents=True, exist_ok=True)  # before the runs, not after them
        side = side_by_side(args, ranks, rel, ["-v" if args.logs else "-q"], args.lock if ranks > 1 else None, log)
        doc, eig, peaks, eig_peaks, wall, timed_out, load1, solve_s = side
        proofs = doc.get("proofs") or [{}]
        modes = doc.get("modes") or []
        row = {"scene": path.name, "dofs": dofs, "retained": doc.get("sizes", {}).get("retained", ""),
               "contacts": doc.get("sizes", {}).get("complementarity", ""), "ranks": ranks,
               "verdict": "TIMEOUT" if timed_out else doc.get("verdict", "ERROR"),
               "divergence": doc.get("divergence"), "test": proofs[0].get("test", ""),
               "sigma": f"{modes[0]['sigma']:.10g}" if modes else "", "flutter": doc.get("flutter"),
               "status": doc.get("status", ""), "command_s": f"{wall:.2f}", "solve_s": f"{solve_s:.2f}",
               "analyze_s": f"{doc.get('timings', {}).get('total', float('nan')):.2f}",
               "eigensolve_s": f"{eig.get('seconds', float('nan')):.3f}",
               "ratio": f"{solve_s / eig['seconds']:.2f}" if eig.get("seconds") else "",
               "peak_mb": "/".join(f"{p:.0f}" for p in peaks),
               "eigensolve_peak_mb": "/".join(f"{p:.0f}" for p in eig_peaks),
               "load1": f"{load1:.1f}", "date": datetime.date.today().isoformat(), "commit": git_commit(),
               "evidence": (doc.get("evidence") or "")[:300],
               "flutter_evidence": (doc.get("flutter_evidence") or "")[:200]}
        rows.append(row)
        print({k: row[k] for k in FIELDS[:18]}, flush=True)
        write_rows(csv_path("scenes"), rows, FIELDS, keep=lambda r: row_identity(r) in before)
    undecided = [r["scene"] for r in rows if r["divergence"] is not True and r["divergence"] is not False]
    print(f"{len(rows)} scene(s); divergence undecided: {', '.join(undecided) or 'none'}")


def side_by_side(args, ranks: int, scene: str, flags: list[str], lock=None, log: Path | None = None) -> tuple:
    """``meicp solve SCENE --no-output --json`` (with ``flags``) and then one eigen-solve of
    the same scene's pencil (:func:`eigensolve`), on ``ranks`` ranks under ``flock lock``
    (both commands side by side, nothing heavy between).  Returns ``(doc, eig, peaks,
    eig_peaks, wall, timed_out, load1, solve_s)``: the solve's JSON ({} when it printed none),
    the eigen-solve's, each command's peak memory per rank, the solve command's wall seconds,
    whether it timed out, the load average before, and meicp's own clock ("wall.total": load +
    analyze; the whole command's wall when absent) to set against the eigen-solve's."""
    with _Lock(lock):
        load1 = os.getloadavg()[0]
        out, peaks, wall, timed_out = _run(_command(args, ranks, ["-m", "meicp", "solve", scene, "--no-output",
                                                                  "--json", *flags]), args.timeout, log)
        eig_out, eig_peaks, _, _ = _run(_command(args, ranks, [__file__, "eigensolve", scene]), args.timeout)
    doc = {}
    try:
        doc = json.loads(out) if out.strip() else {}
    except json.JSONDecodeError:
        pass
    eig = json.loads(eig_out.strip().splitlines()[-1]) if eig_out.strip() else {}
    return doc, eig, peaks, eig_peaks, wall, timed_out, load1, doc.get("wall", {}).get("total") or wall


def eigensolve(args) -> None:
    """One eigen-solve of the scene's pencil on this job's ranks; prints {"seconds": ...}
    on rank 0 (collective)."""
    from mpi4py import MPI

    import meicp
    from bench_common import slepc_eigensolve
    from meicp.contact import pencil
    from meicp.core.matrix import is_petsc_mat
    from meicp.petsc.mat import mat_from_scipy

    comm = MPI.COMM_WORLD
    scene = meicp.load_scene(ROOT / args.scene)
    if scene.contact is not None and scene.contact.states == "solve":
        scene = scene.with_states("stick")
    for interface in scene.interfaces:
        if not interface.bonded and interface.states == "solve":
            scene = scene.with_states("stick", interface=interface.below)
    with pencil(scene, comm=comm if comm.size > 1 else None) as pen:
        A, B = pen.A, pen.B
        if not is_petsc_mat(A):  # one rank: the pencil is SciPy
            A, B = mat_from_scipy(None, A), mat_from_scipy(None, B)
        comm.Barrier()
        t0 = time.perf_counter()
        slepc_eigensolve(A, B, min(4, max(1, pen.maps.retained.size - 1)))
        comm.Barrier()
        seconds = time.perf_counter() - t0
    if comm.rank == 0:
        print(json.dumps({"seconds": seconds}), flush=True)


def chart(args) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    latest = {r["scene"]: r for r in read_rows(csv_path("scenes"))}  # each scene's last run
    rows = sorted(latest.values(), key=lambda r: int(r["dofs"]))
    names = [f"{r['scene'].removesuffix('.toml')}\n{int(r['dofs']):,} DOFs, {r['ranks']} rank(s)" for r in rows]
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 0.55 * len(rows) + 1.8), sharey=True)
    y = range(len(rows))
    solve = [float(r["solve_s"]) for r in rows]
    eig = [float(r["eigensolve_s"]) for r in rows]
    ax.barh([v + 0.2 for v in y], solve, height=0.4, color="tab:blue", label="meicp solve (as shipped)")
    ax.barh([v - 0.2 for v in y], eig, height=0.4, color="tab:gray", label="one eigen-solve, same lattice")
    for v, r in zip(y, rows):
        div = {"True": "divergence", "False": "no divergence"}.get(r["divergence"], "divergence UNDECIDED")
        flu = {"True": "flutter", "False": "no flutter"}.get(r["flutter"], "flutter undecided")
        ax.annotate(f" {r['verdict']}: {div}, {flu}" + (f" ({r['ratio']}×)" if r["ratio"] else ""),
                    (float(r["solve_s"]), v + 0.2), va="center", fontsize=7)
    ax.set_xscale("log")
    ax.set_yticks(list(y), names, fontsize=7)
    ax.set_xlabel("wall time (s)")
    ax.legend(fontsize=7, loc="lower right")
    peak = [max(float(p) for p in r["peak_mb"].split("/")) if r["peak_mb"] else 0 for r in rows]
    eig_peak = [max(float(p) for p in r["eigensolve_peak_mb"].split("/")) if r["eigensolve_peak_mb"] else 0
                for r in rows]
    bx.barh([v + 0.2 for v in y], peak, height=0.4, color="tab:blue", label="meicp solve")
    bx.barh([v - 0.2 for v in y], eig_peak, height=0.4, color="tab:gray", label="eigen-solve")
    bx.set_xscale("log")
    bx.set_xlabel("peak resident set, largest rank (MB)")
    bx.legend(fontsize=7, loc="lower right")
    fig.suptitle("the shipped scenes, run as shipped (scripts/bench_scenes.py)", fontsize=10)
    save_figure(fig, csv_path("scenes").with_suffix(".png"), rect=(0, 0, 1, 0.96))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="what", required=True)
    r = sub.add_parser("run")
    r.add_argument("--only", nargs="+", help="scene file stems (default: every scene with contact)")
    r.add_argument("--large", type=int, default=200_000, help="DOFs above which a scene runs on --ranks ranks")
    r.add_argument("--ranks", type=int, default=2)
    r.add_argument("--skip-large", action="store_true", help="only the scenes up to --large DOFs")
    r.add_argument("--lock", help="flock this file around every run on several ranks")
    r.add_argument("--timeout", type=float, default=1800.0, help="seconds per command")
    r.add_argument("--logs", help="directory for each solve's progress lines (-v; default: -q, none kept)")
    e = sub.add_parser("eigensolve")
    e.add_argument("scene", help="path relative to the repository")
    sub.add_parser("chart")
    args = p.parse_args()
    globals()[args.what](args)


if __name__ == "__main__":
    main()
