#!/usr/bin/env python3
"""Speed against accuracy (issue 7 §2): every LCP and EiCP/MEiCP method, wall time against
error over a sweep of each iterative method's tolerance, 2-3 sizes per problem family.

LCP families (SPD, so the solution is unique; generators imported from bench_lcp.py):
- ``condensed``: dense contact-like — a grid Laplacian condensed onto its bottom row;
- ``lattice``: the two-layer elastic lattice's K on the vertical DOFs (sparse SPD).
Methods: meicp lemke, enumerate (n ≤ 12), pgs, newton, tao, auto, and the Siconos peers
(lemke, enum (n ≤ 12), newton-fb, pgs; dense, n ≤ 1000).  Error: ``‖x − x_ref‖∞ / ‖x_ref‖∞``
with x_ref the reference solution — the support of the best tight solve (newton at
rtol 1e-15, Lemke when dense), re-solved on that support with SciPy (``scipy.linalg.solve``
/ ``spsolve``) and accepted only with a certificate ≤ 1e-12; ``residual`` the certificate.

EiCP families (enumeration finishes, so the full solution set is known):
- ``random_sym``: random symmetric mixed problems (B diagonal SPD, J a random subset);
- ``friction``: the MEiCP of a sheared two-layer lattice on a rough base with every base
  node slipping (+x, μ = 2): nonsymmetric A = −PKQ, B = PMQ (built as ``analyze`` does).
Methods: enumerate (every solution), active-set (SLEPc), rayleigh (symmetric only),
semismooth (PETSc SNES VI, default ``vinewtonrsls``) and semismooth-ssls (the same with
``snes_type="vinewtonssls"``), all from their default starts.  Error: for each returned
solution whose support S (with λ within 1e-6) is a support of the enumeration's solution
set, the reference λ is the nearest eigenvalue of the reduced pencil on R = F ∪ S from
``scipy.linalg.eigh`` / ``eig`` (a dense solve independent of the methods); a certified
"solution" outside that set (possible at a loose certificate tol) is counted in ``wrong``
and compared with the nearest λ of the whole set; error = max over the returned solutions
of ``|λ − λ_ref| / |λ_ref|`` (enumerate: over about 300 of its solutions); ``residual`` is
the largest certificate residual (the best candidate's when nothing was certified).  The
enumeration that builds the reference is also enumerate's timed run when it takes longer
than half the repeat budget.

Tolerance sweep (``tol`` = 1e-2 … 1e-14) for the iterative methods, the method's own
stopping test set to ``tol`` and its certificate tolerance to ``tol`` too:
pgs ``tol`` (natural residual); newton ``snes_rtol``; tao ``tao_grtol``; auto ``tol``;
siconos newton-fb / pgs ``dparam[0]``; active-set ``eps_tol``; rayleigh ``spg_tol``;
semismooth ``snes_atol = tol·max(max|A|, max|B|)``.  Direct methods (lemke, enumerate)
are one point per size (certificate tol 1e-10).  Each wall time is the median of up to 5
repeats within about a second (one run when a run takes longer); serial, one rank.

    .venv/bin/python scripts/bench_tradeoff.py            # full: docs/benchmarks/tradeoff.csv
    .venv/bin/python scripts/charts.py tradeoff docs/benchmarks/tradeoff.csv
    MEICP_BENCH_DIR=build/benchmarks .venv/bin/python scripts/bench_tradeoff.py --quick
"""

from __future__ import annotations

import argparse
import logging
import time
import warnings

import numpy as np
import scipy.linalg
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import meicp
from bench_common import csv_path, timed, write_rows
from bench_lcp import condensed, lattice
from meicp.contact import pencil
from meicp.examples import two_layer_scene
from meicp.lcp.problem import LCPProblem, relative_residual
from meicp.lcp.siconos import siconos_solve
from meicp.lcp.solve import solve_lcp

FIELDS = ["kind", "family", "problem", "n", "J", "method", "tol", "settings", "ranks", "wall_s",
          "repeats", "iterations", "status", "residual", "error", "solutions", "wrong", "lam", "note"]

TOLS = [1e-2, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12, 1e-14]
DIRECT_TOL = 1e-10
LCP_ITERATIVE = ["pgs", "newton", "tao", "auto", "siconos-newton-fb", "siconos-pgs"]
LCP_DIRECT = ["lemke", "enumerate", "siconos-lemke", "siconos-enum"]
EICP_ITERATIVE = ["active-set", "rayleigh", "semismooth", "semismooth-ssls"]
#: at most this many of enumerate's solutions are checked against the dense reference
EICP_CHECK = 300


def fmt(v, spec=".3g"):
    return "" if v is None or (isinstance(v, float) and not np.isfinite(v)) else format(v, spec)


# ------------------------------------------------------------------------------------------
# LCP
# ------------------------------------------------------------------------------------------


def lcp_certificate(M, q, x):
    return relative_residual(LCPProblem.from_data(M, q), x)[0]


def lcp_reference(M, q):
    """(x_ref, residual, note): the support of the best tight solve, re-solved by SciPy."""
    cands = []
    r = solve_lcp(M, q, method="newton", tol=1e-12, options={"snes_rtol": 1e-15})
    if r.x is not None:
        cands.append(r.x)
    if len(q) <= 1000:
        r = solve_lcp(M, q, method="lemke", tol=1e-10)
        if r.x is not None:
            cands.append(r.x)
    best, best_res = None, np.inf
    for x in cands:
        w = M @ x + q
        S = np.flatnonzero(x > w)
        xr = np.zeros_like(q)
        if S.size:
            if sp.issparse(M):
                xr[S] = spla.spsolve(sp.csc_matrix(M[S][:, S]), -q[S])
            else:
                xr[S] = scipy.linalg.solve(M[np.ix_(S, S)], -q[S], assume_a="pos")
        res = lcp_certificate(M, q, xr)
        if res < best_res:
            best, best_res = xr, res
    if best is None or best_res > 1e-12:
        return None, best_res
    return best, best_res


def lcp_call(M, q, method, tol, args):
    """(callable, settings string) for one LCP method at one tolerance."""
    if method.startswith("siconos-"):
        solver = method[len("siconos-"):]
        if solver in ("lemke", "enum"):
            return (lambda: siconos_solve(M, q, solver, tol=tol)), f"certificate tol={tol:g}"
        mi = args.siconos_iter
        return (lambda: siconos_solve(M, q, solver, tol=tol, max_iter=mi)), f"dparam[0]={tol:g} max_iter={mi}"
    if method == "pgs":
        sweeps = args.pgs_sweeps
        return (lambda: solve_lcp(M, q, method="pgs", tol=tol, max_iter=sweeps)), f"tol={tol:g} max_sweeps={sweeps}"
    if method == "newton":
        return (lambda: solve_lcp(M, q, method="newton", tol=tol, options={"snes_rtol": tol})), \
            f"snes_rtol={tol:g} vinewtonrsls+mumps"
    if method == "tao":
        return (lambda: solve_lcp(M, q, method="tao", tol=tol, options={"tao_grtol": tol})), f"tao_grtol={tol:g} tron"
    if method == "auto":
        return (lambda: solve_lcp(M, q, method="auto", tol=tol)), f"tol={tol:g}"
    return (lambda: solve_lcp(M, q, method=method, tol=tol)), f"certificate tol={tol:g}"


def lcp_problems(args):
    out = []
    for n in args.condensed:
        M, q = condensed(n)
        out.append(("condensed", f"condensed_{n}", M, q))
    for nx in args.lattice:
        M, q = lattice(nx)
        out.append(("lattice", f"lattice_{len(q)}", M, q))
    return out


def run_lcp(args):
    rows = []
    for family, name, M, q in lcp_problems(args):
        n = len(q)
        t0 = time.perf_counter()
        x_ref, ref_res = lcp_reference(M, q)
        print(f"\n{name}: n = {n}, reference certificate {ref_res:.1e} ({time.perf_counter() - t0:.1f} s)",
              flush=True)
        dense_ok = n <= args.dense_limit
        methods = []
        for m in LCP_DIRECT + LCP_ITERATIVE:
            if m in ("enumerate", "siconos-enum") and n > 12:
                continue
            if (m == "lemke" or m.startswith("siconos")) and not dense_ok:
                continue
            methods.append(m)
        for method in methods:
            tols = [DIRECT_TOL] if method in LCP_DIRECT else TOLS
            failed_at = None
            for tol in tols:
                fn, settings = lcp_call(M, q, method, tol, args)
                base = dict(kind="lcp", family=family, problem=name, n=n, J=n, method=method, tol=f"{tol:g}",
                            settings=settings, ranks=1)
                if failed_at is not None and args.skip_after_failure and method in ("pgs", "siconos-pgs"):
                    rows.append(dict(base, status="skipped", note=f"not run: failed at looser tol {failed_at:g}"))
                    continue
                try:
                    wall, reps, r = timed(fn, budget=args.budget)
                except Exception as exc:  # noqa: BLE001 - a benchmark records failures
                    rows.append(dict(base, status="error", note=f"{type(exc).__name__}: {exc}"[:200]))
                    print(f"  {method:18s} tol={tol:<7g} error {type(exc).__name__}: {exc}", flush=True)
                    continue
                err = None
                if r.x is not None and x_ref is not None:
                    err = float(np.max(np.abs(r.x - x_ref)) / max(np.max(np.abs(x_ref)), 1e-300))
                res = r.residual if r.x is not None else None
                note = r.method if method == "auto" else ""
                rows.append(dict(base, wall_s=f"{wall:.6g}", repeats=reps, iterations=r.iterations,
                                 status=r.status, residual=fmt(res), error=fmt(err), solutions=1 if r.success else 0,
                                 note=note))
                print(f"  {method:18s} tol={tol:<7g} {wall:9.4f}s x{reps} {r.status:16s} "
                      f"res={fmt(res, '.1e'):8s} err={fmt(err, '.1e'):8s} its={r.iterations} {note}", flush=True)
                if not r.success and failed_at is None:
                    failed_at = tol
    return rows


# ------------------------------------------------------------------------------------------
# EiCP
# ------------------------------------------------------------------------------------------


def random_sym(n: int, nJ: int, seed: int):
    """Random symmetric mixed problem: A = G + Gᵀ, B diagonal in [0.5, 2], J random."""
    rng = np.random.default_rng(seed)
    G = rng.standard_normal((n, n))
    A = G + G.T
    B = np.diag(rng.uniform(0.5, 2.0, n))
    J = np.sort(rng.choice(n, nJ, replace=False))
    return A, B, J


def friction_pencil(nx: int, mu: float = 2.0, rows: int = 3):
    """The slip+ MEiCP of a sheared two-layer lattice on a rough base, as ``analyze`` builds it."""
    pen = pencil(two_layer_scene(nx, (rows, rows), mu=mu, shear=0.3))
    return pen.A.toarray(), pen.B.toarray(), pen.J


def eicp_problems(args):
    out = []
    for k, spec in enumerate(args.random_sym):
        n, nJ = (int(v) for v in spec.split(":"))
        A, B, J = random_sym(n, nJ, seed=100 + k)
        out.append(("random_sym", f"random_sym_n{n}_J{nJ}", A, B, J, float(np.abs(A).sum(axis=1).max() / 0.5)))
    for nx in args.friction:
        A, B, J = friction_pencil(nx)
        out.append(("friction", f"friction_nx{nx}", A, B, J, 0.0))
    return out


class EiCPReference:
    """Supports of the enumeration's solution set, and dense λ's of a support's pencil."""

    def __init__(self, A, B, J, enum_result):
        self.A, self.B, self.J = A, B, J
        self.F = np.setdiff1d(np.arange(A.shape[0]), J)
        self.symmetric = np.allclose(A, A.T, rtol=0, atol=1e-13 * np.abs(A).max()) and np.allclose(B, B.T)
        self.supports = {}
        for s in enum_result.solutions:
            self.supports.setdefault(tuple(int(i) for i in s.support), []).append(s.lam)
        self.all_lams = np.array([s.lam for s in enum_result.solutions])
        self.cache = {}

    def eigenvalues(self, S):
        key = tuple(int(i) for i in S)
        if key not in self.cache:
            R = np.union1d(self.F, np.asarray(key, dtype=np.int64))
            A, B = self.A[np.ix_(R, R)], self.B[np.ix_(R, R)]
            if self.symmetric:
                lam = scipy.linalg.eigh(A, B, eigvals_only=True)
            else:
                lam = scipy.linalg.eig(A, B, right=False)
                lam = lam[np.isfinite(lam) & (np.abs(lam.imag) <= 1e-8 * np.maximum(1.0, np.abs(lam)))].real
            self.cache[key] = lam
        return self.cache[key]

    def error(self, sol):
        """(relative λ error, in_set).  A solution whose support is one of the enumeration's
        solution supports (with λ within 1e-6) is compared with the nearest eigenvalue of that
        support's pencil by SciPy; any other "solution" (certified only at a loose tol) with
        the nearest λ of the whole enumerated set, and counted as not in the set."""
        key = tuple(int(i) for i in sol.support)
        scale = max(1.0, abs(sol.lam))
        in_set = key in self.supports and min(abs(v - sol.lam) for v in self.supports[key]) <= 1e-6 * scale
        if in_set:
            lam = self.eigenvalues(sol.support)
            ref = lam[np.argmin(np.abs(lam - sol.lam))]
        else:
            ref = self.all_lams[np.argmin(np.abs(self.all_lams - sol.lam))]
        return abs(sol.lam - ref) / max(abs(ref), 1e-300), in_set


def eicp_call(A, B, J, method, tol, target):
    if method == "enumerate":
        return (lambda: meicp.solve_eicp(A, B, J=J, method="enumerate", tol=tol)), f"certificate tol={tol:g}"
    if method == "active-set":
        return (lambda: meicp.solve_eicp(A, B, J=J, method="active-set", tol=tol, target=target,
                                         options={"eps_tol": tol})), \
            f"eps_tol={tol:g} target={target:.3g} sinvert+mumps nev=4"
    if method == "rayleigh":
        return (lambda: meicp.solve_eicp(A, B, J=J, method="rayleigh", tol=tol, spg_tol=tol)), \
            f"spg_tol={tol:g} n_starts=8"
    scale = max(np.abs(A).max(), np.abs(B).max(), 1.0)
    snes_type = "vinewtonssls" if method == "semismooth-ssls" else "vinewtonrsls"
    return (lambda: meicp.solve_eicp(A, B, J=J, method="semismooth", tol=tol, snes_type=snes_type,
                                     options={"snes_atol": tol * scale})), \
        f"snes_atol={tol:g}*scale {snes_type}"


def run_eicp(args):
    rows = []
    for family, name, A, B, J, target in eicp_problems(args):
        n = A.shape[0]
        t0 = time.perf_counter()
        enum = meicp.solve_eicp(A, B, J=J, method="enumerate", tol=DIRECT_TOL)
        t_enum = time.perf_counter() - t0
        ref = EiCPReference(A, B, J, enum)
        print(f"\n{name}: n = {n}, |J| = {J.size}, {len(enum.solutions)} solutions "
              f"({t_enum:.1f} s), symmetric = {ref.symmetric}", flush=True)
        methods = ["enumerate"] + [m for m in EICP_ITERATIVE if m != "rayleigh" or ref.symmetric]
        for method in methods:
            for tol in ([DIRECT_TOL] if method == "enumerate" else TOLS):
                fn, settings = eicp_call(A, B, J, method, tol, target)
                base = dict(kind="eicp", family=family, problem=name, n=n, J=J.size, method=method,
                            tol=f"{tol:g}", settings=settings, ranks=1)
                try:
                    if method == "enumerate" and t_enum > args.budget / 2:
                        wall, reps, r = t_enum, 1, enum  # the reference run is the measurement
                    else:
                        wall, reps, r = timed(fn, budget=args.budget)
                except Exception as exc:  # noqa: BLE001
                    rows.append(dict(base, status="error", note=f"{type(exc).__name__}: {exc}"[:200]))
                    print(f"  {method:12s} tol={tol:<7g} error {type(exc).__name__}: {exc}", flush=True)
                    continue
                sols = r.solutions
                if len(sols) > EICP_CHECK:
                    pick = np.random.default_rng(0).choice(len(sols), EICP_CHECK, replace=False)
                    sols = [sols[i] for i in sorted(set(pick) | set(range(5)))]
                errs, outside = [], 0
                for s in sols:
                    e, in_set = ref.error(s)
                    errs.append(e)
                    outside += not in_set
                err = max(errs) if errs else None
                res = max((s.residual for s in r.solutions), default=None)
                if res is None and r.candidates:
                    res = min(c.residual for c in r.candidates)
                note = f"{outside} certified solution(s) not in the enumeration's set" if outside else ""
                if len(r.solutions) > EICP_CHECK:
                    note = (note + "; " if note else "") + f"error over {len(sols)} of {len(r.solutions)} solutions"
                rows.append(dict(base, wall_s=f"{wall:.6g}", repeats=reps, iterations=r.iterations, status=r.status,
                                 residual=fmt(res), error=fmt(err), solutions=len(r.solutions), wrong=outside,
                                 lam=fmt(r.lam, ".12g") if r.solutions else "", note=note))
                print(f"  {method:12s} tol={tol:<7g} {wall:9.4f}s x{reps} {r.status:16s} "
                      f"res={fmt(res, '.1e'):8s} err={fmt(err, '.1e'):8s} its={r.iterations} "
                      f"sols={len(r.solutions)} λ={fmt(r.lam, '.6g') if r.solutions else ''} {note}", flush=True)
    return rows


def warm_up():
    """First PETSc/SLEPc calls pay for imports and initialisation: do them untimed."""
    M = np.array([[2.0, -1.0], [-1.0, 2.0]])
    q = np.array([-1.0, 1.0])
    for m in ("newton", "tao", "pgs", "lemke"):
        solve_lcp(M, q, method=m)
    try:
        siconos_solve(M, q, "lemke")
    except ImportError:
        pass
    A, B, J = random_sym(6, 3, 0)
    for m in ("active-set", "semismooth", "rayleigh", "enumerate"):
        meicp.solve_eicp(A, B, J=J, method=m)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--parts", nargs="+", default=["lcp", "eicp"], choices=["lcp", "eicp"],
                   help="which half to run; the other half's rows in the CSV are kept")
    p.add_argument("--condensed", nargs="+", type=int, default=[12, 100, 400], help="contacts of the condensed family")
    p.add_argument("--lattice", nargs="+", type=int, default=[6, 20, 45, 142],
                   help="nx of the lattice family (n = nx·(nx//2 − 1))")
    p.add_argument("--random-sym", nargs="+", default=["20:8", "60:10", "150:12"], help="n:|J| of random_sym problems")
    p.add_argument("--friction", nargs="+", type=int, default=[6, 8, 10], help="nx of the friction family (|J| = nx)")
    p.add_argument("--dense-limit", type=int, default=1000, help="largest n for Lemke and the Siconos (dense) solvers")
    p.add_argument("--pgs-sweeps", type=int, default=5000)
    p.add_argument("--siconos-iter", type=int, default=5000, help="iteration limit of Siconos newton-fb / pgs")
    p.add_argument("--budget", type=float, default=1.0, help="seconds of repeats per measured point")
    p.add_argument("--skip-after-failure", action=argparse.BooleanOptionalAction, default=True,
                   help="PGS: do not run tighter tolerances once a looser one failed (recorded as skipped)")
    p.add_argument("--quick", action="store_true", help="small sizes, short repeat budget (build/benchmarks)")
    args = p.parse_args()
    if args.quick:
        args.condensed, args.lattice = [12, 100], [6, 20]
        args.random_sym, args.friction = ["20:8", "60:10"], [6, 8]
        args.budget = 0.3
    warnings.filterwarnings("ignore", category=sp.SparseEfficiencyWarning)
    # solve_eicp warns on every call with tol > 1e-6; the sweep asks for such tolerances on
    # purpose: show each distinct warning once
    seen = set()

    def once(rec):
        msg = rec.getMessage()
        if msg in seen:
            return False
        seen.add(msg)
        return True

    logging.getLogger("meicp").addFilter(once)
    t0 = time.perf_counter()
    warm_up()
    rows = []
    if "lcp" in args.parts:
        rows += run_lcp(args)
    if "eicp" in args.parts:
        rows += run_eicp(args)
    out = csv_path("tradeoff")
    write_rows(out, rows, FIELDS, keep=lambda r: r["kind"] not in args.parts)
    print(f"\nwrote {len(rows)} rows to {out} in {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
