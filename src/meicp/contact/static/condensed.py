"""The condensed formulation of the static problem: the dense friction LCP on the contact
unknowns (docs/static-equilibrium.md, "Formulation (condensed, dense)" and "Floating
components"), solved by :func:`meicp.solve_lcp` and classified by :func:`meicp.classify`.
Serial SciPy."""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse.linalg as spla

from ...core import limits
from ...core.errors import ProblemError
from ...core.results import SOLVED
from ...lcp.classes import classify
from ...lcp.problem import LCPResult
from ...lcp.solve import solve_lcp
from .data import StaticData, singular_message
from .result import StaticResult
from .states import settle

#: K_rr counts as singular when the Rayleigh quotient of its inverse-iteration vector is
#: below this times max|K_rr| (a genuinely held lattice of 10⁶ DOFs is around 1e-6)
SINGULAR_RTOL = 1e-12
#: entries of q below this times max|q| are rounding noise and set to 0
Q_NOISE = 1e-12
#: right-hand sides per block when forming G (bounded by memory, see _condense)
RHS_BLOCK_ENTRIES = 2 * 10**7


def solve_condensed(data: StaticData, *, method: str, lcp_tol: float, classify_limit: int,
                    lcp_options: dict, timings: dict, t_start: float) -> StaticResult:
    """Condense onto the contacts, solve the LCP, classify its matrix, read the states."""
    model, cts, free, keep, N = data.model, data.contacts, data.free, data.keep, data.N
    K_ff, b0, u_p = data.K_ff, data.b0, data.u_p
    active, fric = data.active, data.fric
    nc, k = data.n_contacts, data.rigid_modes
    t0 = time.perf_counter()
    if k:
        kn = float(np.abs(K_ff @ N).max()) / max(float(np.abs(K_ff.data).max()), 1e-300)
        if kn > 1e-8:  # the rigid modes must be in the null space of K (a bug otherwise)
            raise RuntimeError(f"rigid modes are not in the null space of K (|K N| = {kn:.1e})")
    free_r = free[keep]
    K_rr = K_ff[keep][:, keep].tocsc()
    lu = _factor(K_rr, model, free_r)
    timings["factor"] += time.perf_counter() - t0

    # ---------------------------------------------------------------- condensation
    t0 = time.perf_counter()
    C_r = data.C_f[keep]
    G = _condense(lu, C_r, free_r.size)
    u0_r = lu.solve(b0[keep]) if lu is not None else np.zeros(0)
    c0 = C_r.T @ u0_r + np.concatenate([data.A_np[active] @ u_p, data.A_tp[fric] @ u_p])
    H = data.H
    e = N.T @ b0
    timings["condense"] = time.perf_counter() - t0

    # ---------------------------------------------------------------- the LCP
    nN, nF = active.size, fric.size
    pos_in_N = np.searchsorted(active, fric)
    sG = float(np.max(np.abs(G))) if G.size and np.max(np.abs(G)) > 0 else 1.0
    Gs = G / sG
    Gnn, Gnt = Gs[:nN, :nN], Gs[:nN, nN:]
    Gtn, Gtt = Gs[nN:, :nN], Gs[nN:, nN:]
    Hn, Ht = H[:nN], H[nN:]
    n_lcp = nN + 3 * nF + 2 * k
    sl = {}
    o = 0
    for name, size in (("r_n", nN), ("beta_plus", nF), ("beta_minus", nF), ("lam", nF),
                       ("alpha_plus", k), ("alpha_minus", k)):
        sl[name] = slice(o, o + size)
        o += size
    Mx = np.zeros((n_lcp, n_lcp))
    q = np.zeros(n_lcp)
    R, P, Mi, L, Ap, Am = (sl[s] for s in ("r_n", "beta_plus", "beta_minus", "lam", "alpha_plus",
                                           "alpha_minus"))
    I_F = np.eye(nF)
    E = np.zeros((nF, nN))
    E[np.arange(nF), pos_in_N] = cts.mu[fric]
    Mx[R, R], Mx[R, P], Mx[R, Mi], Mx[R, Ap], Mx[R, Am] = Gnn, Gnt, -Gnt, Hn, -Hn
    Mx[P, R], Mx[P, P], Mx[P, Mi], Mx[P, L], Mx[P, Ap], Mx[P, Am] = Gtn, Gtt, -Gtt, I_F, Ht, -Ht
    Mx[Mi, R], Mx[Mi, P], Mx[Mi, Mi], Mx[Mi, L], Mx[Mi, Ap], Mx[Mi, Am] = -Gtn, -Gtt, Gtt, I_F, -Ht, Ht
    Mx[L, R], Mx[L, P], Mx[L, Mi] = E, -I_F, -I_F
    Mx[Ap, R], Mx[Ap, P], Mx[Ap, Mi] = -Hn.T, -Ht.T, Ht.T
    Mx[Am, R], Mx[Am, P], Mx[Am, Mi] = Hn.T, Ht.T, -Ht.T
    q[R], q[P], q[Mi] = c0[:nN], c0[nN:], -c0[nN:]
    q[Ap], q[Am] = -sG * e, sG * e
    # rounding noise of the condensation (e.g. 1e-18 slips of a symmetric problem) makes
    # Lemke's degenerate pivots fail on a secondary ray: entries this small are zero
    q[np.abs(q) <= Q_NOISE * float(np.max(np.abs(q), initial=0.0))] = 0.0
    layout = dict(sl, scale=sG, normal=active, friction_set=fric, contacts=list(cts.labels),
                  rigid_modes=k, sets=[(s.name, s.start, s.end) for s in cts.spans])

    t0 = time.perf_counter()
    if n_lcp == 0:
        lcp = LCPResult(method="none", status=SOLVED, x=np.zeros(0), w=np.zeros(0), residual=0.0,
                        message="no contact unknowns: every contact is held by the Dirichlet boundary")
    else:
        lcp = solve_lcp(Mx, q, method=method, tol=lcp_tol, **lcp_options)
        tried = {a[0] for a in lcp.attempts}
        if (method == "auto" and not lcp.success and lcp.status != "infeasible"
                and "lemke" not in tried and n_lcp <= limits.STATIC_LEMKE_LIMIT):
            # auto skips dense pivoting above its DENSE_LIMIT; the friction LCP (zero λ
            # diagonal) often defeats Newton, so pivot anyway: slow (O(n³)) but robust
            first = lcp
            lcp = solve_lcp(Mx, q, method="lemke", tol=lcp_tol, **lcp_options)
            lcp.attempts = list(first.attempts) + [("lemke", lcp.status, lcp.message)]
    timings["lcp"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    classes = classify(Mx, exact_limit=classify_limit) if n_lcp else None
    timings["classify"] = time.perf_counter() - t0

    result = StaticResult(lcp=lcp, lcp_matrix=Mx, lcp_q=q, layout=layout, classes=classes,
                          friction=data.friction(), rigid_modes=k, notes=data.notes,
                          iterations=lcp.iterations, residual=lcp.residual)
    result.guarantees = _guarantees(classes, G[:nN, :nN], data, lcp)
    result.timings = timings
    if not lcp.success:
        result.status = lcp.status
        result.message = (f"the static LCP ({n_lcp} unknowns) was not solved: {lcp.message or lcp.status}; "
                          "no contact states reported")
        result.timings["total"] = time.perf_counter() - t_start
        return result

    # ---------------------------------------------------------------- reconstruction
    t0 = time.perf_counter()
    x = lcp.x
    r_n = np.zeros(nc)
    r_t = np.zeros(nc)
    r_n[active] = x[R] / sG
    r_t[fric] = (x[P] - x[Mi]) / sG
    alpha = x[Ap] - x[Am]
    load_r = b0 + data.C_f @ np.concatenate([r_n[active], r_t[fric]])
    u_f = np.zeros(free.size)
    if lu is not None:
        u_f[keep] = lu.solve(load_r[keep])
    u_f += N @ alpha

    def load_response(contacts):  # at r = 0: u_r = K_rr⁻¹ b0, rigid modes pinned
        if lu is None:
            return np.zeros(contacts.size)
        return data.A_tf[contacts][:, keep] @ u0_r + data.A_tp[contacts] @ u_p

    counts = settle(result, data, u_f, r_n, r_t, load_response, lcp_tol)
    result.message = (f"{nc} contacts ({counts}); LCP "
                      f"{n_lcp} unknowns by {lcp.method}, certificate {lcp.residual:.1e}; equilibrium "
                      f"residual {result.equilibrium_residual:.1e}")
    return result.finish(t0, t_start)



def _factor(K_rr, model, free_r):
    """``splu`` of the SPD ``K_rr`` and a singularity check (inverse iteration)."""
    n = K_rr.shape[0]
    if n == 0:
        return None
    try:
        lu = spla.splu(K_rr.tocsc(), permc_spec="COLAMD")  # measured faster solves than MMD here
    except RuntimeError as exc:  # "Factor is exactly singular"
        raise ProblemError(singular_message(model, None, free_r, f"SuperLU: {exc}")) from None
    rng = np.random.default_rng(20240607)
    x = rng.standard_normal(n)
    rho = np.inf
    for _ in range(3):
        x = lu.solve(x)
        nrm = np.linalg.norm(x)
        if not np.isfinite(nrm) or nrm == 0:
            rho = 0.0
            break
        x /= nrm
        rho = float(x @ (K_rr @ x))
    kmax = float(np.max(np.abs(K_rr.data))) if K_rr.nnz else 1.0
    if not rho > SINGULAR_RTOL * kmax:
        raise ProblemError(singular_message(model, x if np.all(np.isfinite(x)) else None, free_r,
                                             f"smallest-eigenvalue estimate {rho:.2e} ≤ "
                                             f"{SINGULAR_RTOL:g}·max|K| = {SINGULAR_RTOL * kmax:.2e}"))
    return lu


def _condense(lu, C_r, nr):
    """``C_rᵀ K_rr⁻¹ C_r`` (dense), solving in blocks of right-hand sides."""
    m = C_r.shape[1]
    G = np.zeros((m, m))
    if m == 0 or lu is None:
        return G
    C_r = C_r.tocsc()
    step = max(1, min(m, RHS_BLOCK_ENTRIES // max(nr, 1)))
    CT = C_r.T.tocsr()
    for a in range(0, m, step):
        b = min(m, a + step)
        X = lu.solve(C_r[:, a:b].toarray())
        G[:, a:b] = CT @ X
    return 0.5 * (G + G.T)


def _guarantees(classes, Gnn, data: StaticData, lcp) -> list:
    nN, nF, k = data.active.size, data.fric.size, data.rigid_modes
    g = [f"Static LCP ({data.describe_friction()}): {nN} normal reactions, {nF} frictional contacts (β⁺, β⁻, λ each)"
         + (f", {k} rigid-body modes held by contact (α⁺, α⁻ each)" if k else "")
         + f" — {nN + 3 * nF + 2 * k} unknowns."]
    if classes is not None:
        g.extend(f"LCP matrix: {s}" for s in classes.guarantees)
    if nF:
        g.append("The friction split makes the LCP matrix neither P nor R0 by construction (zero λ "
                 "diagonal; λ e_λ solves LCP(0, M)): at a contact with r_n = 0 any λ ≥ |u_t| solves, "
                 "and at a sticking contact β⁺ and β⁻ may grow together.  These change neither the "
                 "reactions (r_n, r_t) nor the displacements, so 'not P' / 'not R0' above do not by "
                 "themselves mean that the equilibrium is non-unique; uniqueness of the reactions at "
                 "this μ is not decided by these classes.")
    if k:
        g.append("Rigid-body modes held by contact add a skew block (α⁺, α⁻ with zero diagonal): "
                 "existence then also needs the contacts to be able to carry the load of each "
                 "floating component (e.g. no uplift of a free block).")
    if nN and k == 0:
        try:
            np.linalg.cholesky(Gnn / max(np.abs(Gnn).max(), 1e-300))
            g.append("Normal compliance G_nn is SPD (Cholesky), hence P: the frictionless problem "
                     "(μ = 0) has exactly one equilibrium for every load.")
        except np.linalg.LinAlgError:
            g.append("Normal compliance G_nn is not numerically positive definite: even the "
                     "frictionless problem may have several equilibria.")
    if lcp.success:
        g.append(f"For this load an equilibrium exists: the LCP solution passed its certificate "
                 f"(residual {lcp.residual:.1e}).")
    else:
        g.append(f"For this load no equilibrium was certified (LCP status {lcp.status!r}).")
    return g

