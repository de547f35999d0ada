"""The failure map's problems and their brute-force references (docs/benchmarks.md,
"Failure map"; ``scripts/bench_failure.py`` sweeps them, tests/test_failure_modes.py pins
points of it).

Problems: :func:`two_layers` (``data/scenes/two_layers.toml`` with its friction, upper
stiffness, shear and base states replaced) and its dense pencil (:func:`dense_pencil`); the
Z-family of repeated eigenvalues (:func:`z_family`); a mode-coupling pencil whose real
eigenvalues merge into a complex pair (:func:`mode_coupling`); the static slip LCP of the
two-layer lattice (:func:`slip_lcp`).

References, independent of meicp's solvers: :func:`all_eicp_solutions` and
:func:`all_lcp_solutions` try every support with ``scipy.linalg.eig`` /
``numpy.linalg.solve`` — exponential, for the small problems here only.
"""

from __future__ import annotations

import itertools
import tomllib

import numpy as np
import scipy.linalg as sla

from ..api import assemble
from ..contact import pencil
from ..contact.static import prescribed_displacements
from ..lattice.model import LatticeModel
from . import two_layer_scene

#: μ_c of two_layers.toml with every base node slip+ (data/scenes/README.md's value;
#: bench_failure.py recomputes it by bisection on :func:`all_eicp_solutions`)
MU_C = 1.90603249


# ----------------------------------------------------------------------------- problems

def two_layers(mu=3.0, kB=5.0, shear=0.0, states='"slip+"'):
    """data/scenes/two_layers.toml (nx = 5, 2 + 2 rows, top held, load, eps_tol = 1e-10) with
    its friction μ, upper stiffness k_B, shear and base states (a TOML value) replaced."""
    return two_layer_scene(5, (2, 2), mu=mu, stiffness=(1.0, kB), shear=shear,
                           states=tomllib.loads(f"states = {states}")["states"], load=(0.06, -0.1),
                           petsc={"eps_tol": 1e-10}, title="two layers on a rough base")


def dense_pencil(scene):
    """(A, B, J) of the scene's contact states, dense: A = −PKQ, B = PMQ."""
    pen = pencil(scene)
    return pen.A.toarray(), pen.B.toarray(), pen.J


def z_family(delta, n=8, a=0.5):
    """(A, B) with A = −(a(eeᵀ − I) + I + δ·diag(0..n−1)), B = I: at δ = 0 every support of
    one size has the same eigenvalue and every block of size ≥ 2 a repeated one."""
    A = -(a * (np.ones((n, n)) - np.eye(n)) + np.eye(n) + delta * np.diag(np.arange(n, dtype=float)))
    return A, np.eye(n)


def mode_coupling(gamma):
    """A nonsymmetric 8×8 pencil: a 2×2 block [[1.5, γ], [−γ, 0.5]] (real σ 1 ± √(0.25 − γ²),
    complex for γ > 1/2) coupled weakly to a stable part; J = the last three DOFs."""
    n = 8
    rng = np.random.default_rng(7)
    C = rng.uniform(-0.05, 0.05, (n, n))
    C = 0.5 * (C + C.T)
    C[:2, :2] = 0.0
    A = np.diag([1.5, 0.5, -1.0, -1.5, -2.0, -2.5, -3.0, -3.5]) + C
    A[0, 1] += gamma
    A[1, 0] -= gamma
    B = np.diag(np.concatenate([[1.0, 1.0], rng.uniform(0.8, 1.2, n - 2)]))
    return A, B, np.arange(5, 8)


def slip_lcp_data():
    """G_nn, G_nt, c_n of the two_layers lattice: gap and slip of the base nodes per unit
    normal / tangential reaction (condensed compliance), and the gap under the load."""
    sc = two_layers(mu=3.0)
    m = LatticeModel(sc)
    K, _ = assemble(m)
    K = K.toarray()
    presc, up, _ = prescribed_displacements(m, sc.load)
    free = m.free_dofs()
    pos = {int(d): i for i, d in enumerate(free)}
    nodes = m.contact_nodes()
    En = np.zeros((free.size, nodes.size))
    Et = np.zeros_like(En)
    for k, nd in enumerate(nodes):
        En[pos[2 * nd + 1], k] = 1.0
        Et[pos[2 * nd], k] = 1.0
    Kff = K[np.ix_(free, free)]
    sol = np.linalg.solve(Kff, np.hstack([En, Et, -K[np.ix_(free, presc)] @ up[:, None]]))
    nc = nodes.size
    return En.T @ sol[:, :nc], En.T @ sol[:, nc:2 * nc], (En.T @ sol[:, -1])


def slip_lcp(mu, data=None):
    """LCP(q, M) of the static slip problem at friction μ under the compressive load:
    M = G_nn − μ G_nt and q = c_n, each scaled to max |entry| = 1.  ``data``: the
    (G_nn, G_nt, c_n) of ``slip_lcp_data()``, to reuse across μ (computed if None)."""
    Gnn, Gnt, cn = slip_lcp_data() if data is None else data
    M = Gnn - mu * Gnt
    return M / np.abs(M).max(), cn / np.abs(cn).max()


# ----------------------------------------------------------------------------- references

def all_eicp_solutions(A, B, J, lam_min=None):
    """Every MEiCP solution by brute force: each support S ⊆ J, scipy.linalg.eig of the
    reduced pencil on F ∪ S, sign and dual tests.  Returns (list of (λ, support tuple),
    number of complex eigenvalues met with Re ≥ lam_min (or any))."""
    n = A.shape[0]
    J = np.asarray(J, dtype=int)
    F = np.setdiff1d(np.arange(n), J)
    scale = np.abs(A).max()
    sols, ncomplex = [], 0
    for k in range(J.size + 1):
        for S in itertools.combinations(J.tolist(), k):
            R = np.concatenate([F, np.array(S, dtype=int)])
            if R.size == 0:
                continue
            lam, V = sla.eig(A[np.ix_(R, R)], B[np.ix_(R, R)])
            for l, v in zip(lam, V.T):
                if not np.isfinite(l):
                    continue
                if abs(l.imag) > 1e-8 * max(1.0, abs(l)):
                    if lam_min is None or l.real >= lam_min:
                        ncomplex += 1
                    continue
                l = float(l.real)
                if lam_min is not None and l < lam_min - 1e-12:
                    continue
                v = v.real / np.abs(v.real).max()
                if k:
                    if v[F.size:].sum() < 0:
                        v = -v
                    if v[F.size:].min() <= 1e-9:
                        continue
                x = np.zeros(n)
                x[R] = v
                w = l * (B @ x) - A @ x
                out = np.setdiff1d(J, S)
                s = scale + abs(l) * np.abs(B).max()
                if out.size and w[out].min() < -1e-9 * s:
                    continue
                if np.abs(w[R]).max() > 1e-8 * s:
                    continue
                if not any(abs(l - m) <= 1e-9 * max(1, abs(l)) and S == T for m, T in sols):
                    sols.append((l, tuple(S)))
    return sols, ncomplex


def all_lcp_solutions(M, q):
    """Every solution of LCP(q, M) by brute force over the 2^n supports, and the number of
    supports skipped as singular (the sweeps' matrices have none, which bench_failure.py
    checks)."""
    n = q.size
    sols, singular = [], 0
    for k in range(n + 1):
        for S in itertools.combinations(range(n), k):
            S = list(S)
            x = np.zeros(n)
            if k:
                MS = M[np.ix_(S, S)]
                if np.linalg.cond(MS) > 1e12:
                    singular += 1
                    continue
                x[S] = np.linalg.solve(MS, -q[S])
            w = M @ x + q
            if x.min() >= -1e-12 * max(1.0, np.abs(x).max()) and w.min() >= -1e-10 * np.abs(q).max():
                sols.append(np.maximum(x, 0.0))
    return sols, singular
