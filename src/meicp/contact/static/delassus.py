"""The 2-D frictional contact problem on its Delassus operator, the dense contact compliance
``G = Cᵀ K_ff⁻¹ C`` (docs/static-equilibrium.md, "Schur formulation"): find reactions
``r = (r_n (normal set), r_t (friction set))`` with the contact response ``w = G r + c0``
(``w_n`` the gap, ``w_t`` the slip) such that

    w_n ≥ 0,  r_n ≥ 0,  w_n r_n = 0,  |r_t| ≤ μ r_n,  w_t ≠ 0 ⇒ r_t = −sign(w_t) μ r_n.

Order 2|J| instead of the 4|J| of the friction LCP, solved in two stages (as Siconos does for
its frictional contact problems, then made exact):

1. projected nonsmooth Gauss–Seidel (NSGS): each contact's 2×2 problem solved exactly in
   turn, the others' reactions fixed — cheap sweeps that find the states;
2. an exact active-set polish: the equalities of the states (gap = 0 or r_n = 0; slip = 0 or
   r_t = ∓μ r_n) solved by dense LU, the violators moved to the state their violation points
   to (penetration → contact, tension → separated, outside the cone → slip against r_t, slip
   against the friction → stick), repeated until none is left.

A solution is returned as solved only when it passes the certificate (:func:`violation`) at
``tol``.  Pure NumPy; deterministic (contacts swept left to right, no random state).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...core.progress import Ticker

#: per-contact states of the polish: normal (separated, in contact) and tangential
SEP, CONTACT = 0, 1
NONE, STICK, PLUS, MINUS = 0, 1, 2, 3
#: most NSGS sweeps before the polish (the polish, not the sweeps, makes the answer exact)
SWEEPS = 400
#: NSGS stops when the states have not changed for this many sweeps and the reactions moved
#: less than SWEEP_RTOL (relative) in the last one: loose first (the polish corrects a few
#: wrong states at one dense solve each, cheaper than the sweeps' slow tail), tight after a
#: polish that did not certify
SETTLED_SWEEPS = 3
SWEEP_RTOL = (1e-5, 1e-10)
#: most active-set corrections, and most NSGS restarts when the corrections cycle
POLISH_ITERS = 60
RESTARTS = 3


@dataclass
class DelassusSolution:
    """What :func:`solve_delassus` found: ``r``, ``w = G r + c0``, the states (``normal``
    per normal contact: SEP / CONTACT; ``tangent`` per frictional one: NONE / STICK / PLUS /
    MINUS), the work done and the certificate (:func:`violation`, relative).  ``success``
    only when ``certificate ≤ tol``."""

    r: np.ndarray
    w: np.ndarray
    normal: np.ndarray
    tangent: np.ndarray
    success: bool
    certificate: float
    sweeps: int = 0
    polish_iterations: int = 0
    restarts: int = 0
    message: str = ""
    history: list = field(default_factory=list)


def violation(r, w, mu_f, pos, n_normal, *, F: float | None = None, D: float | None = None) -> float:
    """The largest violation of the contact laws by ``(r, w)``, relative: signs of r_n and the
    gap over the force scale F (default max|r|) and displacement scale D (default max|w|;
    give the load's when every contact may be closed and still), the products over
    F·D; Coulomb: the cone ``|r_t| ≤ μ r_n`` over F, and the friction direction — a slip
    ``w_t`` only against ``r_t`` and only on the cone: ``|w_t|·(μ r_n − |r_t|) ≤ ε F D`` and
    ``w_t r_t ≤ ε F D``."""
    rn, rt = r[:n_normal], r[n_normal:]
    gap, slip = w[:n_normal], w[n_normal:]
    F = max(float(np.max(np.abs(r), initial=0.0)) if F is None else F, 1e-300)
    D = max(float(np.max(np.abs(w), initial=0.0)) if D is None else D, 1e-300)
    rnf = rn[pos]
    parts = [np.max(-rn, initial=0.0) / F, np.max(-gap, initial=0.0) / D,
             np.max(np.abs(rn * gap), initial=0.0) / (F * D),
             np.max(np.abs(rt) - mu_f * rnf, initial=0.0) / F,
             np.max(np.abs(slip) * np.maximum(mu_f * rnf - np.abs(rt), 0.0), initial=0.0) / (F * D),
             np.max(slip * rt, initial=0.0) / (F * D)]
    return float(max(parts))


def _local(qn, qt, gaa, gab, gbb, mu):
    """The exact 2×2 frictional problem of one contact (``q`` its response to everything
    else): separated, sticking, or sliding in +x / −x, in that order; the projection of the
    sticking reaction onto the cone if no case fits (only while the sweeps are far off)."""
    if qn >= 0.0:
        return 0.0, 0.0
    det = gaa * gbb - gab * gab
    rn = (gab * qt - gbb * qn) / det
    rt = (gab * qn - gaa * qt) / det
    if rn >= 0.0 and abs(rt) <= mu * rn:
        return rn, rt
    for s in (1.0, -1.0):  # slides in direction s: r_t = −s μ r_n, s·slip ≥ 0
        den = gaa - s * mu * gab
        if den > 0.0:
            rn = -qn / den
            ut = qt + (gab - s * mu * gbb) * rn
            if rn >= 0.0 and s * ut >= 0.0:
                return rn, -s * mu * rn
    rn = max(0.0, -qn / gaa)
    return rn, min(max(-(qt + gab * rn) / gbb, -mu * rn), mu * rn)


def _sweeps(G, c0, r, mu_f, pos, n_normal, max_sweeps, rtol, ticker):
    """NSGS from ``r`` (in place) until the states settle and the reactions move less than
    ``rtol`` (relative); returns ``(w, sweeps)``."""
    w = G @ r + c0
    tang = np.full(n_normal, -1, dtype=np.int64)
    tang[pos] = n_normal + np.arange(pos.size)
    mu_of = np.zeros(n_normal)
    mu_of[pos] = mu_f
    d = np.diag(G).copy()
    states = np.zeros(n_normal, dtype=np.int8)
    settled, done = 0, 0
    for sweep in range(max_sweeps):
        moved = 0.0
        new_states = states.copy()
        for a in range(n_normal):
            b = tang[a]
            if b < 0:
                qn = w[a] - d[a] * r[a]
                rn = max(0.0, -qn / d[a])
                dn = rn - r[a]
                if dn != 0.0:
                    w += dn * G[a]
                    r[a] = rn
                    moved = max(moved, abs(dn))
                new_states[a] = rn > 0.0
                continue
            gab = G[a, b]
            qn = w[a] - d[a] * r[a] - gab * r[b]
            qt = w[b] - gab * r[a] - d[b] * r[b]
            rn, rt = _local(qn, qt, d[a], gab, d[b], mu_of[a])
            dn, dt = rn - r[a], rt - r[b]
            if dn != 0.0 or dt != 0.0:
                w += dn * G[a] + dt * G[b]
                r[a], r[b] = rn, rt
                moved = max(moved, abs(dn), abs(dt))
            new_states[a] = 0 if rn <= 0.0 else (1 if abs(rt) < mu_of[a] * rn else (2 if rt < 0 else 3))
        done = sweep + 1
        settled = settled + 1 if np.array_equal(new_states, states) else 0
        states = new_states
        scale = max(float(np.max(np.abs(r), initial=0.0)), 1e-300)
        ticker.say(lambda: f"NSGS sweep {done}, largest change {moved / scale:.1e} (relative)")
        if settled >= SETTLED_SWEEPS and moved <= rtol * scale:
            break
    return G @ r + c0, done


def _states_of(r, w, mu_f, pos, n_normal):
    """The states a nearly converged ``(r, w)`` points to."""
    rn, rt = r[:n_normal], r[n_normal:]
    F = max(float(np.max(np.abs(r), initial=0.0)), 1e-300)
    normal = np.where(rn > 1e-9 * F, CONTACT, SEP).astype(np.int8)
    tangent = np.full(pos.size, NONE, dtype=np.int8)
    on = normal[pos] == CONTACT
    rnf = rn[pos]
    saturated = np.abs(rt) >= mu_f * rnf * (1 - 1e-9)
    tangent[on] = STICK
    tangent[on & saturated & (rt <= 0)] = PLUS
    tangent[on & saturated & (rt > 0)] = MINUS
    return normal, tangent


def _polish(G, c0, mu_f, pos, n_normal, normal, tangent):
    """The reactions that satisfy the equalities of the states exactly (dense LU on the
    unknowns the states leave free; a sliding contact's r_t = ∓μ r_n is substituted)."""
    m = c0.size
    nF = pos.size
    contact = np.flatnonzero(normal == CONTACT)
    stick = np.flatnonzero(tangent == STICK)
    slide = np.flatnonzero((tangent == PLUS) | (tangent == MINUS))
    unknowns = np.concatenate([contact, n_normal + stick])            # y: r on these
    eqs = unknowns                                                    # w = 0 on the same
    r = np.zeros(m)
    if unknowns.size == 0:
        return r
    col = np.full(m, -1, dtype=np.int64)
    col[unknowns] = np.arange(unknowns.size)
    A = G[np.ix_(eqs, unknowns)]
    if slide.size and nF:
        coef = np.where(tangent[slide] == PLUS, -1.0, 1.0) * mu_f[slide]   # r_t = coef · r_n
        at = col[pos[slide]]                                               # r_n of the contact is y[at]
        A[:, at] += G[np.ix_(eqs, n_normal + slide)] * coef
    y = np.linalg.solve(A, -c0[eqs])
    r[unknowns] = y
    if slide.size and nF:
        r[n_normal + slide] = coef * r[pos[slide]]
    return r


def _correct(r, w, mu_f, pos, n_normal, normal, tangent, eps, D):
    """One active-set correction (``D``: the displacement scale); returns ``(normal, tangent,
    changed)``."""
    rn, rt = r[:n_normal], r[n_normal:]
    gap, slip = w[:n_normal], w[n_normal:]
    F = max(float(np.max(np.abs(r), initial=0.0)), 1e-300)
    n2, t2 = normal.copy(), tangent.copy()
    n2[(normal == CONTACT) & (rn < -eps * F)] = SEP
    n2[(normal == SEP) & (gap < -eps * D)] = CONTACT
    on = n2[pos] == CONTACT
    t2[~on] = NONE
    t2[on & (tangent == NONE)] = STICK
    rnf = rn[pos]
    over = on & (tangent == STICK) & (np.abs(rt) > mu_f * rnf * (1 + eps) + eps * F)
    t2[over & (rt < 0)] = PLUS
    t2[over & (rt >= 0)] = MINUS
    t2[on & (tangent == PLUS) & (slip < -eps * D)] = STICK
    t2[on & (tangent == MINUS) & (slip > eps * D)] = STICK
    changed = bool(np.any(n2 != normal) or np.any(t2 != tangent))
    return n2, t2, changed


def solve_delassus(G: np.ndarray, c0: np.ndarray, mu_f: np.ndarray, pos: np.ndarray, *, tol: float,
                   max_sweeps: int = SWEEPS, what: str = "static equilibrium (schur)") -> DelassusSolution:
    """Solve the frictional contact problem on ``G`` (symmetric positive definite, order
    ``nN + nF``: the normal set then the friction set) with load response ``c0``; ``mu_f``
    and ``pos`` (index of its normal row) per frictional contact.  The reactions are found by
    NSGS and made exact by the active-set polish; ``success`` only with a certificate
    (:func:`violation`) ≤ ``tol``.  Progress lines under ``what``."""
    G = np.ascontiguousarray(G, dtype=float)
    c0 = np.asarray(c0, dtype=float)
    m, nF = c0.size, pos.size
    n_normal = m - nF
    ticker = Ticker(what)
    r = np.zeros(m)
    out = DelassusSolution(r=r, w=c0.copy(), normal=np.zeros(n_normal, np.int8),
                           tangent=np.zeros(nF, np.int8), success=False, certificate=np.inf)
    if m == 0:
        out.success, out.certificate = True, 0.0
        return out
    seen = set()
    best = None
    for restart in range(RESTARTS + 1):
        rtol = SWEEP_RTOL[min(restart, 1)]
        w, sweeps = _sweeps(G, c0, r, mu_f, pos, n_normal, max_sweeps, rtol, ticker)
        out.sweeps += sweeps
        normal, tangent = _states_of(r, w, mu_f, pos, n_normal)
        for _ in range(POLISH_ITERS):
            out.polish_iterations += 1
            key = normal.tobytes() + tangent.tobytes()
            if key in seen:
                break  # a cycle of corrections: more sweeps from the last iterate
            seen.add(key)
            try:
                rp = _polish(G, c0, mu_f, pos, n_normal, normal, tangent)
            except np.linalg.LinAlgError:
                break
            wp = G @ rp + c0
            D = max(float(np.max(np.abs(wp))), float(np.max(np.abs(c0))), 1e-300)
            cert = violation(rp, wp, mu_f, pos, n_normal, D=D)
            out.history.append(cert)
            if best is None or cert < best[0]:
                best = (cert, rp, wp, normal, tangent)
            if cert <= tol:
                break
            normal, tangent, changed = _correct(rp, wp, mu_f, pos, n_normal, normal, tangent, 0.1 * tol, D)
            if not changed:
                break
            ticker.say(lambda: f"active-set polish {out.polish_iterations}, certificate {cert:.1e}")
        if best is not None and best[0] <= tol:
            break
        out.restarts = restart + 1
        if best is not None:
            r[:] = best[1]
        max_sweeps *= 2
    if best is not None:
        out.certificate, out.r, out.w, out.normal, out.tangent = best
    out.restarts = min(out.restarts, RESTARTS)
    out.success = out.certificate <= tol
    out.message = (f"NSGS {out.sweeps} sweeps, active-set polish {out.polish_iterations} solves, "
                   f"certificate {out.certificate:.1e}")
    return out
