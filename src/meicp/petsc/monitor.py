"""Progress lines from inside PETSc's and SLEPc's own iterations.

A SLEPc eigen-solve of a 10⁶-DOF pencil or the static equilibrium's SNES VI runs for minutes
inside one call, where no Python loop can say where it is: the 10⁶-DOF static scene printed
nothing from 13 s to 224 s.  :func:`watch` gives such a solver a monitor that reports through
:class:`meicp.core.progress.Ticker` — one line every few seconds at most, on rank 0, at INFO
(silent under ``-q``): an eigen-solve's Krylov–Schur restarts with its converged pairs and the
best residual estimate of the others, a SNES's iterations with its residual norm.
:meth:`meicp.petsc.options.OptionsScope.configure` calls it for every EPS and SNES it
configures, so every solver under a meicp prefix is watched.  Collective objects call their
monitor on every rank; only rank 0's logger prints.
"""

from __future__ import annotations

import numpy as np

from ..core.progress import Ticker
from . import import_petsc, import_slepc


def watch(obj, prefix: str) -> None:
    """Attach a throttled progress monitor to a SLEPc EPS or a PETSc SNES (other objects are
    left alone).  ``prefix``: the options prefix, which names the solver in the lines."""
    PETSc, SLEPc = import_petsc(), import_slepc()
    if isinstance(obj, SLEPc.EPS):
        obj.setMonitor(_EigenProgress(Ticker(f"SLEPc -{prefix}")))
    elif isinstance(obj, PETSc.SNES):
        obj.setMonitor(_NewtonProgress(Ticker(f"SNES -{prefix}")))


class _EigenProgress:
    """An EPS monitor: ``(eps, its, nconv, eig, err)`` at every restart."""

    def __init__(self, ticker: Ticker):
        self.ticker = ticker

    def __call__(self, eps, its, nconv, eig, err) -> None:
        if not self.ticker.due():
            return
        wanted = eps.getDimensions()[0]
        # the estimates of the pairs still wanted (SLEPc sorts the converged ones first); 0 is
        # "not estimated yet"
        others = np.asarray(err if err is not None else [], dtype=float)[nconv:max(wanted, nconv + 1)]
        others = others[others > 0]
        best = f", best residual estimate of the others {others.min():.1e}" if others.size else ""
        self.ticker.say(f"restart {its}, {nconv} of {wanted} eigenpair(s) converged{best}")


class _NewtonProgress:
    """A SNES monitor: ``(snes, its, fnorm)`` at every iteration."""

    def __init__(self, ticker: Ticker):
        self.ticker = ticker

    def __call__(self, snes, its, fnorm) -> None:
        self.ticker.say(lambda: f"iteration {its}, residual norm {fnorm:.3e}")
