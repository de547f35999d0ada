#!/usr/bin/env python3
"""Benchmark: how λ and μ_c converge with lattice resolution, and what each scene feature costs.

Commands that produce the committed data (``docs/benchmarks/resolution.csv``, ``resolution*.png``)::

    flock /tmp/meicp-bench.lock env BENCH_ONLY=resolution bash scripts/bench.sh full
    # i.e.  OMP_NUM_THREADS=1 .venv/bin/python scripts/bench_resolution.py
    #       .venv/bin/python scripts/charts.py resolution docs/benchmarks/resolution.csv

``--quick`` (``make bench`` quick mode) runs the coarse levels only (< 2 min).

Part A, *convergence*: one physical scene — a W × H = 4 × 4 block of two bonded layers
(k = 1 below y = 2, k = 5 above; areal mass density 1 and 2), top edge held, free sides, on a
rigid rough base with every base node sliding to the right (slip+) at μ = 3 — meshed with
n = W/a cells across, nx = n + 1 nodes per row, ny = H/a + 1 rows.  Held fixed under
refinement: the physical size, the bond stiffness k (in 2-D a lattice of equal-k springs has
a modulus ∝ k whatever a), the areal mass density ρ·a (the lumped node mass is ρ a³, so the
scene's ``density`` is set to ρ_areal / a), μ and the prescribed states.  Measured per level:
the fastest divergence mode σ (λ = √σ) by ``meicp.analyze`` (the method it picked, its
evidence, where the mode lives: its share of ‖u‖² on the leading corner node and the radius
holding 90 % of it; a dense SciPy eigen-solve of the same reduced pencil as an independent
check up to 600 reduced DOFs); μ_c by ``meicp.critical_friction`` (it condenses the EiCP in
μ onto the |J| = n + 1 contact DOFs and enumerates all 2^|J| supports: a proof of the
smallest μ, up to its limit of 20 pairs, n ≤ 18), timed without its bisection check, and at
n ≤ 8 also with the check (its default there); and at n = 4, 8, …, 256 (beyond the limit from n = 32) by
the smallest μ with a certified full-support solution of the same condensed EiCP
(``meicp.contact.critical_friction.friction_pencils``; the support at which every enumerated level
attains μ_c; not a proof of minimality).  Richardson
extrapolation from the three finest dyadic levels gives the limit and the observed order
(or, when the differences grow, the growth exponent).  Controls: the same block with its
sides on rollers, and with only the middle half of the base sliding, at μ = 3 and 6.

Part B, *features*: the same scene at n = 8 (nx = 9, 162 DOFs: the largest dyadic level at
which ``analyze`` still enumerates by itself and ``critical_friction`` runs its bisection
check by default) and, for the features that scale, at n = 64 (8450 DOFs); timed with and without each feature, the MEiCP
solved by the active-set search unless the feature *is* enumeration; each run in a fresh
process (wall time of the call alone, peak RSS above the resident set before it), the
repeats interleaved so that every ratio to the base is measured side by side.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import time

import numpy as np
import scipy.linalg as sl

import meicp
from bench_common import Stage, csv_path, write_rows
from meicp.contact import pencil
from meicp.contact.critical_friction import friction_pencils
from meicp.examples import two_layer_scene

FIELDS = ["part", "problem", "quantity", "method", "settings", "ranks", "n", "nx", "ny", "spacing", "dofs",
          "retained", "complementarity", "repeat", "wall_s", "iterations", "status", "value", "sigma",
          "reference", "check_err", "error", "order", "mode_corner_share", "mode_r90_cells", "peak_rss_mb", "feature",
          "evidence"]
W, H, Y_INTERFACE, MU = 4.0, 4.0, 2.0, 3.0
TOP_DISPLACEMENT = [0.06, -0.1]   # physical units: the same at every resolution
FEATURE_N = 8      # part B: 162 DOFs, where enumeration and critical_friction still run
BIG_N = 64         # part B, active-set features only: 8450 DOFs
#: the active-set's shift at each part-B size: the default 0 at n = 8; at n = 64 the mode's σ
#: (about 21.6, part A) lies beyond the 4 eigenvalues nearest 0, so the shift a user would take
#: from the coarser levels (σ roughly ×4 per halving of a) is given
SHIFT = {FEATURE_N: None, BIG_N: 20.0}


# ---------------------------------------------------------------------------- the scene
def make_scene(n: int, *, mu: float = MU, states="slip+", interface=None, solver=None, sides="free"):
    """The physical scene of part A meshed with n cells across (a = W/n)."""
    a = W / n
    ny = round(H / a) + 1
    rows_a = round(Y_INTERFACE / a)   # nodes with y < 2 are layer A; the A–B bonds straddle y = 2 − a/2
    return two_layer_scene(n + 1, (rows_a, ny - rows_a), spacing=a, density=(1.0 / a, 2.0 / a), mu=mu,
                           states=states, load=TOP_DISPLACEMENT, sides=sides, interface=interface,
                           solver=solver, title=f"two layers 4x4 on a rough base, n={n}")


def geometry(n):
    a = W / n
    ny = round(H / a) + 1
    return {"n": n, "nx": n + 1, "ny": ny, "spacing": f"{a:.6g}", "dofs": 2 * (n + 1) * ny}


# ---------------------------------------------------------------------------- part A: λ
def dense_lambda(scene):
    """Independent check: the largest real σ > 0 of the reduced pencil (dense SciPy eig)
    whose eigenvector has x_J > 0 (the full-support MEiCP solutions), and its time."""
    t0 = time.perf_counter()
    pen = pencil(scene)
    A, B = pen.A.toarray(), pen.B.toarray()
    ev, V = sl.eig(A, B)
    best = -np.inf
    for k in np.flatnonzero(np.isfinite(ev) & (np.abs(ev.imag) <= 1e-9 * np.abs(ev[np.isfinite(ev)]).max())):
        x = V[:, k].real[pen.J]
        x = x if x.sum() > 0 else -x
        if ev[k].real > 0 and x.min() > 0:
            best = max(best, ev[k].real)
    return best, time.perf_counter() - t0, A.shape[0]


def lambda_level(n, sigmas, dense_max_r):
    """analyze() at level n; for the active-set levels the shift is guessed from the coarser
    levels (σ grows under refinement) and widened until a certified mode is found."""
    scene = make_scene(n)
    geo = geometry(n)
    guesses = [None]
    if len(sigmas) >= 2:
        g = sigmas[-1] ** 2 / sigmas[-2]
        guesses = [g, 2 * g, 0.5 * g, 4 * g, 0.25 * g]
    elif sigmas:
        guesses = [2 * sigmas[-1], sigmas[-1], 4 * sigmas[-1]]
    total, tries = 0.0, 0
    for g in guesses:
        kw = {} if g is None else {"target": g, "nev": 8}
        t0 = time.perf_counter()
        r = meicp.analyze(scene, **kw)
        total += time.perf_counter() - t0
        tries += 1
        if r.modes:
            break
    method = "enumerate" if r.evidence.startswith("enumeration") else "active-set"
    cov = r.eicp[0].coverage if r.eicp and r.eicp[0] is not None else {}
    sigma = r.modes[0].sigma if r.modes else float("nan")
    row = {"part": "convergence", "problem": "two-layer 4x4, slip+ base, mu=3", "quantity": "lambda",
           "method": method, "settings": (f"target={'0 (default)' if guesses[0] is None else 'extrapolated'};"
                                     f"nev={4 if guesses[0] is None else 8};tries={tries}"
                                     if method == "active-set" else "auto chose enumeration"),
           "ranks": 1, **geo, "retained": r.sizes.get("retained"), "complementarity": r.sizes.get("complementarity"),
           "repeat": 0, "wall_s": f"{total:.4f}",
           "iterations": cov.get("eigen_solves", cov.get("supports", "")),
           "status": "certified" if r.modes else r.status, "value": f"{math.sqrt(sigma):.12g}" if r.modes else "",
           "sigma": f"{sigma:.12g}" if r.modes else "", "evidence": r.evidence[:160]}
    if r.modes:
        share, r90 = corner_localisation(r.modes[0].x, scene)
        row["mode_corner_share"], row["mode_r90_cells"] = f"{share:.4f}", f"{r90 / (W / n):.4g}"
    if r.sizes.get("retained", 0) <= dense_max_r:
        ref, t_ref, _ = dense_lambda(scene)
        row["reference"] = f"{math.sqrt(ref):.12g}" if np.isfinite(ref) else "none"
        if r.modes and np.isfinite(ref):
            row["check_err"] = f"{abs(math.sqrt(sigma) - math.sqrt(ref)) / math.sqrt(ref):.3e}"
        row["settings"] += f";dense_ref_s={t_ref:.3f}"
    print(f"  lambda n={n:4d} dofs={geo['dofs']:7d} {method:>10}: λ = {row['value'] or '-':>14} "
          f"({row['status']}, {total:.2f} s, {tries} tr{'y' if tries == 1 else 'ies'}) dense ref {row.get('reference', '-')}",
          flush=True)
    return row, sigma


def corner_localisation(x, scene):
    """Where the mode lives: the share of its ‖u‖² on the leading bottom corner node (x = W,
    y = 0: the slip+ side) and the radius around it holding 90 % of ‖u‖² (a mode that lives
    at the lattice scale keeps r90 / a fixed)."""
    a = W / (scene.nx - 1)
    j, i = np.divmod(np.arange(scene.nx * scene.ny), scene.nx)
    d = np.hypot(i * a - W, j * a)
    e = x[0::2] ** 2 + x[1::2] ** 2
    o = np.argsort(d, kind="stable")
    c = np.cumsum(e[o]) / e.sum()
    return float(c[0]), float(d[o][np.searchsorted(c, 0.9)])


def control_rows(levels, mus, dense_max_r):
    """Controls for where the divergence mode comes from: the same block with the sides on
    rollers (x fixed), and with only the middle 1 ≤ x ≤ 3 of the base sliding (the nodes near
    the free corners sticking).  analyze() enumerates (a proof) where it chooses to; above
    that the dense full-support check of the same pencil."""
    rows = []
    for variant in ("rollers", "middle-slip"):
        for mu in mus:
            for n in levels:
                a = W / n
                kw = {"mu": mu}
                if variant == "rollers":
                    kw["sides"] = "fixed_x"
                else:
                    kw["states"] = ["slip+" if 1 - 1e-9 <= i * a <= 3 + 1e-9 else "stick" for i in range(n + 1)]
                scene = make_scene(n, **kw)
                t0 = time.perf_counter()
                r = meicp.analyze(scene)
                wall = time.perf_counter() - t0
                enum = r.evidence.startswith("enumeration")
                row = {"part": "convergence", "quantity": "control", "ranks": 1, "repeat": 0, **geometry(n),
                       "problem": {"rollers": "two-layer 4x4, sides on rollers (fixed_x), slip+ base",
                                   "middle-slip": "two-layer 4x4, free sides, slip+ only for 1<=x<=3"}[variant],
                       "settings": f"mu={mu}", "method": "enumerate" if enum else "active-set",
                       "retained": r.sizes.get("retained"), "complementarity": r.sizes.get("complementarity"),
                       "wall_s": f"{wall:.4f}", "evidence": r.evidence[:160],
                       "status": {True: "stable (proof)", False: "unstable", None: "undecided"}[r.stable],
                       "sigma": f"{r.modes[0].sigma:.8g}" if r.modes else ""}
                if not enum and r.sizes.get("retained", 0) <= dense_max_r:
                    ref, _, _ = dense_lambda(scene)
                    row["reference"] = "none" if not np.isfinite(ref) else f"{math.sqrt(ref):.8g}"
                    if r.stable is None and not np.isfinite(ref):
                        row["status"] = "no full-support mode (dense check)"
                rows.append(row)
                print(f"  control {variant:>11} mu={mu} n={n:3d}: {row['status']} ({row['method']}, {wall:.2f} s)",
                      flush=True)
    return rows


# ---------------------------------------------------------------------------- part A: μ_c
def mu_c_full_support(Ac, Bc):
    """The smallest μ > 0 of the condensed pencil (``meicp.contact.critical_friction.friction_pencils``)
    with an eigenvector x > 0 (y = 0: a certified EiCP solution on the full support; its
    minimality is not proved).  Solved in ν = 1/μ, whose second matrix −Ac is positive
    definite (Bc is nearly singular)."""
    nu, V = sl.eig(-Bc, -Ac)
    for k in np.argsort(-nu.real):
        if not np.isfinite(nu[k]) or abs(nu[k].imag) > 1e-10 * abs(nu[k]) or nu[k].real <= 0:
            continue
        x = V[:, k].real
        x = x if x.sum() > 0 else -x
        if x.min() > 0:
            mu = 1.0 / nu[k].real
            res = np.linalg.norm((mu * Bc - Ac) @ x) / (np.linalg.norm(Ac, 1) * np.linalg.norm(x))
            return mu, res
    return math.inf, math.nan


#: μ_c methods: key -> (critical_friction keyword arguments, settings text)
CF_VARIANTS = {
    "critical_friction": ({"bisection": False}, "condensed enumeration, bisection=False"),
    "critical_friction+check": ({}, "condensed enumeration + bisection check (the default at this size)"),
}


def mu_c_rows(cf_levels, enum_levels, full_levels):
    """μ_c per level: critical_friction (condensed, no check) at enum_levels; with its check
    at cf_levels; the full-support value at full_levels."""
    rows = []
    base = {"part": "convergence", "problem": "two-layer 4x4, slip+ base, mu=3", "quantity": "mu_c", "ranks": 1,
            "repeat": 0}
    for n in sorted(set(cf_levels) | set(enum_levels) | set(full_levels)):
        scene, geo = make_scene(n), geometry(n)
        variants = (["critical_friction"] if n in enum_levels else []) + \
            (["critical_friction+check"] if n in cf_levels else [])
        for m in variants:
            kw, text = CF_VARIANTS[m]
            t0 = time.perf_counter()
            v = meicp.critical_friction(scene, **kw)
            rows.append({**base, **geo, "method": m, "settings": text, "wall_s": f"{time.perf_counter() - t0:.4f}",
                         "status": "proved", "value": f"{v:.12g}", "complementarity": n + 1,
                         "iterations": 2 ** (n + 1)})
        if n in full_levels:
            t0 = time.perf_counter()
            (Ac, Bc, _), = friction_pencils(scene)
            v, res = mu_c_full_support(Ac, Bc)
            rows.append({**base, **geo, "method": "condensed-full-support", "settings": f"residual={res:.1e}",
                         "wall_s": f"{time.perf_counter() - t0:.4f}", "status": "certified",
                         "value": f"{v:.12g}", "complementarity": n + 1})
        print(f"  mu_c   n={n:4d} " + "  ".join(f"{r['method']} {float(r['value']):.10f} ({float(r['wall_s']):.2f} s)"
                                              for r in rows if r["n"] == n), flush=True)
    # independent checks: each value against critical_friction (condensed) at the same n
    for r in rows:
        ref = [q for q in rows if q["n"] == r["n"] and q["method"] == "critical_friction"]
        if ref and ref[0] is not r:
            r["reference"] = ref[0]["value"]
            r["check_err"] = f"{abs(float(r['value']) - float(ref[0]['value'])) / float(ref[0]['value']):.3e}"
    return rows


# ---------------------------------------------------------------------------- extrapolation
def richardson(ns, values):
    """From the three finest dyadic levels: observed order p, limit q∞ (None if the
    differences do not shrink, i.e. no convergence)."""
    (n1, q1), (n2, q2), (n3, q3) = sorted(zip(ns, values))[-3:]
    if not (n2 == 2 * n1 and n3 == 2 * n2):
        raise ValueError("Richardson needs three dyadic levels")
    d1, d2 = q2 - q1, q3 - q2
    if d1 == 0 or d2 / d1 <= 0 or abs(d2) >= abs(d1):
        return None, None, d2 / d1 if d1 else math.nan
    p = math.log2(d1 / d2)
    return p, q3 + d2 / (2 ** p - 1), d2 / d1


def add_extrapolation(rows, quantity, method):
    mine = [r for r in rows if r["quantity"] == quantity and r["method"] == method and r["value"]
            and math.log2(int(r["n"]) / 4).is_integer()]
    if len(mine) < 3:
        return None
    ns = [int(r["n"]) for r in mine]
    vals = [float(r["value"]) for r in mine]
    p, limit, ratio = richardson(ns, vals)
    finest = max(ns)
    out = {"part": "convergence", "problem": mine[0]["problem"], "quantity": quantity + "_limit", "method": method,
           "ranks": 1, "n": finest, "repeat": 0}
    if p is None:
        # no limit: fit the growth q ∝ n^s on the three finest levels
        s = math.log(vals[-1] / vals[-3]) / math.log(ns[-1] / ns[-3]) if vals[-3] > 0 else math.nan
        out.update(status="diverges", order=f"{s:.4f}",
                   settings=f"difference ratio {ratio:.3f} (>= 1: no convergence); growth exponent q ~ n^{s:.3f}")
        print(f"  {quantity}: does not converge (difference ratio {ratio:.3f}); grows like n^{s:.3f}")
        return out
    for r in rows:
        if r["quantity"] == quantity and r.get("value"):
            r["error"] = f"{abs(float(r['value']) - limit) / abs(limit):.4e}"
            r["order"] = f"{p:.4f}"
    e_fin = abs(vals[-1] - limit) / abs(limit)
    n_needed = finest * (e_fin / 1e-3) ** (1.0 / p) if e_fin > 1e-3 else None
    reached = sorted(int(r["n"]) for r in rows if r["quantity"] == quantity and r.get("error")
                     and float(r["error"]) <= 1e-3)
    out.update(status="converges", value=f"{limit:.12g}", order=f"{p:.4f}",
               settings=(f"Richardson n={ns[-3]},{ns[-2]},{ns[-1]}; difference ratio {ratio:.4f}; "
                         + (f"1e-3 first reached at n={reached[0]}" if reached else
                            f"1e-3 not reached; predicted n >= {n_needed:.0f} (nx >= {n_needed + 1:.0f})")))
    print(f"  {quantity}: limit {limit:.10f}, observed order {p:.3f}; {out['settings']}")
    return out


# ---------------------------------------------------------------------------- part B
#: feature key -> (description, scene changes).  Every analyze() runs the active-set search
#: (the method that scales) unless the key says otherwise, so each ratio isolates one feature.
FEATURES = {
    "base": "prescribed slip+ at every base node, bonded layers, analyze(method='active-set')",
    "enumeration": "base, analyze(method='enumerate'): every support, a proof",
    "grazing-1": "base with 1 grazing base node (3 tangential cases, one MEiCP each)",
    "grazing-2": "base with 2 grazing base nodes (9 tangential cases)",
    "interface-stick": "base + frictional A/B interface, every pair sticking (nonsymmetric B)",
    "interface-slip": "base + frictional A/B interface, every pair slip+ at mu=0.3 (|J| doubles)",
    "static-states": "base states from the static frictional LCP (states='solve', top pushed (0.06,-0.1))",
    "critical-friction": "meicp.critical_friction of the base scene (condensed enumeration + bisection check)",
    "critical-friction-nocheck": "meicp.critical_friction(bisection=False): the condensed enumeration alone",
}


def feature_scene(name, n):
    states = "slip+"
    interface = None
    if name.startswith("grazing"):
        states = ["slip+"] * (n + 1)
        for i in (n // 4, (3 * n) // 4)[:int(name[-1])]:
            states[i] = "grazing"
    if name == "interface-stick":
        interface = {"kind": "frictional", "friction": 0.3, "states": "stick"}
    if name == "interface-slip":
        interface = {"kind": "frictional", "friction": 0.3, "states": "slip+"}
    if name == "static-states":
        states = "solve"
    return make_scene(n, states=states, interface=interface)


def run_feature(name, n):
    """One timed run in this (fresh) process; prints a JSON line."""
    meicp.analyze(make_scene(4), method="active-set")   # warm-up: imports, PETSc initialisation
    meicp.analyze(make_scene(4), method="enumerate")
    scene = feature_scene(name, n)
    method = "enumerate" if name == "enumeration" else "active-set"
    with Stage() as st:
        if name.startswith("critical-friction"):
            v = meicp.critical_friction(scene, **{"critical-friction": {},
                                                  "critical-friction-nocheck": {"bisection": False}}[name])
        else:
            kw = {"target": SHIFT[n], "nev": 8} if method == "active-set" and SHIFT.get(n) else {}
            r = meicp.analyze(scene, method=method, **kw)
    if name.startswith("critical-friction"):
        out = {"status": "solved", "value": v, "method": "critical_friction", "sizes": {}, "evidence": name}
    else:
        out = {"status": r.status, "value": r.modes[0].sigma if r.modes else None, "method": method,
               "sizes": r.sizes, "stable": r.stable, "evidence": r.evidence[:160],
               "cases": r.evidence.count("|") + 1, "timings": r.timings}
    out.update(wall=st.wall, peak_mb=st.delta / 2**20, n=n, dofs=scene.n_dofs)
    print("RESULT " + json.dumps(out, default=str), flush=True)


def feature_rows(plan, repeats):
    """plan: list of (n, feature); every repeat runs the whole plan (rotated), so each ratio
    to the base at the same n is measured side by side."""
    rows = []
    for rep in range(repeats):
        order = plan[rep % len(plan):] + plan[:rep % len(plan)]   # rotate: no feature always first
        for n, name in order:
            p = subprocess.run([sys.executable, __file__, "--one-feature", name, "--feature-n", str(n)],
                               capture_output=True, text=True,
                               env=dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1"))
            line = [ln for ln in p.stdout.splitlines() if ln.startswith("RESULT ")]
            if p.returncode or not line:
                rows.append({"part": "features", "feature": name, "repeat": rep, "status": "failed", **geometry(n),
                             "evidence": (p.stderr.strip().splitlines() or ["?"])[-1][:160], "ranks": 1,
                             "problem": "two-layer 4x4, slip+ base, mu=3", "quantity": "cost"})
                print(f"  feature n={n:3d} {name:>18} rep {rep}: FAILED {rows[-1]['evidence']}", flush=True)
                continue
            d = json.loads(line[0][7:])
            sizes = d.get("sizes") or {}
            rows.append({"part": "features", "problem": "two-layer 4x4, slip+ base, mu=3", "quantity": "cost",
                         "feature": name, "method": d["method"], "settings": FEATURES[name], "ranks": 1,
                         **geometry(d["n"]), "retained": sizes.get("retained"),
                         "complementarity": sizes.get("complementarity"), "repeat": rep,
                         "wall_s": f"{d['wall']:.4f}", "iterations": d.get("cases", ""), "status": d["status"],
                         "value": "" if d["value"] is None else f"{d['value']:.10g}",
                         "peak_rss_mb": f"{d['peak_mb']:.1f}", "evidence": d.get("evidence", "")})
            print(f"  feature n={n:3d} {name:>18} rep {rep}: {d['wall']:.3f} s, peak +{d['peak_mb']:.1f} MB, "
                  f"{d['method']}, {d['status']}, value {rows[-1]['value']}", flush=True)
    return rows


# ---------------------------------------------------------------------------- main
def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="coarse levels only (< 2 min)")
    ap.add_argument("--parts", nargs="+", default=["convergence", "features"], choices=["convergence", "features"])
    ap.add_argument("--repeats", type=int, default=None)
    ap.add_argument("--one-feature", help=argparse.SUPPRESS)
    ap.add_argument("--feature-n", type=int, default=FEATURE_N, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.one_feature:
        run_feature(args.one_feature, args.feature_n)
        return 0
    if args.quick:
        lam_levels, dense_r = [4, 8, 16, 32, 64], 600
        cf, enum, full, ctrl = [4, 6], [4, 6, 8, 10, 12], [4, 8, 16, 32, 64], [4, 8]
        repeats = args.repeats or 3
        plan = [(8, k) for k in ("base", "enumeration", "grazing-1", "interface-slip", "static-states",
                                 "critical-friction-nocheck")]
    else:
        lam_levels, dense_r = [4, 8, 16, 32, 64, 128, 256, 512], 600
        cf, enum, full = [4, 6, 8], [4, 6, 8, 10, 12, 14, 16, 18], [4, 8, 16, 32, 64, 128, 256]
        ctrl = [4, 8, 16]
        repeats = args.repeats or 5
        plan = [(8, k) for k in FEATURES] + [(BIG_N, k) for k in FEATURES
                                             if k != "enumeration" and not k.startswith("critical-friction")]
    path = csv_path("resolution")
    rows = []
    if "convergence" in args.parts:
        print("part A: resolution convergence", flush=True)
        sigmas = []
        for n in lam_levels:
            row, sigma = lambda_level(n, sigmas, dense_r)
            rows.append(row)
            if math.isfinite(sigma):
                sigmas.append(sigma)
            else:
                break
        rows += mu_c_rows(cf, enum, full)
        rows += control_rows(ctrl, (3.0, 6.0), dense_r)
        for quantity, method in (("lambda", None), ("mu_c", "condensed-full-support")):
            if method is None:   # λ: whatever method analyze used at each level
                for r in rows:
                    if r["quantity"] == "lambda":
                        r["_m"] = r["method"]
                        r["method"] = "analyze"
                ext = add_extrapolation(rows, quantity, "analyze")
                for r in rows:
                    if "_m" in r:
                        r["method"] = r.pop("_m")
            else:
                ext = add_extrapolation(rows, quantity, method)
            if ext:
                rows.append(ext)
    if "features" in args.parts:
        print(f"part B: cost of scene features ({repeats} repeats, fresh process each)", flush=True)
        rows += feature_rows(plan, repeats)
    parts = set(args.parts)
    write_rows(path, rows, FIELDS, keep=lambda r: r.get("part") not in parts)
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
