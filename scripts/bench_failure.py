#!/usr/bin/env python3
"""Failure map (issue 7 §4): where each EiCP/MEiCP and LCP method fails, and whether it
says so.  Five parameter sweeps; at every point each method's answer is judged against an
independent reference computed here (dense enumeration of every support with
``scipy.linalg.eig`` / ``numpy.linalg.solve``, or the analytic answer), never against
meicp's own solvers:

1. ``mu``: friction μ across μ_c on ``data/scenes/two_layers.toml`` (every base node
   slip+; μ_c = 1.90603249), dense near μ_c.  Methods: ``solve_eicp`` enumerate,
   active-set, rayleigh, semismooth on the reduced pencil (σ ≥ 0), ``meicp.analyze`` and
   ``meicp.critical_friction`` (its verdict μ ≥ μ_c against the reference's existence of
   a σ ≥ 0 mode; μ_c itself against a bisection on the reference).
2. ``contrast``: the same scene at μ = 3 with k_B/k_A from 1 to 10^6.
3. ``degenerate``: (a) the Z-family ``A = −(a(eeᵀ − I) + I + δ·diag(0..n−1))``, B = I,
   n = 8: at δ = 0 every support of one size has the same eigenvalue and every reduced
   pencil of size ≥ 2 has a repeated eigenvalue; the solutions are exactly
   ``{λ_min(A_SS)}`` for the 255 supports (Perron–Frobenius), analytically;
   (b) two identical, uncoupled copies of the two_layers pencil (mirror twins), the second
   at μ = 3(1 + δ): at δ = 0 every eigenvalue is double and the solution set is a cone.
4. ``flutter``: nonsymmetric pencils whose eigenvalues turn complex: (a) a mode-coupling
   family ``A(γ)`` (two real positive σ merge at γ* = 0.5 into a complex pair with
   Re σ > 0: no divergence mode beyond, the answer must be "none"); (b) the sheared
   two_layers lattice (shear 0.5, states stick, slip+ ×3, stick) across μ: complex σ
   from μ ≈ 2, never a real σ ≥ 0.
5. ``lcp``: the static slip LCP of the two_layers lattice, every base node sliding in +x:
   ``g = (G_nn − μ G_nt) r_n + c_n ≥ 0 ⊥ r_n ≥ 0`` (G the condensed compliance), for the
   scene's compressive load and for a mixed load.  ``meicp.classify`` records P / Q / R0;
   every LCP method (lemke, enumerate, pgs, newton, tao, auto, Siconos lemke, enum,
   newton-fb, pgs) against the enumeration reference.

Outcomes (column ``outcome``): ``correct``; ``wrong`` (a success whose answer is not the
reference's); ``failed`` (a failure status while a solution exists); ``none_reported``
(a failure status, or no answer, where the reference has no solution either — honest, but
not a proof); ``na`` (the method refuses this input with a clear error, e.g. rayleigh on a
nonsymmetric pencil).  A method that claims all solutions (enumerate) or a verdict
(analyze, critical_friction) is correct only if it matches the reference exactly; a
method that promises one certified solution is correct if it returns one that is in the
reference set.

    .venv/bin/python scripts/bench_failure.py            # full: docs/benchmarks/failure.csv
    .venv/bin/python scripts/bench_failure.py --quick    # fewer points (make bench quick)
    .venv/bin/python scripts/charts.py failure docs/benchmarks/failure.csv
"""

from __future__ import annotations

import argparse
import itertools
import time
import warnings

import numpy as np
import scipy.linalg as sla

import meicp
from bench_common import csv_path, write_rows
from meicp.core.errors import ConvergenceError, ProblemError
from meicp.examples.failure_map import (MU_C, all_eicp_solutions, all_lcp_solutions, dense_pencil, mode_coupling,
                                        slip_lcp, slip_lcp_data, two_layers, z_family)
from meicp.lcp.siconos import siconos_solve

FIELDS = ["sweep", "problem", "param", "method", "settings", "ranks", "wall_s", "iterations", "status",
          "outcome", "error", "reference", "answer", "residual", "classes", "detail"]

EIG_METHODS = ("enumerate", "active-set", "rayleigh", "semismooth")
LCP_METHODS = ("lemke", "enumerate", "pgs", "newton", "tao", "auto")
SICONOS = ("lemke", "enum", "newton-fb", "pgs")


# ----------------------------------------------------------------------------- μ_c by bisection on the brute force

def mu_c_reference(make, lo=0.0, hi=10.0, rtol=1e-9):
    """μ_c by bisection on the existence of a σ ≥ 0 mode in the brute-force reference."""
    def exists(mu):
        A, B, J = dense_pencil(make(mu))
        return bool(all_eicp_solutions(A, B, J, lam_min=0.0)[0])
    if not exists(hi):
        return np.inf
    if exists(lo):
        return lo
    while hi - lo > max(rtol * hi, 4 * np.spacing(hi)):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if exists(mid) else (mid, hi)
    return hi


# ----------------------------------------------------------------------------- judging

def lam_close(a, b, rtol=1e-7):
    return abs(a - b) <= rtol * max(1.0, abs(a), abs(b))


def judge_eicp(method, res, ref, status):
    """Outcome of one solve_eicp result against the reference list of (λ, support)."""
    lams_ref = [l for l, _ in ref]
    if method == "enumerate":
        got = [(s.lam, tuple(int(j) for j in s.support)) for s in res.solutions]
        if not ref:
            ok = not got and status == "no_solution"
        else:
            ok = (all(any(lam_close(l, m) for m in (g[0] for g in got)) for l in lams_ref)
                  and all(any(lam_close(g[0], l) for l in lams_ref) for g in got))
        err = _lam_error(got and [g[0] for g in got], lams_ref)
        return ("correct" if ok else "wrong"), err
    if res.solutions:
        bad = [s.lam for s in res.solutions if not any(lam_close(s.lam, l) for l in lams_ref)]
        return ("wrong" if bad else "correct"), _lam_error([s.lam for s in res.solutions], lams_ref)
    return ("failed" if ref else "none_reported"), float("nan")


def _lam_error(got, ref):
    if not got or not ref:
        return float("nan")
    return max(min(abs(g - l) / max(1.0, abs(l)) for l in ref) for g in got)


def run_eicp_methods(A, B, J, ref, lam_min, common, rows, methods=EIG_METHODS):
    for method in methods:
        t0 = time.perf_counter()
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                res = meicp.solve_eicp(A, B, J=J, method=method, lam_min=lam_min)
        except ProblemError as exc:
            rows.append(dict(common, method=method, wall_s=f"{time.perf_counter() - t0:.4g}", status="refused",
                             outcome="na", detail=str(exc)[:200]))
            continue
        wall = time.perf_counter() - t0
        outcome, err = judge_eicp(method, res, ref, res.status)
        answer = ";".join(f"{s.lam:.10g}" for s in res.solutions[:8]) or "none"
        rows.append(dict(common, method=method, wall_s=f"{wall:.4g}", iterations=res.iterations, status=res.status,
                         outcome=outcome, error=_fmt(err), answer=answer,
                         residual=_fmt(max((s.residual for s in res.solutions), default=float("nan"))),
                         detail=(res.message or "")[:200]))


def run_analyze(sc, ref, common, rows, mu=None, mu_c_ref=None):
    for method in ("auto", "active-set"):
        _run_analyze(sc, ref, common, rows, method)
    if mu is not None:
        _run_critical_friction(sc, ref, common, rows, mu, mu_c_ref)


def _run_analyze(sc, ref, common, rows, method):
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = meicp.analyze(sc, method=method)
    wall = time.perf_counter() - t0
    sig = sorted((m.sigma for m in r.modes), reverse=True)
    lams_ref = [l for l, _ in ref]
    # the references are divergence modes: judge the divergence verdict, not `stable`, which
    # also counts flutter of steady sliding (docs/flutter.md) since issue 15
    if r.divergence is None:
        outcome = "failed" if ref else "none_reported"
    elif not r.divergence:
        outcome = "wrong" if ref else "correct"
    else:
        outcome = ("correct" if ref and all(any(lam_close(s, l) for l in lams_ref) for s in sig)
                   and lam_close(sig[0], max(lams_ref)) else "wrong")
    verdict = {True: "divergence", False: "no divergence", None: "divergence undecided"}[r.divergence]
    rows.append(dict(common, method="analyze" if method == "auto" else f"analyze {method}", wall_s=f"{wall:.4g}", status=f"{r.status}:{verdict}",
                     outcome=outcome, error=_fmt(_lam_error(sig, lams_ref)),
                     answer=";".join(f"{s:.10g}" for s in sig) or "none", detail=(r.evidence or "")[:200]))


def _run_critical_friction(sc, ref, common, rows, mu, mu_c_ref):
    t0 = time.perf_counter()
    try:
        # the divergence onset μ_c, which the reference is: the float of critical_friction with
        # flutter is the overall onset (two_layers.toml flutters from 0.6308), judged wrong here
        mc = meicp.critical_friction(sc, flutter=False)
        status = "solved"
    except ConvergenceError:
        mc, status = float("nan"), "convergence_error"
    wall = time.perf_counter() - t0
    if not np.isfinite(mc) and status != "solved":
        outcome = "failed" if ref else "none_reported"
    else:
        # its verdict at this μ: a σ ≥ 0 mode exists iff μ ≥ μ_c
        outcome = "correct" if (mu >= mc) == bool(ref) else "wrong"
    err = abs(mc - mu_c_ref) / mu_c_ref if mu_c_ref and np.isfinite(mu_c_ref) else float("nan")
    rows.append(dict(common, method="critical_friction", wall_s=f"{wall:.4g}", status=status,
                     outcome=outcome, error=_fmt(err), answer=f"mu_c={mc:.10g}",
                     detail=f"reference mu_c (bisection on brute force) {mu_c_ref:.10g}"))


def _fmt(v):
    return "" if v is None or (isinstance(v, float) and not np.isfinite(v)) else f"{v:.3g}"


def _ref_text(ref, ncomplex=0):
    s = ";".join(f"{l:.10g}" for l in sorted({round(l, 12) for l, _ in ref}, reverse=True)[:8]) if ref else "none"
    return s + (f" (+{ncomplex} complex)" if ncomplex else "")


# ----------------------------------------------------------------------------- sweeps

def sweep_mu(quick):
    mus = ([0.0, 1.0, 1.8, MU_C * (1 - 1e-6), MU_C * (1 + 1e-6), 2.0, 3.0] if quick else
           [0.0, 0.25, 0.5, 1.0, 1.5, 1.8, 1.9, MU_C * (1 - 1e-4), MU_C * (1 - 1e-6), MU_C * (1 + 1e-6),
            MU_C * (1 + 1e-4), 1.92, 2.0, 2.5, 3.0, 3.8])
    mu_c_ref = mu_c_reference(lambda m: two_layers(mu=m), rtol=1e-13)
    # μ_c(1 ± 1e-10): σ = ∓5e-11; before the fix of issue 7 the −5e-11 counted as a mode
    mus = sorted(mus + [mu_c_ref * (1 - 1e-10), mu_c_ref * (1 + 1e-10)])
    rows = []
    for mu in mus:
        sc = two_layers(mu=mu)
        A, B, J = dense_pencil(sc)
        ref, nc = all_eicp_solutions(A, B, J, lam_min=0.0)
        top = max(l for l, _ in all_eicp_solutions(A, B, J)[0])  # the largest real MEiCP σ, any sign
        common = dict(sweep="mu", problem=f"two_layers mu={mu:.10g}", param=f"{mu:.10g}", settings="lam_min=0",
                      ranks=1, reference=_ref_text(ref, nc), classes=f"largest real sigma={top:.6g}")
        run_eicp_methods(A, B, J, ref, 0.0, common, rows)
        run_analyze(sc, ref, common, rows, mu=mu, mu_c_ref=mu_c_ref)
        print(f"mu={mu:.8g}: ref {common['reference']}", flush=True)
    return rows


def sweep_contrast(quick):
    ratios = [1, 1e2, 1e4, 1e6] if quick else [1, 10, 1e2, 1e3, 1e4, 1e5, 1e6]
    rows = []
    for ratio in ratios:
        make = (lambda m, kB=float(ratio): two_layers(mu=m, kB=kB))
        sc = make(3.0)
        A, B, J = dense_pencil(sc)
        ref, nc = all_eicp_solutions(A, B, J, lam_min=0.0)
        mu_c_ref = mu_c_reference(make, hi=50.0)
        common = dict(sweep="contrast", problem=f"two_layers kB/kA={ratio:g} mu=3", param=f"{ratio:g}",
                      settings="lam_min=0", ranks=1, reference=_ref_text(ref, nc))
        run_eicp_methods(A, B, J, ref, 0.0, common, rows)
        run_analyze(sc, ref, common, rows, mu=3.0, mu_c_ref=mu_c_ref)
        print(f"kB/kA={ratio:g}: ref {common['reference']} mu_c {mu_c_ref:.8g} cond(A) {np.linalg.cond(A):.2e}",
              flush=True)
    return rows


def sweep_degenerate(quick):
    deltas = [0.0, 1e-12, 1e-8, 1e-4, 1e-1] if quick else [0.0, 1e-14, 1e-12, 1e-10, 1e-8, 1e-6, 1e-4, 1e-2, 1e-1]
    rows = []
    for d in deltas:
        A, B = z_family(d)
        n = A.shape[0]
        J = np.arange(n)
        # analytic reference: every nonempty S gives λ_min(A_SS) with a positive Perron vector
        ref = [(float(np.linalg.eigvalsh(A[np.ix_(S, S)])[0]), tuple(S))
               for k in range(1, n + 1) for S in itertools.combinations(range(n), k)]
        common = dict(sweep="degenerate", problem=f"z_family n=8 delta={d:g}", param=f"{d:g}",
                      settings="EiCP, all lam", ranks=1, reference=f"{len(ref)} solutions (analytic)")
        run_eicp_methods(A, B, J, ref, None, common, rows)
        # enumerate must find every (support, λ) pair, not only every λ value
        for r in rows[-4:]:
            if r["method"] == "enumerate" and r["outcome"] == "correct":
                res = meicp.solve_eicp(A, B, J=J, method="enumerate")
                got = {tuple(int(j) for j in s.support) for s in res.solutions}
                if len(res.solutions) != len(ref) or got != {S for _, S in ref}:
                    r["outcome"] = "wrong"
                    r["detail"] = f"{len(res.solutions)} solutions, {len(got)} supports, reference {len(ref)}"
        print(f"z delta={d:g}: " + " ".join(f"{r['method']}={r['outcome']}" for r in rows[-4:]), flush=True)
    # mirror twins: two uncoupled copies of the two_layers pencil, the second at μ = 3(1 + δ)
    for d in deltas:
        A1, B1, J1 = dense_pencil(two_layers(mu=3.0))
        A2, B2, J2 = dense_pencil(two_layers(mu=3.0 * (1 + d)))
        n1 = A1.shape[0]
        A, B = sla.block_diag(A1, A2), sla.block_diag(B1, B2)
        J = np.concatenate([J1, J2 + n1])
        ref1, _ = all_eicp_solutions(A1, B1, J1, lam_min=0.0)
        ref2, _ = all_eicp_solutions(A2, B2, J2, lam_min=0.0)
        # block-diagonal MEiCP: its λ values are those of either block (x = (αξ₁, βξ₂))
        ref = ref1 + ref2
        common = dict(sweep="degenerate", problem=f"twin two_layers mu=3,3(1+{d:g})", param=f"{d:g}",
                      settings="lam_min=0", ranks=1, reference=_ref_text(ref))
        run_eicp_methods(A, B, J, ref, 0.0, common, rows)
        print(f"twin delta={d:g}: " + " ".join(f"{r['method']}={r['outcome']}" for r in rows[-4:]), flush=True)
    return rows


def sweep_flutter(quick):
    gammas = [0.0, 0.3, 0.45, 0.5, 0.55, 0.7, 1.0] if quick else \
        [0.0, 0.1, 0.2, 0.3, 0.4, 0.45, 0.48, 0.5, 0.52, 0.55, 0.6, 0.7, 0.85, 1.0, 1.5]
    rows = []
    for g in gammas:
        A, B, J = mode_coupling(g)
        ref, nc = all_eicp_solutions(A, B, J, lam_min=0.0)
        ev = sla.eigvals(A, B)
        common = dict(sweep="flutter", problem=f"mode_coupling gamma={g:g}", param=f"{g:g}", settings="lam_min=0",
                      ranks=1, reference=_ref_text(ref, nc),
                      classes=f"max|Im sigma|={np.abs(ev.imag).max():.3g}")
        run_eicp_methods(A, B, J, ref, 0.0, common, rows)
        print(f"gamma={g:g}: ref {common['reference']}", flush=True)
    mus = [0.5, 1.0, 2.0, 4.0, 8.0] if quick else [0.5, 1.0, 1.5, 1.75, 2.0, 2.5, 3.0, 4.0, 6.0, 8.0, 12.0, 16.0]
    states = '["stick", "slip+", "slip+", "slip+", "stick"]'
    for mu in mus:
        sc = two_layers(mu=mu, shear=0.5, states=states)
        A, B, J = dense_pencil(sc)
        ref, nc = all_eicp_solutions(A, B, J, lam_min=0.0)
        ev = sla.eigvals(A, B)
        top = ev[np.argmax(ev.real)]
        common = dict(sweep="flutter", problem=f"sheared stick/slip mu={mu:g}", param=f"{mu:g}",
                      settings="lam_min=0", ranks=1, reference=_ref_text(ref, nc),
                      classes=f"max|Im sigma|={np.abs(ev.imag).max():.3g}; top sigma={top.real:.4g}{top.imag:+.4g}j")
        run_eicp_methods(A, B, J, ref, 0.0, common, rows)
        run_analyze(sc, ref, common, rows)
        print(f"sheared mu={mu:g}: ref {common['reference']} {common['classes']}", flush=True)
    return rows


def judge_lcp(method, res, ref):
    if method == "enumerate" or method == "siconos-enum":
        pass
    x = res.x if res.success else None
    if method == "enumerate":
        got = res.solutions if res.success else []
        if not ref:
            return ("correct" if res.status == "infeasible" else ("wrong" if got else "none_reported")), float("nan")
        match = len(got) == len(ref) and all(any(np.allclose(g, r, rtol=1e-6, atol=1e-9) for g in got) for r in ref)
        return ("correct" if match else "wrong"), _x_error(got[0] if got else None, ref)
    if x is None:
        if res.status == "infeasible" and not ref:
            return "correct", float("nan")
        return ("failed" if ref else "none_reported"), float("nan")
    if not ref:
        return "wrong", float("nan")
    err = _x_error(x, ref)
    return ("correct" if err <= 1e-6 else "wrong"), err


def _x_error(x, ref):
    if x is None or not ref:
        return float("nan")
    return min(np.abs(x - r).max() / max(1.0, np.abs(r).max()) for r in ref)


def sweep_lcp(quick):
    data = Gnn, Gnt, cn = slip_lcp_data()

    def min_minor(mu):  # brute force over the 31 principal minors (independent of classify)
        M = Gnn - mu * Gnt
        return min(np.linalg.det(M[np.ix_(S, S)]) for k in range(1, cn.size + 1)
                   for S in itertools.combinations(range(cn.size), k))
    lo, hi = 0.0, 10.0  # P is lost where the smallest principal minor crosses 0
    while hi - lo > 1e-10:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if min_minor(mid) > 0 else (lo, mid)
    mu_p = hi
    mus = [0.0, 1.0, 1.8, 2.0, 3.0, 6.0] if quick else \
        [0.0, 0.5, 1.0, 1.5, 1.8, 1.85, 1.9, MU_C, 1.92, 1.95, 2.0, 2.5, 3.0, 4.0, 6.0, 10.0]
    loads = {"compression": cn / np.abs(cn).max(),
             "lift": np.ones(cn.size)}
    rows = []
    for load, q in loads.items():
        for mu in mus:
            M, _ = slip_lcp(mu, data)
            ref, singular = all_lcp_solutions(M, q)
            assert singular == 0
            c = meicp.classify(M)
            cls = (f"P={c.p_matrix} Q={c.q_matrix} R0={c.r0} E0={c.semimonotone} "
                   f"v={c.game_value.value:.3g}" if c.game_value is not None else "") + f" mu_P={mu_p:.6g}"
            common = dict(sweep="lcp", problem=f"slip_lcp {load} mu={mu:.10g}", param=f"{mu:.10g}",
                          settings=f"load={load}", ranks=1, reference=f"{len(ref)} solution(s)", classes=cls)
            for method in LCP_METHODS + tuple(f"siconos-{s}" for s in SICONOS):
                t0 = time.perf_counter()
                try:
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")
                        if method.startswith("siconos-"):
                            res = siconos_solve(M, q, method.split("-", 1)[1], max_iter=2000)
                        else:
                            res = meicp.solve_lcp(M, q, method=method)
                except ProblemError as exc:
                    rows.append(dict(common, method=method, wall_s=f"{time.perf_counter() - t0:.4g}",
                                     status="refused", outcome="na", detail=str(exc)[:200]))
                    continue
                wall = time.perf_counter() - t0
                outcome, err = judge_lcp(method, res, ref)
                answer = "none" if res.x is None or not res.success else ";".join(f"{v:.6g}" for v in res.x)
                if method == "enumerate" and res.success:
                    answer = f"{len(res.solutions)} solution(s)"
                rows.append(dict(common, method=method, wall_s=f"{wall:.4g}", iterations=res.iterations,
                                 status=res.status, outcome=outcome, error=_fmt(err), answer=answer,
                                 residual=_fmt(res.residual if res.residual is not None else float("nan")),
                                 detail=(res.message or "")[:200]))
            print(f"lcp {load} mu={mu:.8g}: {len(ref)} sol, {cls}: "
                  + " ".join(f"{r['method']}={r['outcome']}" for r in rows[-10:]), flush=True)
    return rows


SWEEPS = {"mu": sweep_mu, "contrast": sweep_contrast, "degenerate": sweep_degenerate, "flutter": sweep_flutter,
          "lcp": sweep_lcp}


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--quick", action="store_true", help="fewer points per sweep (make bench quick)")
    p.add_argument("--sweeps", nargs="+", choices=sorted(SWEEPS), default=list(SWEEPS))
    args = p.parse_args(argv)
    t0 = time.perf_counter()
    out = csv_path("failure")
    for name in args.sweeps:
        rows = SWEEPS[name](args.quick)
        # one sweep's rows replace that sweep's old rows (re-running one sweep keeps the others)
        write_rows(out, rows, FIELDS, keep=lambda r, name=name: r["sweep"] != name)
        counts = {}
        for r in rows:
            counts[r["outcome"]] = counts.get(r["outcome"], 0) + 1
        print(f"== {name}: {len(rows)} rows {counts} ({time.perf_counter() - t0:.1f} s so far) -> {out}", flush=True)


if __name__ == "__main__":
    main()
