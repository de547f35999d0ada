"""The mixed formulation of the static problem: displacements and contact unknowns together
in one sparse complementarity system, solved by PETSc SNES VI and certified after an exact
polish (docs/static-equilibrium.md, "Mixed formulation").  Distributed over ``comm``."""

from __future__ import annotations

import logging
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ...core.comm import mpi_comm
from ...petsc.lcp import lu_solve, snes_vi_affine
from ...petsc.options import STATIC, STATIC_POLISH
from .data import StaticData
from .result import StaticResult
from .states import settle

log = logging.getLogger("meicp")

#: relative diagonal regularisation of the β± and λ rows in the SNES VI stage of the mixed
#: formulation (removed again by the certified polish)
MIXED_REG = 1e-8
#: relative threshold that reads contact states from the (regularised) SNES iterate
MIXED_ID_TOL = 1e-6
#: most active-set corrections of the polish
MIXED_POLISH_ITERS = 40
#: certificate tolerance of the mixed formulation (complementarity and equilibrium)
MIXED_CERT_TOL = 1e-9
#: options prefix of the mixed formulation's SNES VI
MIXED_PREFIX = STATIC

# per-contact states of the polish
_SEP, _STICK, _PLUS, _MINUS, _CONTACT = 0, 1, 2, 3, 4



class MixedSystem:
    """The sparse mixed LCP in scaled variables: z = (u_f, ρ_n, ρ⁺, ρ⁻, λ), forces r = s_K·ρ."""

    def __init__(self, data: StaticData):
        K_ff, b0, u_p, active, fric = data.K_ff, data.b0, data.u_p, data.active, data.fric
        A_nf, A_tf, A_np, A_tp = data.A_nf, data.A_tf, data.A_np, data.A_tp
        self.nf = K_ff.shape[0]
        self.nN, self.nF = active.size, fric.size
        self.sK = float(np.max(np.abs(K_ff.data))) if K_ff.nnz else 1.0
        self.Cn = A_nf[active].tocsr()                        # nN × nf
        self.Ct = A_tf[fric].tocsr()                          # nF × nf
        self.gn0 = A_np[active] @ u_p                         # gap at u_f = 0
        self.gt0 = A_tp[fric] @ u_p                           # slip at u_f = 0
        self.K = (K_ff / self.sK).tocsr()
        self.b = b0 / self.sK
        self.b0 = b0
        self.K_ff = K_ff
        self.mu_f = data.contacts.mu[fric]
        self.pos = np.searchsorted(active, fric)              # friction contact → its normal row
        E = sp.csr_matrix((self.mu_f, (np.arange(self.nF), self.pos)), shape=(self.nF, self.nN))
        self.E = E
        nf, nN, nF = self.nf, self.nN, self.nF
        o = np.cumsum([0, nf, nN, nF, nF, nF])
        self.sl = {k: slice(o[i], o[i + 1]) for i, k in enumerate(("u", "n", "p", "m", "l"))}
        self.n = int(o[-1])
        I = sp.identity(nF, format="csr")
        if nF:
            self.J0 = sp.bmat([
                [self.K, -self.Cn.T, -self.Ct.T, self.Ct.T, None],
                [self.Cn, None, None, None, None],
                [self.Ct, None, None, None, I],
                [-self.Ct, None, None, None, I],
                [None, E, -I, -I, None]], format="csr")
        elif nN:
            self.J0 = sp.bmat([[self.K, -self.Cn.T], [self.Cn, None]], format="csr")
        else:
            self.J0 = self.K.copy()
        self.J0 = sp.csr_matrix(self.J0, shape=(self.n, self.n))
        self.q = np.concatenate([-self.b, self.gn0, self.gt0, -self.gt0, np.zeros(nF)])
        self.lower = np.concatenate([np.full(nf, -np.inf), np.zeros(nN + 3 * nF)])
        self.upper = np.full(self.n, np.inf)

    def regularised(self, eps):
        d = np.zeros(self.n)
        d[self.nf + self.nN:] = eps
        return (self.J0 + sp.diags(d)).tocsr()

    def split(self, z):
        s = self.sl
        return z[s["u"]], z[s["n"]], z[s["p"]], z[s["m"]], z[s["l"]]

    def scales(self, z):
        u, rn, rp, rm, lam = self.split(z)
        F = max(float(np.max(np.abs(z[self.nf:self.nf + self.nN + 2 * self.nF]), initial=0.0)),
                float(np.max(np.abs(self.b), initial=0.0)))
        D = max(float(np.max(np.abs(u), initial=0.0)), float(np.max(np.abs(self.gn0), initial=0.0)),
                float(np.max(np.abs(self.gt0), initial=0.0)), float(np.max(np.abs(lam), initial=0.0)))
        return F, D

    def certificate(self, z):
        """``(complementarity residual, equilibrium residual)``, both relative: per pair
        (r_n ⊥ gap, β± ⊥ λ ± slip, λ ⊥ μ r_n − β⁺ − β⁻) the bound violations of each side and
        the product, over the force scale F, the displacement scale D and F·D; the
        equilibrium ``‖K_ff u_f − b0 − C r‖∞ / F`` — all from the unregularised sparse data."""
        w = self.J0 @ z + self.q
        F, D = self.scales(z)
        F, D = max(F, 1e-300), max(D, 1e-300)
        nf, nN, nF = self.nf, self.nN, self.nF
        x, wc = z[nf:], w[nf:]
        is_force = np.concatenate([np.ones(nN + 2 * nF, bool), np.zeros(nF, bool)])
        xs = np.where(is_force, F, D)       # scale of the variable
        ws = np.where(is_force, D, F)       # scale of its complementary function
        comp = 0.0
        if x.size:
            comp = max(float(np.max(-x / xs, initial=0.0)), float(np.max(-wc / ws, initial=0.0)),
                       float(np.max(np.abs(x * wc) / (F * D), initial=0.0)))
        eq = float(np.max(np.abs(w[:nf]), initial=0.0)) / F
        return comp, eq

    def identify(self, z):
        """States read from an iterate (tolerant: MIXED_ID_TOL)."""
        u, rn, rp, rm, lam = self.split(z)
        F, D = self.scales(z)
        t = MIXED_ID_TOL
        sn = np.where(rn > t * F, _CONTACT, _SEP)
        st = np.full(self.nF, _SEP)
        rt = rp - rm
        rnf = rn[self.pos]
        slip = self.Ct @ u + self.gt0
        incontact = sn[self.pos] == _CONTACT
        sat = np.abs(rt) >= self.mu_f * rnf * (1 - t)
        moving = lam > t * D
        d = np.where(rt != 0, -np.sign(rt), np.sign(slip))
        st[incontact] = _STICK
        sl = incontact & (sat | moving)
        st[sl & (d >= 0)] = _PLUS
        st[sl & (d < 0)] = _MINUS
        return sn, st

    def polish(self, sn, st, comm):
        """Exact solve of the equalities of the given states in (u_f, ρ_n, ρ_t), then
        (β⁺, β⁻, λ) from ρ_t and the slip.  Returns z or None (singular)."""
        nf, nN, nF = self.nf, self.nN, self.nF
        con = (sn == _CONTACT).astype(float)
        sep_f = (st == _SEP).astype(float)
        stk = (st == _STICK).astype(float)
        sgn = np.where(st == _PLUS, 1.0, np.where(st == _MINUS, -1.0, 0.0))
        slp = np.abs(sgn)
        # normal rows: contact → gap = 0; separated → ρ_n = 0
        Rn_u = sp.diags(con) @ self.Cn
        Rn_n = sp.diags(1.0 - con)
        rhs_n = -con * self.gn0
        # tangential rows: stick → slip = 0; slip s → ρ_t + s μ ρ_n = 0; separated → ρ_t = 0
        Rt_u = sp.diags(stk) @ self.Ct
        Rt_n = sp.diags(sgn) @ self.E
        Rt_t = sp.diags(slp + sep_f)
        rhs_t = -stk * self.gt0
        blocks = [[self.K, -self.Cn.T, -self.Ct.T], [Rn_u, Rn_n, None], [Rt_u, Rt_n, Rt_t]]
        if nF == 0:
            blocks = [[self.K, -self.Cn.T], [Rn_u, Rn_n]]
        A = sp.bmat(blocks, format="csr")
        rhs = np.concatenate([self.b, rhs_n, rhs_t]) if nF else np.concatenate([self.b, rhs_n])
        sol, ok = lu_solve(A, rhs, comm=comm, prefix=STATIC_POLISH,
                           options={"mat_mumps_icntl_14": 400})
        if not ok:
            return None
        u, rn = sol[:nf], sol[nf:nf + nN]
        rt = sol[nf + nN:] if nF else np.zeros(0)
        slip = self.Ct @ u + self.gt0
        lam = np.where(slp > 0, sgn * slip, np.where(sep_f > 0, np.abs(slip), 0.0))
        return np.concatenate([u, rn, np.maximum(rt, 0.0), np.maximum(-rt, 0.0), lam])

    def correct(self, z, sn, st):
        """One primal-dual active-set correction of the states from a polished z; returns
        ``(sn, st, changed)``."""
        u, rn, rp, rm, lam = self.split(z)
        F, D = self.scales(z)
        t = MIXED_CERT_TOL
        gap = self.Cn @ u + self.gn0
        slip = self.Ct @ u + self.gt0
        rt = rp - rm
        sn2, st2 = sn.copy(), st.copy()
        sn2[(sn == _SEP) & (gap < -t * D)] = _CONTACT
        sn2[(sn == _CONTACT) & (rn < -t * F)] = _SEP
        con_f = sn2[self.pos] == _CONTACT
        st2[~con_f] = _SEP
        newly = con_f & (st == _SEP)
        st2[newly] = _STICK
        rnf = rn[self.pos]
        over = (st == _STICK) & con_f & (np.abs(rt) > self.mu_f * rnf * (1 + t) + t * F)
        st2[over & (rt < 0)] = _PLUS
        st2[over & (rt >= 0)] = _MINUS
        sgn = np.where(st == _PLUS, 1.0, np.where(st == _MINUS, -1.0, 0.0))
        back = (sgn != 0) & con_f & (sgn * slip < -t * D)
        st2[back] = _STICK
        changed = bool(np.any(sn2 != sn) or np.any(st2 != st))
        return sn2, st2, changed



def _solve(system: MixedSystem, pcomm, petsc_options) -> tuple:
    """SNES VI on the regularised mixed LCP, then the certified polish.  Returns
    ``(z or None, info dict)``."""
    info = {"attempts": []}
    J = system.regularised(MIXED_REG)
    best = None
    types = ("vinewtonrsls", "vinewtonssls")
    if petsc_options and "snes_type" in petsc_options:
        types = types[:1]  # the caller's choice overrides both defaults: one attempt
    for snes_type in types:
        t0 = time.perf_counter()
        z, its, reason, sec, snes_type = snes_vi_affine(
            J, system.q, system.lower, system.upper, comm=pcomm, prefix=MIXED_PREFIX,
            defaults={"snes_type": snes_type, "snes_rtol": 1e-12, "snes_max_it": 100,
                      # delayed pivots of the saddle-point systems overflow MUMPS' default workspace
                      "mat_mumps_icntl_14": 400},
            options=petsc_options)
        attempt = {"snes_type": snes_type, "iterations": its, "reason": reason,
                   "seconds": time.perf_counter() - t0}
        info["attempts"].append(attempt)
        if not np.all(np.isfinite(z)):
            continue
        sn, st = system.identify(z)
        zp = None
        for k in range(MIXED_POLISH_ITERS):
            zp = system.polish(sn, st, pcomm)
            if zp is None:
                break
            comp, eq = system.certificate(zp)
            if comp <= MIXED_CERT_TOL and eq <= MIXED_CERT_TOL:
                attempt.update(polish_iterations=k + 1, certificate=(comp, eq))
                info.update(attempt)
                return zp, info
            sn, st, changed = system.correct(zp, sn, st)
            if not changed:
                break
        if zp is not None:
            cert = system.certificate(zp)
            attempt["certificate"] = cert
            if best is None or max(cert) < max(best[1]):
                best = (zp, cert)
    info["best_certificate"] = best[1] if best else None
    return None, info


def solve_mixed(static: StaticData, *, comm, petsc_options: dict | None, timings: dict,
                t_start: float) -> StaticResult:
    """Solve the mixed system (SNES VI on ``comm``, distributed when it has several ranks),
    polish and certify it, read the states."""
    cts, active, fric, keep = static.contacts, static.active, static.fric, static.keep
    nc, k = static.n_contacts, static.rigid_modes
    t0 = time.perf_counter()
    system = MixedSystem(static)
    timings["assemble_mixed"] = time.perf_counter() - t0
    notes = list(static.notes) + [
        "formulation = mixed: the LCP matrix is not classified (the mixed matrix, displacements and "
        "reactions together, is not the contact operator: its classes say nothing about the "
        "contact problem; the condensed formulation classifies it)"]
    # the first SNES iteration holds the factorisation: at 10⁶ DOFs 20 s before its progress line
    log.info("static equilibrium: mixed LCP of %s unknowns (%d normal reactions, %d frictional contacts) "
             "assembled in %.1f s; SNES VI on it", f"{system.n:,}", system.nN, system.nF,
             timings["assemble_mixed"])
    t0 = time.perf_counter()
    z, info = _solve(system, mpi_comm(comm), petsc_options) if system.n else (np.zeros(0), {"attempts": []})
    timings["lcp"] = time.perf_counter() - t0
    n_lcp = system.nN + 3 * system.nF
    lay = {"formulation": "mixed", "unknowns": system.n, "normal": active, "friction_set": fric,
           "contacts": list(cts.labels), "rigid_modes": k, "sets": [(s.name, s.start, s.end) for s in cts.spans],
           "scale": 1.0 / system.sK, "attempts": info.get("attempts", [])}
    reason = "; ".join(f"{a['snes_type']}: {a['reason']} after {a['iterations']} iterations"
                       for a in info.get("attempts", []))
    result = StaticResult(layout=lay, friction=static.friction(), rigid_modes=k, notes=notes)
    result.timings = timings
    result.guarantees = [f"Static mixed LCP ({static.describe_friction()}): {system.nf} displacement "
                         f"unknowns, {system.nN} normal reactions, {system.nF} frictional contacts (β⁺, β⁻, "
                         f"λ each) — {system.n} unknowns; matrix classes not computed (mixed formulation)."]
    if z is None:
        result.status = "failed"
        best = info.get("best_certificate")
        result.message = (f"the static mixed LCP ({system.n} unknowns) was not solved: SNES VI {reason}; "
                          + (f"best polished certificate (complementarity, equilibrium) = "
                             f"({best[0]:.1e}, {best[1]:.1e}) > {MIXED_CERT_TOL:g}" if best else
                             "no iterate could be polished")
                          + "; no contact states reported")
        result.guarantees.append("For this load no equilibrium was certified.")
        timings["total"] = time.perf_counter() - t_start
        return result
    t0 = time.perf_counter()
    comp, eq = system.certificate(z) if system.n else (0.0, 0.0)
    u_f, rn_s, rp, rm, lam = system.split(z) if system.n else (np.zeros(0),) * 5
    r_n = np.zeros(nc)
    r_t = np.zeros(nc)
    r_n[active] = rn_s * system.sK
    r_t[fric] = (rp - rm) * system.sK

    def load_response(contacts):
        # at r = 0, one solve with the rigid modes pinned as in the condensed formulation
        K_rr = static.K_ff[keep][:, keep].tocsc()
        if not K_rr.shape[0]:
            return np.zeros(contacts.size)
        u0_r = spla.spsolve(K_rr, static.b0[keep])
        return static.A_tf[contacts][:, keep] @ u0_r + static.A_tp[contacts] @ static.u_p

    counts = settle(result, static, u_f, r_n, r_t, load_response, MIXED_CERT_TOL)
    result.residual = comp
    result.iterations = int(info.get("iterations", 0))
    result.guarantees.append(f"For this load an equilibrium exists: the mixed LCP solution passed its "
                             f"certificate (complementarity {comp:.1e}, equilibrium {eq:.1e}).")
    how = (f"SNES {info.get('snes_type')} ({info.get('reason')}, {info.get('iterations')} it) + "
           f"{info.get('polish_iterations')} polish" if info.get("attempts") else "no unknowns")
    result.message = (f"{nc} contacts ({counts}); mixed LCP "
                      f"{system.n} unknowns ({n_lcp} contact) by {how}, certificate {comp:.1e}; "
                      f"equilibrium residual {result.equilibrium_residual:.1e}")
    return result.finish(t0, t_start)

