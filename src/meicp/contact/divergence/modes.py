"""The certified divergence modes of an EiCP result, in natural numbering."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...core.matrix import max_abs_entry
from ...eicp.problem import lam_floor
from ..result import Mode


@dataclass(frozen=True)
class FoundModes:
    """listed: the certified modes with σ ≥ lam_min; found: every one with σ ≥ 0 (within
    rounding); note: what the evidence adds about those not listed ("" when none)."""

    listed: list
    found: list
    note: str


def certified_modes(eicp, pen, lam_min: float) -> FoundModes:
    """The certified modes with σ ≥ lam_min, every one with σ ≥ 0, and a note on those left out."""
    red = pen.maps
    # a σ below 0 (even by 5e-11 just below μ_c) is not a divergence mode, but an exact σ = 0
    # (a block free to slide as a whole) computed a few ulps below it is (eicp.problem.lam_floor)
    scales = (max_abs_entry(pen.A), max_abs_entry(pen.B))
    found = [mode_of(sol, red) for sol in eicp.solutions if sol.lam >= lam_floor(0.0, scales)]
    modes = [m for m in found if lam_min == 0 or m.sigma >= lam_floor(lam_min, scales)]
    left_out = (f"; {len(found) - len(modes)} with 0 ≤ σ < lam_min = {lam_min:g} not listed"
                if len(modes) < len(found) else "")
    if any(m.sigma < 0 for m in found):
        left_out += (f"; σ = {min(m.sigma for m in found):.2g} is 0 within rounding "
                     f"(≥ {lam_floor(0.0, scales):.2g}): an exact σ = 0 mode")
    return FoundModes(modes, found, left_out)


def mode_of(sol, red) -> Mode:
    """The :class:`Mode` of one EiCP solution: its shape lifted to natural numbering (unit
    norm) and its support as contact node indices, per contact line."""
    u = red.Q @ sol.x
    nrm = np.linalg.norm(u)
    u = u / nrm if nrm > 0 else u
    base_support, interface_support = [], {}
    for j in sol.support:
        name, idx, _ = red.pair_of[int(np.flatnonzero(red.J == j)[0])]
        if name == "base":
            base_support.append(idx)
        else:
            interface_support.setdefault(name, []).append(idx)
    return Mode(float(sol.lam), u, np.unique(np.array(base_support, dtype=np.int64)), float(sol.residual),
                {k: np.unique(v) for k, v in interface_support.items()})
