"""The contact states read from a static solution (docs/static-equilibrium.md,
"Classification tolerances"): every contact's gap, slip and reactions, the held contacts'
forces, and ``stick`` / ``slip+`` / ``slip-`` / ``separated`` / ``grazing``."""

from __future__ import annotations

import numpy as np

from ...core.errors import ProblemError
from ...core.results import SOLVED
from ...scene import STATES
from ..lines import BASE
from .data import StaticData


def settle(result, data: StaticData, u_f, r_n, r_t, load_response, certificate_tol: float) -> str:
    """Store in ``result`` what a certified solution (free displacements ``u_f``, reactions
    ``r_n``, ``r_t`` per contact) means: the displacement, each contact's gap, slip and state,
    the equilibrium residual, the tolerances used; ``status`` becomes solved.
    ``load_response(contacts)``: the tangential response of those (frictionless) contacts to
    the load with every reaction zero, asked only when one of them has not moved (the
    direction rule of μ = 0).  Returns the state counts, e.g. ``"3 slip+, 2 stick"``."""
    cts, tol = data.contacts, data.tol
    u, gap, slip, F, D = _response(data, u_f, r_n, r_t)
    load_r = data.b0 + data.C_f @ np.concatenate([r_n[data.active], r_t[data.fric]])
    res = data.K_ff @ u_f - load_r
    result.equilibrium_residual = float(np.max(np.abs(res))) / F if res.size and F > 0 else 0.0
    _held_contacts(cts, gap, slip, r_n, r_t, data.held_n, data.held_t, tol, D)
    c0_t = np.zeros(data.n_contacts)
    zero_mu = np.flatnonzero(~data.held_n & ~data.held_t & (cts.mu == 0))
    if zero_mu.size and np.any(np.abs(slip[zero_mu]) <= tol * D):
        c0_t[zero_mu] = load_response(zero_mu)
    states = _classify_states(r_n, r_t, gap, slip, cts.mu, data.held_n, data.held_t, c0_t, tol, F, D,
                              result.notes, cts.labels)
    _store_contacts(result, cts, states, (r_n, r_t, gap, slip, data.held_n), u, tol, F, D, certificate_tol)
    result.status = SOLVED
    return ", ".join(f"{states.count(s)} {s}" for s in STATES if s in states)


def _response(data: StaticData, u_f, r_n, r_t):
    """The full displacement, each contact's gap and slip, and the force and displacement
    scales the classification tolerances are relative to."""
    u = np.zeros(data.model.n_dofs)
    u[data.free] = u_f
    u[data.presc] = data.u_p
    F = max(float(np.max(np.abs(np.concatenate([r_n, r_t])))) if r_n.size else 0.0,
            float(np.max(np.abs(data.b0))) if data.b0.size else 0.0)
    D = float(np.max(np.abs(u))) if u.size else 0.0
    return u, data.contacts.A_n @ u, data.contacts.A_t @ u, F, D


def _held_contacts(cts, gap, slip, r_n, r_t, held_n, held_t, tol, D) -> None:
    """Contacts the Dirichlet boundary holds: a prescribed penetration is an error; on a
    tangentially prescribed contact friction acts on prescribed DOFs only, so r_t (in place)
    is ∓μ r_n when it moves and 0 when it does not."""
    for c in np.flatnonzero(held_n):
        if gap[c] < -tol * D:
            name, i = cts.labels[c]
            raise ProblemError(f"static equilibrium: the prescribed displacements close contact "
                               f"{name!r} column {i} by {-gap[c]:g} (penetration): the load moves "
                               "both sides of a contact held by the Dirichlet boundary into each other")
    tang_held = np.flatnonzero(~held_n & held_t & (cts.mu > 0))
    moving = np.abs(slip[tang_held]) > tol * D
    r_t[tang_held] = np.where(moving, -np.sign(slip[tang_held]) * cts.mu[tang_held] * r_n[tang_held], 0.0)


def _store_contacts(result, cts, states, per_contact, u, tol, F, D, certificate_tol) -> None:
    """Put the classified states, the per-contact arrays (r_n, r_t, gap, slip, held) and the
    tolerances used into ``result``, split into the base and each frictional interface."""
    r_n, r_t, gap, slip, held_n = per_contact
    result.tolerances = {"tol": tol, "force_scale": F, "displacement_scale": D,
                         "contact_force": tol * F, "gap": tol * D, "slip": tol * D,
                         "cone": f"|r_t| >= mu*r_n*(1 - {tol:g}) - {tol * F:.3g}",
                         "lcp_certificate": certificate_tol}
    result.u = u
    for span in cts.spans:
        name, a, b = span.name, span.start, span.end
        if name == BASE:
            result.states = states[a:b]
            result.r_n, result.r_t, result.gap, result.slip = r_n[a:b], r_t[a:b], gap[a:b], slip[a:b]
            result.held = held_n[a:b].copy()
        else:
            result.interface_states[name] = states[a:b]
            result.interface_r_n[name], result.interface_r_t[name] = r_n[a:b], r_t[a:b]
            result.interface_gap[name], result.interface_slip[name] = gap[a:b], slip[a:b]
            result.interface_held[name] = held_n[a:b].copy()


def _classify_states(r_n, r_t, gap, slip, mu, held_n, held_t, c0_t, tol, F, D, notes, labels) -> list:
    out = []
    f_tol, d_tol = tol * F, tol * D
    for c in range(r_n.size):
        if held_n[c]:
            out.append("stick" if held_t[c] else "separated")
            continue
        if r_n[c] > f_tol:
            moving = abs(slip[c]) > d_tol
            if held_t[c]:  # the boundary prescribes the slip: forced slip, or held (stick)
                out.append(("slip+" if slip[c] > 0 else "slip-") if moving else "stick")
                continue
            if mu[c] == 0.0:
                if moving:
                    s = np.sign(slip[c])
                elif abs(c0_t[c]) > d_tol:
                    s = np.sign(c0_t[c])
                else:
                    s = 1.0
                out.append("slip+" if s > 0 else "slip-")
                continue
            saturated = abs(r_t[c]) >= mu[c] * r_n[c] * (1.0 - tol) - f_tol
            if saturated or moving:
                s = -np.sign(r_t[c]) if r_t[c] != 0 else np.sign(slip[c])
                if s == 0:
                    s = 1.0
                if moving and np.sign(slip[c]) != s:
                    notes.append(f"{labels[c]}: slip {slip[c]:.3g} against the friction direction "
                                 f"(r_t = {r_t[c]:.3g}) within tolerance")
                if moving and not saturated:
                    notes.append(f"{labels[c]}: slip {slip[c]:.3g} inside the cone "
                                 f"(|r_t| = {abs(r_t[c]):.3g} < μ r_n = {mu[c] * r_n[c]:.3g}) within tolerance")
                out.append("slip+" if s > 0 else "slip-")
            else:
                out.append("stick")
        else:
            out.append("separated" if gap[c] > d_tol else "grazing")
    return out

