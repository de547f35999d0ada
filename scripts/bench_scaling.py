#!/usr/bin/env python3
"""Scaling benchmark (issue 7 §3): a two-layer lattice instability problem from 10^4 to 10^6
DOFs, on 1 and on 2 ranks, time and peak memory per stage, with the peers in the same run.

Commands that produce the committed ``docs/benchmarks/scaling.csv`` (``scripts/bench.sh full``)::

    export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1
    .venv/bin/python scripts/bench_scaling.py                       # 1 rank + every peer
    mpirun -n 2 --oversubscribe .venv/bin/python scripts/bench_scaling.py   # 2 ranks (appends)
    .venv/bin/python scripts/charts.py scaling docs/benchmarks/scaling.csv
    # quick mode (build/benchmarks/): the same with --quick (10^4 and 3·10^4 DOFs only)

    # MUMPS orderings (docs/benchmarks/scaling_ordering.csv; SCALING_ORDERINGS=1 scripts/bench.sh full)
    .venv/bin/python scripts/bench_scaling.py --orderings                    # 3·10^5 (3 repeats), 10^6 (2)
    mpirun -n 2 --oversubscribe .venv/bin/python scripts/bench_scaling.py --orderings   # appends

Problem ("lattice family"): nx × ny nodes with nx = 2·ny (10^6 DOFs: 1000 × 500, the lattice
of ``data/scenes/extensive_contact.toml``), a soft layer (k = 1, ρ = 1) under a stiff one
(k = 5, ρ = 2), top row fixed, every base node in contact with the rigid rough base and
sliding in +x (``states = "slip+"``) at μ = 2: an MEiCP with |J| = nx complementarity pairs
and a nonsymmetric pencil (friction), which has a certified divergence mode at every size
measured (σ > 0).

Stages (``stage`` column), each timed barrier to barrier (max over ranks), with the peak
resident set of the stage (``/proc/self/status`` VmHWM, reset through ``clear_refs`` before
the stage; largest over ranks in ``peak_rss_mb``, summed over ranks in ``total_rss_mb``):

- ``assemble``: K and M (SciPy on 1 rank as ``analyze`` does, PETSc MPIAIJ on 2);
- ``pencil``: the contact maps and the reduced pencil ``A = −PKQ``, ``B = PMQ``;
- ``eigensolve``: one SLEPc Krylov–Schur shift-and-invert solve (MUMPS LU) of the full
  pencil, ``nev`` eigenvalues nearest the target 0 (in modulus), tol 1e-10;
- ``meicp``: ``solve_eicp(A, B, J, method="active-set", lam_min=0)`` — iterations (support
  updates) and eigen-solves from ``result.coverage``;
- ``analyze``: ``meicp.analyze(scene, comm, method="active-set")`` end to end (its own
  ``timings`` in ``detail``).

``cpu_frac``: CPU time of the stage / its wall time, smallest over ranks (below 1: the rank
was descheduled — the machine is shared); ``load1``: the 1-minute load average at its start.

``above_base_mb``: ``peak_rss_mb`` minus the resident set of the process after importing
meicp, PETSc and SLEPc (about 100 MB), i.e. what the problem itself uses.

``setup_s`` (eigen-solve rows): the time of ``EPSSetUp`` alone, i.e. MUMPS' analysis and
numeric factorisation; the rest of ``wall_s`` is the Krylov–Schur iterations (triangular solves).

Multi-support family (``xy-eigensolve`` and ``xy-meicp`` stages, ``--xy`` sizes, default the
same as ``--dofs``): the symmetric pencil of ``bench_eicp.py lattice --dofs xy`` (A = −K_ff,
B = M_ff of an nx × nx/2 two-layer lattice with the bottom and top rows fixed; J = the x and
y DOFs of the lowest free row, |J| = 2·nx): ``solve_eicp(..., method="active-set")`` has to
drop and re-add indices, so ``iterations``, ``eigen_solves`` and ``supports`` (supports
visited) are measured against size, next to one eigen-solve of the same pencil (GHEP, the
active-set's own options: target 0 in real part, tol 1e-12).

MUMPS orderings (``--orderings [NAME ...]``, its own CSV
``scaling_ordering.csv``): one eigen-solve of the main pencil at 3·10^5 and 10^6 DOFs per
fill-reducing ordering (``auto`` = MUMPS' default ICNTL(7) = 7, ``amd`` 0, ``amf`` 2; also ``qamd`` 6, ``pord`` 4),
interleaved and rotated per repeat, with the ordering MUMPS actually used (INFOG(7)), the
factor's entries (INFOG(29)) and flops (RINFOG(3)); first an availability check of METIS
(ICNTL(7) = 5), SCOTCH (3) and, on several ranks, the parallel analysis ICNTL(28) = 2 with
PT-Scotch or ParMETIS (ICNTL(29) = 1, 2).

Peers (1 rank only, on the same pencil or LCP, in the same process and run):

- ``eigensolve`` by SciPy ARPACK + SuperLU (``scipy.sparse.linalg.eigs`` with ``sigma=0``,
  same nev, tol 1e-10): eigenvalue agreement with SLEPc's in ``error``; skipped with status
  ``not run: time limit`` when its time predicted from the previous size (∝ n^1.5) exceeds
  ``--peer-limit`` seconds;
- ``meicp`` by dense enumeration (``method="enumerate"``): the main sizes are far beyond it
  (``not run: too large``); it runs on tiny lattices of the same family (nx = 6..12,
  2^nx supports), next to the active-set on the same pencil (λ agreement in ``error``);
- ``lcp``: the static frictional contact LCP of the same lattice under a top-row load
  (``states = "solve"``, condensed dense formulation), solved by meicp's Lemke and by
  Siconos' Lemke on the same (M, q); the condensation itself is the ``static`` stage.
  Above ``--lcp-max-dofs`` the condensed LCP is ``not run: too large``.
"""

from __future__ import annotations

import argparse
import gc
import json
import math
import statistics
import time

import numpy as np
import scipy.sparse.linalg as spla

import bench_eicp
import meicp
from bench_common import (MUMPS_ORDER_NAME, Stage, csv_path, lattice_shape, release_memory, rss_bytes,
                          slepc_eigensolve, write_rows)
from meicp.contact import pencil
from meicp.contact.lines import contact_lines, with_states
from meicp.contact.problem import pencil_of
from meicp.contact.static import static_equilibrium
from meicp.examples import two_layer_scene
from meicp.lattice.model import LatticeModel
from meicp.lcp.siconos import siconos_solve
from meicp.petsc import import_slepc
from meicp.petsc.assembly import LatticeMatrices
from meicp.petsc.mat import destroying, mat_from_scipy

FIELDS = ["problem", "stage", "method", "settings", "ranks", "dofs", "nx", "ny", "J", "n", "repeats",
          "wall_s", "wall_min_s", "wall_max_s", "iterations", "eigen_solves", "status", "error",
          "peak_rss_mb", "total_rss_mb", "above_base_mb", "cpu_frac", "load1", "lam", "residual", "detail",
          "supports", "setup_s"]
# MUMPS ICNTL(7) sequential orderings (Debian's MUMPS 5.5 has PORD, AMD, AMF, QAMD; METIS and
# SCOTCH requests fall back to PORD) and ICNTL(28) = 2 parallel ordering (none available)
ORDERINGS = {"auto": None, "amd": 0, "amf": 2, "scotch": 3, "pord": 4, "metis": 5, "qamd": 6}
FULL_DOFS = (10_000, 30_000, 100_000, 300_000, 1_000_000)
QUICK_DOFS = (10_000, 30_000)
MU = 2.0


# ----------------------------------------------------------------------------- problem

def make_scene(nx: int, ny: int, *, states="slip+", load=None):
    lower = max(1, ny // 2)
    return two_layer_scene(nx, (lower, ny - lower), mu=MU, states=states, load=load,
                           solver={"method": "active-set", "nev": 4})


def build_pencil(model, scene, K, M):
    """The pencil as analyze builds it from K, M (SciPy on 1 rank, PETSc products on several);
    the caller keeps K, M and destroys them."""
    comm = K.getComm() if hasattr(K, "getComm") else None
    return pencil_of(LatticeMatrices.wrapping(model, K, M, comm), with_states(contact_lines(scene, model), None))


def main_pencil(dofs: int, comm):
    """(nx, ny, A, B) of the all-slip family at about ``dofs`` DOFs, as PETSc Mats on comm."""
    nx, ny = lattice_shape(dofs)
    pen = pencil(make_scene(nx, ny), comm=comm)
    A, B = pen.A, pen.B
    pen.lattice.destroy()  # K, M: only the pencil is measured
    if not pen.distributed:
        A, B = mat_from_scipy(comm, A), mat_from_scipy(comm, B)
    return nx, ny, A, B


def slepc_eigs(A, B, nev, comm, extra=None, info=None, hermitian=False):
    """One reference eigen-solve (:func:`bench_common.slepc_eigensolve`) under this
    benchmark's prefix."""
    return slepc_eigensolve(A, B, nev, hermitian=hermitian, extra=extra, info=info, prefix="bench_scaling_")


def match_error(ref: np.ndarray, vals: np.ndarray) -> float:
    """max over ref of min |ref − val| / |ref| (the eigenvalues of one solver found by the other)."""
    if ref.size == 0 or vals.size == 0:
        return float("nan")
    return float(max(np.min(np.abs(vals - r)) / max(abs(r), 1e-300) for r in ref))


def fmt_vals(vals) -> str:
    return " ".join(f"{v.real:.10g}" + (f"{v.imag:+.3g}j" if abs(v.imag) > 0 else "") for v in vals)


# ----------------------------------------------------------------------------- runs

class Runner:
    def __init__(self, args, comm):
        self.args, self.comm = args, comm
        self.rows: list = []
        self.arpack_last = None  # (n, seconds) of the last ARPACK run, for the prediction
        import_slepc()  # the libraries in RSS before the baseline
        release_memory()
        self.base_mb = max(comm.allgather(rss_bytes() / 2**20))

    def say(self, msg):
        if self.comm.rank == 0:
            print(msg, flush=True)

    def row(self, **kw):
        base = {k: "" for k in FIELDS}
        base.update(ranks=self.comm.size)
        base.update(kw)
        if isinstance(base["cpu_frac"], float):
            base["cpu_frac"] = f"{base['cpu_frac']:.2f}"
        if isinstance(base["load1"], float):
            base["load1"] = f"{base['load1']:.2f}"
        if isinstance(base["peak_rss_mb"], float):
            base["above_base_mb"] = base["peak_rss_mb"] - self.base_mb
        for k in ("wall_s", "wall_min_s", "wall_max_s", "peak_rss_mb", "total_rss_mb", "above_base_mb"):
            if isinstance(base[k], float):
                base[k] = f"{base[k]:.4g}" if k.startswith("wall") else f"{base[k]:.0f}"
        for k in ("error", "residual"):
            if isinstance(base[k], float):
                base[k] = f"{base[k]:.3g}"
        self.rows.append(base)
        w = base["wall_s"]
        self.say(f"  {base['stage']:<10} {base['method']:<26} {base['status']:<22} {w:>9} s  "
                 f"peak {base['peak_rss_mb']:>6} MB/rank  {base['detail'][:90]}")

    def stages(self, n_rep, fn):
        """Run fn() n_rep times, each a :class:`bench_common.Stage` (wall time, peak memory,
        CPU share, load); return (last value, walls, peak, total)."""
        walls, peaks, totals, out = [], [], [], None
        self.cpu, self.load = [], []
        for rep in range(n_rep):
            out = None
            gc.collect()
            with Stage(self.comm) as st:
                out = fn()
            walls.append(st.wall)
            peaks.append(st.peak)
            totals.append(st.total)
            self.cpu.append(st.cpu_frac)
            self.load.append(st.load1)
            if rep < n_rep - 1:
                _cleanup(out)
        return out, walls, max(peaks), max(totals)

    # -- the main lattice family --------------------------------------------------------
    def lattice(self, dofs):
        comm, args = self.comm, self.args
        nx, ny = lattice_shape(dofs)
        scene = make_scene(nx, ny)
        model = LatticeModel(scene)
        n_dofs = model.n_dofs
        reps = args.repeats if n_dofs <= args.repeat_max_dofs else 1
        prob = f"lattice_{nx}x{ny}"
        common = dict(problem=prob, dofs=n_dofs, nx=nx, ny=ny, J=nx, repeats=reps)
        self.say(f"\n{prob}: {n_dofs} DOFs, {comm.size} rank(s), {reps} repeat(s)")
        mode = "petsc" if comm.size > 1 else "scipy"

        def stat(walls):
            return dict(wall_s=statistics.median(walls), wall_min_s=min(walls), wall_max_s=max(walls),
                        cpu_frac=min(self.cpu), load1=max(self.load))

        # assemble
        (K, M), walls, peak, total = self.stages(reps, lambda: meicp.assemble(model, comm if comm.size > 1 else None))
        self.row(**common, stage="assemble", method=f"meicp-{mode}", settings="K and M", status="ok",
                 peak_rss_mb=peak, total_rss_mb=total, **stat(walls))
        # pencil
        pen, walls, peak, total = self.stages(reps, lambda: build_pencil(model, scene, K, M))
        A, B, J = pen.A, pen.B, pen.J
        n = pen.maps.retained.size
        common["n"] = n
        self.row(**common, stage="pencil", method=f"meicp-{mode}", settings="contact maps, A=-PKQ, B=PMQ",
                 status="ok", peak_rss_mb=peak, total_rss_mb=total, **stat(walls))
        # eigensolve: SLEPc + MUMPS on PETSc matrices (conversion from SciPy untimed on 1 rank)
        if pen.distributed:
            Ap, Bp = A, B
        else:
            Ap, Bp = mat_from_scipy(comm, A), mat_from_scipy(comm, B)
        infos = []

        def eig():
            infos.append({})
            return slepc_eigs(Ap, Bp, args.nev, comm, info=infos[-1])

        (vals, its), walls, peak, total = self.stages(reps, eig)
        slepc_vals, slepc_wall = vals, statistics.median(walls)
        self.row(**common, stage="eigensolve", method="slepc-krylovschur+mumps", iterations=its,
                 eigen_solves=1, settings=f"sinvert target=0 (magnitude) nev={args.nev} tol=1e-10",
                 status="solved" if vals.size >= args.nev else "not_converged", lam=fmt_vals(vals),
                 setup_s=f"{statistics.median(i['setup_s'] for i in infos):.4g}",
                 detail=f"setup_s = EPSSetUp (MUMPS analysis + factorisation, rank 0); ordering "
                        f"{infos[-1].get('ordering_used')}, factor entries {infos[-1].get('factor_entries')}, "
                        f"flops {infos[-1].get('flops', float('nan')):.3g}",
                 peak_rss_mb=peak, total_rss_mb=total, **stat(walls))
        if Ap is not A:
            Ap.destroy()
            Bp.destroy()
        # the MEiCP by the active-set search
        r, walls, peak, total = self.stages(reps, lambda: meicp.solve_eicp(
            A, B, J=J, method="active-set", lam_min=0.0, target=0.0, nev=args.nev, tol=1e-10))
        sol = r.solutions[0] if r.solutions else None
        cov = r.coverage
        self.row(**common, stage="meicp", method="active-set", settings=f"lam_min=0 target=0 nev={args.nev}",
                 iterations=r.iterations, eigen_solves=cov.get("eigen_solves", ""), status=r.status,
                 lam=f"{sol.lam:.10g}" if sol else "", residual=sol.residual if sol else "",
                 detail=f"supports visited {cov.get('supports_visited')}; EPS iterations {cov.get('eps_iterations')}",
                 peak_rss_mb=peak, total_rss_mb=total, **stat(walls))
        as_lam = sol.lam if sol else None
        # enumeration cannot: say why
        if comm.size == 1:
            self.row(**common, stage="meicp", method="enumerate", status="not run: too large",
                     detail=f"2^{nx} supports and |F| = {n - nx} > 2000 (dense pencils); runs on nx ≤ 12 only")
        # peer: ARPACK + SuperLU on the same pencil
        if comm.size == 1:
            self.arpack(common, A, B, slepc_vals, slepc_wall)
        pen.destroy()
        with destroying(K, M):
            pass
        del A, B, K, M, pen
        release_memory()
        # analyze end to end
        res, walls, peak, total = self.stages(reps, lambda: meicp.analyze(scene, comm if comm.size > 1 else None,
                                                                         method="active-set"))
        e = res.eicp[0]
        sigma = res.modes[0].sigma if res.modes else None
        agree = ""
        if sigma is not None and as_lam is not None:
            agree = abs(sigma - as_lam) / abs(as_lam)
        self.row(**common, stage="analyze", method="meicp-analyze", settings="method=active-set, whole pipeline",
                 iterations=e.iterations if e else "", eigen_solves=e.coverage.get("eigen_solves", "") if e else "",
                 status=f"{res.status} ({'unstable' if res.stable is False else res.stable})",
                 lam=f"{sigma:.10g}" if sigma is not None else "", residual=res.modes[0].residual if res.modes else "",
                 error=agree, detail=json.dumps({k: round(v, 3) for k, v in res.timings.items()}),
                 peak_rss_mb=peak, total_rss_mb=total, **stat(walls))
        del res, e
        release_memory()
        # peer: the static contact LCP, meicp vs Siconos (serial)
        if comm.size == 1:
            self.lcp(nx, ny)

    def arpack(self, common, A, B, slepc_vals, slepc_wall):
        n, args = common["n"], self.args
        settings = f"scipy eigs sigma=0 which=LM k={args.nev} tol=1e-10 (SuperLU)"
        if self.arpack_last is not None:
            n0, t0 = self.arpack_last
            pred = t0 * (n / n0) ** 1.5
            if pred > args.peer_limit:
                self.row(**common, stage="eigensolve", method="arpack+superlu", settings=settings,
                         status="not run: time limit",
                         detail=f"predicted {pred:.0f} s (∝ n^1.5 from {t0:.1f} s at n={n0}) > {args.peer_limit:.0f} s")
                return
        Ac, Bc = A.tocsc(), B.tocsc()
        walls, vals, peak, cpu, load = [], None, 0.0, [], []
        reps = common["repeats"]
        for _ in range(reps):
            with Stage(self.comm) as st:
                vals, vecs = spla.eigs(Ac, k=args.nev, M=Bc, sigma=0.0, which="LM", tol=1e-10)
            walls.append(st.wall)
            peak = max(peak, st.peak)
            cpu.append(st.cpu_frac)
            load.append(st.load1)
        t = statistics.median(walls)
        self.arpack_last = (n, t)
        res = max(np.linalg.norm(Ac @ vecs[:, i] - vals[i] * (Bc @ vecs[:, i]))
                  / (abs(vals[i]) * np.linalg.norm(Bc @ vecs[:, i]) + spla.norm(Ac, 1) * np.linalg.norm(vecs[:, i]))
                  for i in range(vals.size))
        err = max(match_error(slepc_vals, vals), match_error(vals, slepc_vals))
        self.row(**common, stage="eigensolve", method="arpack+superlu", settings=settings, eigen_solves=1,
                 status="solved", lam=fmt_vals(vals), residual=float(res), error=err,
                 detail=f"time / SLEPc time = {t / slepc_wall:.2f}; error = eigenvalue disagreement with SLEPc",
                 wall_s=t, wall_min_s=min(walls), wall_max_s=max(walls), peak_rss_mb=peak, total_rss_mb=peak,
                 cpu_frac=min(cpu), load1=max(load))

    def lcp(self, nx, ny):
        args = self.args
        dofs = 2 * nx * ny
        common = dict(problem=f"lattice_{nx}x{ny}", dofs=dofs, nx=nx, ny=ny, J=nx, repeats=1)
        settings = f"static frictional LCP, condensed dense, {nx} contacts, mu={MU}"
        if dofs > args.lcp_max_dofs:
            for stage, method in (("static", "meicp-condensed"), ("lcp", "meicp-lemke"), ("lcp", "siconos-lemke")):
                self.row(**common, stage=stage, method=method, settings=settings, status="not run: too large",
                         detail=f"condensing {nx} contacts needs {2 * nx} sparse solves of {dofs} DOFs and a "
                                f"dense {4 * nx}² LCP; limit --lcp-max-dofs {args.lcp_max_dofs}")
            return
        scene = make_scene(nx, ny, states="solve", load=[0.2 * nx / 100, -0.02 * nx / 100])
        with Stage(self.comm) as st:
            s = static_equilibrium(scene, formulation="condensed", method="lemke")
        M, q = s.lcp_matrix, s.lcp_q
        counts = {k: s.states.count(k) for k in set(s.states)}
        self.row(**common, stage="static", method="meicp-condensed", settings=settings, n=M.shape[0],
                 status=s.status, residual=s.residual, wall_s=st.wall, cpu_frac=st.cpu_frac, load1=st.load1,
                 peak_rss_mb=st.peak, total_rss_mb=st.total,
                 detail=json.dumps({"contact_states": counts, **{k: round(v, 3) for k, v in s.timings.items()}}))
        ref = s.lcp.x
        for method, fn in (("meicp-lemke", lambda: meicp.solve_lcp(M, q, method="lemke")),
                           ("siconos-lemke", lambda: siconos_solve(M, q, "lemke"))):
            with Stage(self.comm) as st:
                r = fn()
            dist = "no reference (the static solve's Lemke failed)"
            if r.success and s.success:
                d = float(np.abs(r.x - ref).max() / max(np.abs(ref).max(), 1e-300))
                dist = (f"max|x − x_static| / max|x_static| = {d:.2g} (x_static: the static solve's own Lemke; "
                        "the friction LCP need not have a unique solution — both are certified)")
            self.row(**common, stage="lcp", method=method, settings=settings, n=M.shape[0],
                     iterations=r.iterations, status=r.status, residual=r.residual, detail=dist,
                     wall_s=st.wall, cpu_frac=st.cpu_frac, load1=st.load1, peak_rss_mb=st.peak,
                     total_rss_mb=st.total)

    # -- tiny lattices: enumeration next to the active-set -------------------------------
    def tiny(self, nx):
        comm = self.comm
        ny = nx // 2
        scene = make_scene(nx, ny)
        model = LatticeModel(scene)
        K, M = meicp.assemble(model)
        pen = build_pencil(model, scene, K, M)
        A, B, J = pen.A, pen.B, pen.J
        Ad, Bd = A.toarray(), B.toarray()
        common = dict(problem=f"lattice_{nx}x{ny}", dofs=model.n_dofs, nx=nx, ny=ny, J=J.size, n=A.shape[0],
                      repeats=1)
        self.say(f"\nlattice_{nx}x{ny} (tiny): {model.n_dofs} DOFs, |J| = {J.size}, {comm.size} rank(s)")
        with Stage(comm) as st:
            r = meicp.solve_eicp(Ad, Bd, J=J, method="enumerate", lam_min=0.0, tol=1e-10,
                           comm=comm if comm.size > 1 else None)
        lams = np.array([s.lam for s in r.solutions])
        self.row(**common, stage="meicp", method="enumerate", settings=f"all 2^{J.size} supports, lam_min=0",
                 iterations=r.iterations, eigen_solves=r.coverage.get("eigen_solves"), status=r.status,
                 lam=" ".join(f"{v:.10g}" for v in lams[:4]),
                 residual=max((s.residual for s in r.solutions), default=float("nan")),
                 detail=f"{lams.size} solution(s) with σ ≥ 0", wall_s=st.wall, cpu_frac=st.cpu_frac,
                 load1=st.load1, peak_rss_mb=st.peak, total_rss_mb=st.total)
        if comm.size == 1:
            with Stage(comm) as st:
                ra = meicp.solve_eicp(A, B, J=J, method="active-set", lam_min=0.0, target=0.0, nev=self.args.nev,
                                tol=1e-10)
            sol = ra.solutions[0] if ra.solutions else None
            err = float(np.min(np.abs(lams - sol.lam)) / abs(sol.lam)) if sol is not None and lams.size else ""
            self.row(**common, stage="meicp", method="active-set", settings=f"lam_min=0 target=0 nev={self.args.nev}",
                     iterations=ra.iterations, eigen_solves=ra.coverage.get("eigen_solves"), status=ra.status,
                     lam=f"{sol.lam:.10g}" if sol else "", residual=sol.residual if sol else "", error=err,
                     detail="error = distance of λ to the nearest enumerated solution, relative",
                     wall_s=st.wall, cpu_frac=st.cpu_frac, load1=st.load1, peak_rss_mb=st.peak,
                     total_rss_mb=st.total)


    # -- multi-support family: J = x and y DOFs of the lowest free row ----------------------
    def xy(self, dofs):
        """The symmetric lattice pencil of ``bench_eicp.py lattice --dofs xy`` (A = −K_ff,
        B = M_ff, bottom and top rows fixed, J = both DOFs of the lowest free row): the
        active-set leaves and re-enters supports, so its iterations are measured against one
        eigen-solve of the same pencil (GHEP, the active-set's own SLEPc options)."""
        comm, args = self.comm, self.args
        nx = 2 * round(math.sqrt(dofs) / 2)
        A, B, J = bench_eicp.lattice_pencil(nx, comm, "xy")
        n = A.getSize()[0]
        reps = args.repeats if nx * nx <= args.repeat_max_dofs else 1
        common = dict(problem=f"lattice_xy_{nx}x{nx // 2}", dofs=nx * (nx // 2) * 2, nx=nx, ny=nx // 2,
                      J=J.size, n=n, repeats=reps)
        self.say(f"\nlattice_xy_{nx}x{nx // 2} (J = x, y of the lowest free row): n = {n}, |J| = {J.size}, "
                 f"{comm.size} rank(s), {reps} repeat(s)")

        def stat(walls):
            return dict(wall_s=statistics.median(walls), wall_min_s=min(walls), wall_max_s=max(walls),
                        cpu_frac=min(self.cpu), load1=max(self.load))

        infos = []

        def eig():
            infos.append({})
            return slepc_eigs(A, B, args.nev, comm, info=infos[-1], hermitian=True)

        (vals, its), walls, peak, total = self.stages(reps, eig)
        t_single = statistics.median(walls)
        self.row(**common, stage="xy-eigensolve", method="slepc-krylovschur+mumps", iterations=its, eigen_solves=1,
                 settings=f"GHEP sinvert target=0 (real) nev={args.nev} tol=1e-12", lam=fmt_vals(vals),
                 status="solved" if vals.size >= args.nev else "not_converged",
                 setup_s=f"{statistics.median(i['setup_s'] for i in infos):.4g}",
                 peak_rss_mb=peak, total_rss_mb=total, **stat(walls))
        r, walls, peak, total = self.stages(reps, lambda: meicp.solve_eicp(A, B, J=J, method="active-set",
                                                                           target=0.0, nev=args.nev, tol=1e-10))
        sol = r.solutions[0] if r.solutions else None
        cov = r.coverage
        hist = cov.get("history", [])
        self.row(**common, stage="xy-meicp", method="active-set", settings=f"target=0 nev={args.nev} tol=1e-10",
                 iterations=r.iterations, eigen_solves=cov.get("eigen_solves", ""),
                 supports=cov.get("supports_visited", ""), status=r.status,
                 lam=f"{sol.lam:.10g}" if sol else "", residual=sol.residual if sol else "",
                 detail=(f"time / one eigen-solve = {statistics.median(walls) / t_single:.2f}; EPS iterations "
                         f"{cov.get('eps_iterations')}; |S| per iteration "
                         + " ".join(str(h.get("support")) for h in hist)
                         + "; seconds per eigen-solve " + " ".join(f"{h.get('seconds', 0):.3g}" for h in hist)),
                 peak_rss_mb=peak, total_rss_mb=total, **stat(walls))
        A.destroy()
        B.destroy()
        del A, B
        release_memory()


def _cleanup(out):
    items = out if isinstance(out, tuple) else (out,)
    for x in items:
        if hasattr(x, "destroy"):
            x.destroy()



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


def orderings_main(args):
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


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--quick", action="store_true", help="10^4 and 3·10^4 DOFs, tiny nx 6 8 (about 1.5 min with the 2-rank run)")
    p.add_argument("--dofs", nargs="+", type=int, help=f"lattice sizes (default {FULL_DOFS})")
    p.add_argument("--tiny", nargs="*", type=int, help="nx of the tiny lattices for enumeration (default 6 8 10 12)")
    p.add_argument("--nev", type=int, default=4)
    p.add_argument("--repeats", type=int, default=3, help="repeats (median) up to --repeat-max-dofs")
    p.add_argument("--repeat-max-dofs", type=int, default=100_000)
    p.add_argument("--peer-limit", type=float, default=180.0, help="skip ARPACK above this predicted time [s]")
    p.add_argument("--lcp-max-dofs", type=int, default=100_000, help="largest lattice for the condensed LCP peer")
    p.add_argument("--xy", nargs="*", type=int,
                   help="sizes of the multi-support (J = xy) family (default: the same as --dofs)")
    p.add_argument("--orderings", nargs="*", metavar="NAME",
                   help=f"instead of everything else: one eigen-solve per MUMPS ordering ({', '.join(ORDERINGS)}; "
                        "default auto amd amf) at --dofs (default 300000 1000000), into scaling_ordering.csv")
    p.add_argument("--ordering-repeats", nargs="+", type=int, default=[3, 2],
                   help="repeats per size of --orderings (the last value for the remaining sizes)")
    args = p.parse_args()
    if args.orderings is not None:
        return orderings_main(args)  # its own study, its own CSV
    dofs = args.dofs or (QUICK_DOFS if args.quick else FULL_DOFS)
    xy = args.xy if args.xy is not None else dofs
    tiny = args.tiny if args.tiny is not None else ([6, 8] if args.quick else [6, 8, 10, 12])
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    run = Runner(args, comm)
    t0 = time.perf_counter()
    for nx in tiny:
        run.tiny(nx)
    for d in dofs:
        run.lattice(d)
    for d in xy:
        run.xy(d)
    if comm.rank == 0:
        out = csv_path("scaling")
        mine = str(comm.size)
        write_rows(out, run.rows, FIELDS, keep=lambda r: r["ranks"] != mine)
        print(f"\nwrote {len(run.rows)} rows ({comm.size} rank(s)) to {out} in {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
