"""What :func:`meicp.analyze` returns (DESIGN §5): divergence modes, stability verdict and
its evidence, contact states, timings."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..core.results import Result


@dataclass
class Mode:
    """One divergence mode: σ = λ² ≥ 0 and its growth rate λ = √σ.

    x: the mode shape in natural DOF numbering (length 2·nx·ny; fixed and sticking DOFs 0,
    relative displacements of frictional interfaces added back to the upper layer),
    normalised ‖x‖₂ = 1.  support: indices of the base's contact nodes (left to right from
    0) whose slip is active; interface_support: the same per frictional interface, keyed by
    the lower layer's name.  residual: the MEiCP certificate of this mode.
    """

    sigma: float
    x: np.ndarray
    support: np.ndarray
    residual: float
    interface_support: dict = field(default_factory=dict)

    @property
    def growth_rate(self) -> float:
        return float(np.sqrt(max(self.sigma, 0.0)))


@dataclass
class InstabilityResult(Result):
    """Result of :func:`meicp.analyze`.

    modes: certified divergence modes, fastest (largest σ) first.
    stable: True when no σ ≥ 0 solution exists and that is proved (``evidence`` says how);
        False when a certified mode exists; None when the search was inconclusive.
    evidence: one sentence on what was searched and what it proves.
    states: the base's contact nodes, left to right, from stick | slip+ | slip- | separated |
        grazing; interface_states: the same per frictional interface (lower layer's name).
    static: the static equilibrium result when states were solved for (else None).
    eicp: the raw :class:`~meicp.eicp.problem.EiCPResult` (None when nothing was solved).
    sizes: DOF counts (all, retained, complementarity).
    """

    modes: list = field(default_factory=list)
    stable: bool | None = None
    evidence: str = ""
    states: list = field(default_factory=list)
    interface_states: dict = field(default_factory=dict)
    static: object = None
    eicp: object = None
    sizes: dict = field(default_factory=dict)

    def summary(self) -> str:
        verdict = {True: "STABLE", False: "UNSTABLE", None: "UNDECIDED"}[self.stable]
        lines = [f"{verdict}: {self.evidence}"]
        for k, m in enumerate(self.modes[:10]):
            lines.append(f"  mode {k}: σ = {m.sigma:.10g}, growth rate λ = {m.growth_rate:.6g}, "
                         f"slipping nodes {m.support.tolist()}, residual {m.residual:.1e}")
        if len(self.modes) > 10:
            lines.append(f"  ... {len(self.modes) - 10} more modes")
        return "\n".join(lines)
