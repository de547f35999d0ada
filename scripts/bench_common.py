"""What every benchmark script measures with, in one place: where results go (CSV rows
appended to what is kept of the file, written under a temporary name and renamed, never
half-written), wall time, peak memory, one reference SLEPc eigen-solve, and the lattice
shape of a DOF count (the scene itself is :func:`meicp.examples.two_layer_scene`).

Results go to ``$MEICP_BENCH_DIR`` if set (``make bench`` quick mode: ``build/benchmarks``),
else ``docs/benchmarks`` (the committed full-mode results).  The scripts run with the
project's venv (``.venv/bin/python scripts/bench_NAME.py``), which has meicp installed.
"""

from __future__ import annotations

import csv
import ctypes
import gc
import math
import os
import statistics
import subprocess
import time
from pathlib import Path

import numpy as np

from meicp.petsc import import_slepc
from meicp.petsc.options import OptionsScope

ROOT = Path(__file__).resolve().parents[1]
#: MUMPS ICNTL(7) ordering codes and names (INFOG(7) reports the one used)
MUMPS_ORDER_NAME = {0: "AMD", 2: "AMF", 3: "SCOTCH", 4: "PORD", 5: "METIS", 6: "QAMD", 7: "auto"}


# ----------------------------------------------------------------------------- CSV

def git_commit() -> str:
    """The short hash of the checkout's HEAD ("" without git): the code a benchmark row measured."""
    try:
        return subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True).stdout.strip()
    except OSError:
        return ""


def out_dir() -> Path:
    """Where CSVs and charts go (created if missing)."""
    d = Path(os.environ.get("MEICP_BENCH_DIR") or ROOT / "docs" / "benchmarks")
    d.mkdir(parents=True, exist_ok=True)
    return d


def csv_path(name: str) -> Path:
    """``out_dir() / f"{name}.csv"``: the CSV of benchmark ``name`` (also its chart's name)."""
    return out_dir() / f"{name}.csv"


def read_rows(path) -> list[dict]:
    """The rows of a benchmark CSV, as dicts of strings."""
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def row_identity(row: dict) -> frozenset:
    """A CSV row's identity across a change of columns: its non-empty fields (a column added
    since the row was written reads back empty and does not make it another row)."""
    return frozenset((k, v) for k, v in row.items() if v not in ("", None))


def rows_before(path) -> set:
    """The identities of the rows a CSV has now (none when it does not exist): a re-run keeps
    them, ``keep=lambda r: row_identity(r) in before``."""
    path = Path(path)
    return {row_identity(r) for r in read_rows(path)} if path.exists() else set()


def write_rows(path, rows: list, fields: list, keep=lambda row: True) -> None:
    """Write ``rows`` after the existing rows for which ``keep(row)`` is true."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    kept = []
    if path.exists():
        with path.open(newline="") as f:
            kept = [r for r in csv.DictReader(f) if keep(r)]
    tmp = path.with_name(path.name + ".part")
    with tmp.open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields)
        w.writeheader()
        w.writerows(kept + rows)
    os.replace(tmp, path)


# ----------------------------------------------------------------------------- sizes

def lattice_shape(dofs: int) -> tuple[int, int]:
    """``(nx, ny)`` with nx = 2·ny and about ``dofs`` DOFs; 10^6 exactly is 1000 × 500 (the
    lattice of data/scenes/extensive.toml)."""
    if dofs == 1_000_000:
        return 1000, 500
    ny = max(2, 2 * round(math.sqrt(dofs / 4) / 2))
    return 2 * ny, ny


def halves(ny: int) -> tuple[int, int]:
    """``ny`` rows split into (lower, upper), the lower layer the thinner when ny is odd."""
    return ny // 2, ny - ny // 2


# ----------------------------------------------------------------------------- memory

def release_memory() -> None:
    """Collect garbage and give freed heap pages back to the OS (glibc keeps them resident
    for reuse otherwise, which would hide the next measurement's peak)."""
    gc.collect()
    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):
        pass


def _status_kb(key: str) -> float:
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(key + ":"):
                return float(line.split()[1])
    return float("nan")


def rss_bytes() -> float:
    """This process's resident set now."""
    return _status_kb("VmRSS") * 1024


def peak_rss_bytes() -> float:
    """This process's peak resident set since it started or since :func:`reset_peak_rss`
    (the kernel's own bookkeeping, VmHWM: no sampling)."""
    return _status_kb("VmHWM") * 1024


def reset_peak_rss() -> float:
    """Reset the peak resident set to the current one (Linux ≥ 4.0: ``5 > clear_refs``);
    returns the current resident set in bytes."""
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
    except OSError:
        pass
    return rss_bytes()


class _Serial:
    """The communicator of a serial run: barriers and reductions over one process."""

    size, rank = 1, 0

    def Barrier(self):
        pass

    def allreduce(self, value, op=None):
        return value

    def allgather(self, value):
        return [value]


class Stage:
    """One measured stage: ``with Stage(comm) as st: ...`` then ``st.wall`` (seconds, barrier
    to barrier, the slowest rank), ``st.cpu_frac`` (CPU time / wall time, the smallest over
    ranks: below 1 the rank was descheduled), ``st.load1`` (1-minute load average at the
    start), ``st.peak`` / ``st.total`` (peak resident set during the stage in MB, largest
    over ranks / summed), ``st.delta`` (this rank's peak above its resident set at the start,
    bytes).  Freed memory is returned to the OS first, so that the peak is the stage's."""

    def __init__(self, comm=None):
        self.comm = comm if comm is not None else _Serial()

    def __enter__(self):
        release_memory()
        self.start = reset_peak_rss()
        self.comm.Barrier()
        self.load1 = os.getloadavg()[0]
        self.c0 = time.process_time()
        self.t0 = time.perf_counter()
        return self

    def __exit__(self, *exc):
        if exc[0] is not None:
            return False
        self.comm.Barrier()
        mine = time.perf_counter() - self.t0
        cpu = (time.process_time() - self.c0) / max(mine, 1e-9)
        peak = peak_rss_bytes()
        self.delta = max(0.0, peak - self.start)
        self.wall = max(self.comm.allgather(mine))
        self.cpu_frac = min(self.comm.allgather(cpu))
        peaks = self.comm.allgather(peak / 2**20)
        self.peak, self.total = max(peaks), sum(peaks)
        return False


# ----------------------------------------------------------------------------- time

def timed(fn, *, repeats: int = 5, budget: float = math.inf):
    """Median wall time of up to ``repeats`` runs of ``fn()``, repeating while the total stays
    under ``budget`` seconds (a slow run is measured once).  Returns
    ``(median seconds, runs, last result)``."""
    times, result = [], None
    while True:
        t0 = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
        if len(times) >= repeats or sum(times) + times[-1] > budget:
            break
    return statistics.median(times), len(times), result


# ----------------------------------------------------------------------------- a reference solve

def slepc_eigensolve(A, B, nev: int, *, hermitian: bool = False, extra: dict | None = None,
                     info: dict | None = None, prefix: str = "bench_ref_"):
    """One shift-and-invert Krylov–Schur solve (MUMPS LU) of the pencil (A, B) of PETSc Mats
    (collective), from scratch: the ``nev`` eigenvalues nearest 0 in modulus (GNHEP, tol
    1e-10) or, ``hermitian``, nearest 0 in real part (GHEP, tol 1e-12: the active-set's own
    options).  ``extra``: more options under ``prefix`` (e.g. ``st_mat_mumps_icntl_7``).
    ``info`` (a dict) receives ``setup_s`` (EPSSetUp: MUMPS analysis and factorisation,
    this rank's wall time) and the factor's ``ordering_used`` (INFOG(7)),
    ``factor_entries`` (INFOG(29)) and ``flops`` (RINFOG(3)).  Returns (eigenvalues, EPS
    iterations)."""
    SLEPc = import_slepc()
    opts = {"eps_nev": nev, "eps_target": 0.0, "eps_target_magnitude": True, "eps_tol": 1e-10,
            "eps_gen_non_hermitian": True, "st_type": "sinvert", "st_ksp_type": "preonly",
            "st_pc_type": "lu", "st_pc_factor_mat_solver_type": "mumps"}
    if hermitian:
        del opts["eps_target_magnitude"], opts["eps_gen_non_hermitian"]
        opts.update(eps_target_real=True, eps_gen_hermitian=True, eps_tol=1e-12)
    opts.update(extra or {})
    eps = SLEPc.EPS().create(comm=A.getComm())
    try:
        eps.setOperators(A, B)
        with OptionsScope(prefix, opts):
            eps.setOptionsPrefix(prefix)
            eps.setFromOptions()
            t0 = time.perf_counter()
            eps.setUp()
            setup = time.perf_counter() - t0
            eps.solve()
        nconv = eps.getConverged()
        vals = np.array([eps.getEigenvalue(i) for i in range(min(nconv, nev))], dtype=complex)
        its = eps.getIterationNumber()
        if info is not None:
            info["setup_s"] = setup
            try:
                F = eps.getST().getKSP().getPC().getFactorMatrix()
                info["ordering_used"] = MUMPS_ORDER_NAME.get(F.getMumpsInfog(7), str(F.getMumpsInfog(7)))
                entries = F.getMumpsInfog(29)  # negative: millions of entries
                info["factor_entries"] = entries if entries >= 0 else -entries * 1_000_000
                info["flops"] = F.getMumpsRinfog(3)
                F.destroy()  # drops this reference (without it the factor outlives the EPS)
            except Exception as e:  # noqa: BLE001 (diagnostics only)
                info["ordering_used"] = f"? ({type(e).__name__})"
    finally:
        eps.destroy()
    return vals, its


#: how a divergence verdict is drawn in the family charts, by its value in the CSVs:
#: (marker, colour, label)
VERDICT_STYLE = {"True": ("x", "tab:red", "mode (unstable)"), "False": ("o", "tab:green", "proof (stable)"),
                 "None": ("s", "tab:gray", "undecided")}


def scatter_verdicts(ax, rows, x, y, **style) -> None:
    """One scatter per divergence verdict of ``rows`` (CSV dicts), labelled with its count;
    ``x``, ``y``: the coordinates of a row."""
    for key, (marker, color, label) in VERDICT_STYLE.items():
        sel = [r for r in rows if r["divergence"] == key]
        if sel:
            ax.scatter([x(r) for r in sel], [y(r) for r in sel], marker=marker, color=color,
                       label=f"{label}: {len(sel)}", **style)


def save_figure(fig, path, *, dpi: int = 110, rect=None) -> None:
    """Lay out (within ``rect`` when a title or legend sits outside the axes), write and close
    a chart."""
    import matplotlib.pyplot as plt

    fig.tight_layout(**({} if rect is None else {"rect": rect}))
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
