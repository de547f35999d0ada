"""Damped divergence modes past the enumeration, followed from the undamped ones
(docs/damping.md, "damped divergence modes at scale").

Light damping moves a divergence mode without changing its support: the first steps of the
undamped verdict of the same pencil (its A and B alone; :mod:`~meicp.contact.divergence.driver`
steps 1–2: the Lanczos estimate of the window's top, then, when it is above 0, the short
active-set search from the proxy's estimate or the top, :func:`~.divergence.search.first_search`) find modes (σ, x, S), and each is followed to the quadratic problem on the same support —
``(λ²B + λD − A)_RR x_R = 0``, ``x = 0`` on ``J ∖ S`` — from ``(√σ, x)`` by residual inverse
iteration (:func:`meicp.petsc.damped_refine.refine_real_pair`).  What it converges to is a
damped divergence mode only when it passes the quadratic MEiCP's certificate on the whole
reduced pencil (λ ≥ 0, x_J ≥ 0, y_J ≥ 0, complementarity, every row within
``tol`` of its scale: :func:`meicp.petsc.damped_refine.quadratic_certificate`).  A way to
find modes, never a proof of absence: when the damping moves the support, or the short
search finds no undamped mode, nothing is found and the verdict stays undecided.  The
undamped verdict's proofs and its whole search are not run: they would cost condensations
and prove nothing about the damped problem.
"""

from __future__ import annotations

import logging
import time
from types import SimpleNamespace

import numpy as np

from ..core.comm import mpi_comm
from ..petsc.damped_refine import quadratic_certificate, refine_real_pair
from ..petsc.mumps_c import MumpsError
from ..petsc.flutter_quadratic import QuadraticPencilOps
from ..petsc.mat import distributed
from .divergence.modes import mode_of
from .divergence.search import first_search, search_settings
from .divergence.sigma_window import probe_top, ritz_estimate

log = logging.getLogger("meicp")

#: undamped modes followed, the fastest first
FOLLOWED = 3
#: the certificate a followed mode must pass (the quadratic MEiCP's row-wise residual): 10×
#: the dense enumeration's 1e-10, as the undamped critical friction's lifted mode (1e-9) — at
#: 10⁶ DOFs the followed mode's rows land at 2.2e-10 (docs/benchmarks.md, "Damping at scale")
CERTIFICATE_TOL = 1e-9
#: two followed modes whose σ agree to this relative tolerance are one (two undamped modes can
#: lead to the same damped one)
SAME = 1e-8


def followed_modes(pen, scene, comm, tol: float, options) -> tuple[list, str]:
    """``(modes, statement)``: the damped divergence modes followed from the undamped modes of
    ``pen`` (module docstring), each a certified :class:`~meicp.contact.result.Mode` with
    σ = λ², and one sentence on what was done.  Collective."""
    t0 = time.perf_counter()
    solutions, searched = _undamped_modes(pen, scene, comm, tol, options)
    if not solutions:
        return [], f"no undamped divergence mode to follow ({searched}), {time.perf_counter() - t0:.1f} s"
    red = pen.maps
    J = np.asarray(red.J, dtype=np.int64)
    modes, notes = [], []
    # a serial SciPy pencil gets PETSc Mats of its own
    with distributed(mpi_comm(comm), pen.A, pen.B, pen.damping()) as mats, QuadraticPencilOps(*mats) as ops:
        for sol in solutions:
            out = np.setdiff1d(J, np.asarray(sol.support, dtype=np.int64))
            try:
                lam, x, info = refine_real_pair(ops, float(np.sqrt(sol.lam)), np.asarray(sol.x, dtype=float),
                                                out)
            except MumpsError as exc:  # T(√σ) singular on the support: nothing to follow from here
                notes.append(f"σ = {sol.lam:.6g}: {exc}")
                continue
            if not info["converged"]:
                notes.append(f"σ = {sol.lam:.6g}: {info['why']}")
                continue
            mode, why = certified_mode(ops, red, lam, x)
            if mode is None:
                notes.append(f"σ = {sol.lam:.6g} → λ = {lam:.8g} on its support, not a mode ({why})")
                continue
            if any(abs(lam * lam - m.sigma) <= SAME * max(lam * lam, 1e-300) for m in modes):
                notes.append(f"σ = {sol.lam:.6g} → λ = {lam:.8g}, a mode already found")
                continue
            modes.append(mode)
            notes.append(f"σ = {sol.lam:.6g} → λ = {lam:.8g} in {info['iterations']} steps, certified ({why})")
    statement = (f"{len(solutions)} undamped mode(s) followed to the damped problem on their supports "
                 f"(residual inverse iteration): {'; '.join(notes)}; {time.perf_counter() - t0:.1f} s")
    log.info("damped divergence: %s", statement)
    modes.sort(key=lambda m: -m.sigma)
    return modes, statement


def certified_mode(ops: QuadraticPencilOps, red, lam: float, x: np.ndarray):
    """``(mode, why)``: the :class:`~meicp.contact.result.Mode` (σ = λ²) of a real candidate
    ``(λ, x)`` that passes the quadratic MEiCP's certificate on the whole reduced pencil
    (λ ≥ 0, every row within :data:`CERTIFICATE_TOL`), and ``"residual …"``; or ``(None, why
    not)``.  Collective."""
    res, parts, support = quadratic_certificate(ops, lam, x, np.asarray(red.J, dtype=np.int64))
    if lam < 0:
        return None, "λ < 0"
    if res > CERTIFICATE_TOL:
        worst = max(parts, key=parts.get)
        return None, f"{worst} {parts[worst]:.1e} > {CERTIFICATE_TOL:g}"
    return mode_of(SimpleNamespace(lam=lam * lam, x=x, support=support, residual=res), red), f"residual {res:.1e}"


def _undamped_modes(pen, scene, comm, tol: float, options) -> tuple[list, str]:
    """The certified undamped modes (EiCP solutions, σ ≥ 0, the fastest first, at most
    :data:`FOLLOWED`) of the first, short search (from the proxy's estimate or the window's
    top: :func:`~.divergence.search.first_search`), and what was done."""
    started = time.perf_counter()
    top = probe_top(pen.A, pen.B, ritz_estimate)
    if not top.positive:
        return [], (f"the window's top θ = {top.theta:.6g} of (sym A, sym B) is not above 0: the undamped short "
                    "search would start among the slow vibrations, so none was made")
    # the only search of the damped verdict: made even where the proxy has no real σ above 0
    outcome = first_search(search_settings(pen, scene, comm, 0.0, tol, options, top.shift, started), scene,
                           skip=False)
    solutions = sorted((s for s in getattr(outcome.eicp, "solutions", None) or [] if s.lam >= 0),
                       key=lambda s: -s.lam)[:FOLLOWED]
    return solutions, (f"the undamped short search from σ = {outcome.target:.6g} found "
                       f"{len(solutions) or 'no'} mode(s)")


__all__ = ["certified_mode", "followed_modes"]
