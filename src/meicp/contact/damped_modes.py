"""Damped divergence modes past the enumeration, followed from the undamped ones
(docs/damping.md, "damped divergence modes at scale").

Light damping moves a divergence mode without changing its support: the undamped verdict of
the same pencil (:func:`~meicp.contact.divergence.driver.window_verdict`, its A and B alone)
finds modes (σ, x, S), and each is followed to the quadratic problem on the same support —
``(λ²B + λD − A)_RR x_R = 0``, ``x = 0`` on ``J ∖ S`` — from ``(√σ, x)`` by residual inverse
iteration (:func:`meicp.petsc.damped_refine.refine_real_pair`).  What it converges to is a
damped divergence mode only when it passes the quadratic MEiCP's certificate on the whole
reduced pencil (λ ≥ 0, x_J ≥ 0, y_J ≥ 0, complementarity, every row within
``tol`` of its scale: :func:`meicp.petsc.damped_refine.quadratic_certificate`).  A way to
find modes, never a proof of absence: when the damping moves the support, or the undamped
pencil has no mode, nothing is found and the verdict stays undecided.
"""

from __future__ import annotations

import logging
import time
from types import SimpleNamespace

import numpy as np

from ..core.comm import mpi_comm
from ..core.matrix import is_petsc_mat
from ..petsc.damped_refine import quadratic_certificate, refine_real_pair
from ..petsc.flutter_quadratic import QuadraticPencilOps
from ..petsc.mat import mat_from_scipy
from ..petsc.pencil import reduced_matrix
from .divergence.driver import window_verdict
from .divergence.modes import mode_of

log = logging.getLogger("meicp")

#: undamped modes followed, the fastest first
FOLLOWED = 3
#: the certificate a followed mode must pass (the quadratic MEiCP's row-wise residual)
CERTIFICATE_TOL = 1e-9


def followed_modes(pen, scene, comm, tol: float, options) -> tuple[list, str]:
    """``(modes, statement)``: the damped divergence modes followed from the undamped modes of
    ``pen`` (module docstring), each a certified :class:`~meicp.contact.result.Mode` with
    σ = λ², and one sentence on what was done.  Collective."""
    t0 = time.perf_counter()
    undamped = window_verdict(pen, scene, comm, 0.0, tol, options)
    solutions = sorted(getattr(undamped.eicp, "solutions", None) or [], key=lambda s: -s.lam)[:FOLLOWED]
    solutions = [s for s in solutions if s.lam >= 0]
    if not solutions:
        return [], (f"the undamped pencil has no divergence mode to follow ({_clip(undamped.evidence)}), "
                    f"{time.perf_counter() - t0:.1f} s")
    red = pen.maps
    J = np.asarray(red.J, dtype=np.int64)
    C = pen.lattice.damping_in_layout()
    D = None
    matrices = []
    try:
        D = reduced_matrix(C, red.P, red.Q, red.retained)
        A, B = pen.A, pen.B
        if not is_petsc_mat(A):  # a serial SciPy pencil: PETSc Mats of its own
            A, B, D = matrices = [mat_from_scipy(mpi_comm(comm), M) for M in (A, B, D)]
        modes, notes = [], []
        with QuadraticPencilOps(A, B, D) as ops:
            for sol in solutions:
                out = np.setdiff1d(J, np.asarray(sol.support, dtype=np.int64))
                lam, x, info = refine_real_pair(ops, float(np.sqrt(sol.lam)), np.asarray(sol.x, dtype=float), out)
                if not info["converged"]:
                    notes.append(f"σ = {sol.lam:.6g}: {info['why']}")
                    continue
                res, parts, support = quadratic_certificate(ops, lam, x, J)
                worst = max(parts, key=parts.get)
                if lam < 0 or res > CERTIFICATE_TOL:
                    why = "λ < 0" if lam < 0 else f"{worst} {parts[worst]:.1e} > {CERTIFICATE_TOL:g}"
                    notes.append(f"σ = {sol.lam:.6g} → λ = {lam:.8g} on its support, not a mode ({why})")
                    continue
                modes.append(mode_of(SimpleNamespace(lam=lam * lam, x=x, support=support, residual=res), red))
                notes.append(f"σ = {sol.lam:.6g} → λ = {lam:.8g} in {info['iterations']} steps, certified "
                             f"(residual {res:.1e})")
    finally:
        for M in (C, D, *matrices):
            if is_petsc_mat(M) and M not in (pen.A, pen.B):
                M.destroy()
    statement = (f"{len(solutions)} undamped mode(s) followed to the damped problem on their supports "
                 f"(residual inverse iteration): {'; '.join(notes)}; {time.perf_counter() - t0:.1f} s")
    log.info("damped divergence: %s", statement)
    modes.sort(key=lambda m: -m.sigma)
    return modes, statement


def _clip(text: str, length: int = 300) -> str:
    return text if len(text) <= length else text[:length] + " …"


__all__ = ["followed_modes"]
