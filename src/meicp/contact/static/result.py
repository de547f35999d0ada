"""What :func:`~meicp.contact.static.static_equilibrium` returns (docs/static-equilibrium.md)."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ...core.results import Result, brief_text
from ...lcp.problem import LCPResult


@dataclass
class StaticResult(Result):
    """Result of :func:`static_equilibrium`.

    states: the base's contact nodes, left to right (empty without a base, or when the LCP
        failed); interface_states: the same per frictional interface, keyed by the lower
        layer's name.
    r_n, r_t, gap, slip: per base contact (arrays, left to right): reactions on the node,
        gap change ``u_y`` and slip ``u_x``; interface_r_n, interface_r_t, interface_gap,
        interface_slip: dicts of the same per interface (reaction on the upper node,
        relative displacement ``u_upper − u_lower``).
    held, interface_held: bool arrays, contacts held by the Dirichlet boundary
        (docs/static-equilibrium.md).
    u: displacement, natural numbering (length 2·N); None when the LCP failed.
    lcp: the :class:`~meicp.lcp.problem.LCPResult`; lcp_matrix, lcp_q: the LCP solved
        (scaled, docs/static-equilibrium.md); layout: how its unknowns map to contacts.
    classes: :class:`~meicp.lcp.classes.MatrixClasses` of ``lcp_matrix`` (exact tests up to
        ``classify_limit`` unknowns, sufficient tests above); guarantees: sentences on
        existence / uniqueness at this μ (seed 002 §7 workflow).
    tolerances: the classification tolerances actually used.
    equilibrium_residual: ``‖K_ff u_f − b0 − C r‖∞ / F`` of the returned state.
    friction: μ per contact set.  rigid_modes: how many rigid modes the contacts hold.
    notes: remarks (ignored load components, inconsistencies within tolerance).
    """

    states: list = field(default_factory=list)
    interface_states: dict = field(default_factory=dict)
    r_n: np.ndarray | None = None
    r_t: np.ndarray | None = None
    gap: np.ndarray | None = None
    slip: np.ndarray | None = None
    held: np.ndarray | None = None
    interface_r_n: dict = field(default_factory=dict)
    interface_r_t: dict = field(default_factory=dict)
    interface_gap: dict = field(default_factory=dict)
    interface_slip: dict = field(default_factory=dict)
    interface_held: dict = field(default_factory=dict)
    u: np.ndarray | None = None
    lcp: LCPResult | None = None
    lcp_matrix: np.ndarray | None = None
    lcp_q: np.ndarray | None = None
    layout: dict = field(default_factory=dict)
    classes: object = None
    guarantees: list = field(default_factory=list)
    tolerances: dict = field(default_factory=dict)
    equilibrium_residual: float = float("nan")
    friction: dict = field(default_factory=dict)
    rigid_modes: int = 0
    notes: list = field(default_factory=list)

    def __repr__(self) -> str:
        if not self.success:
            return f"StaticResult({self.status}: {brief_text(self.message)})"
        lines = ([("base", self.states)] if self.states else []) + [
            (f"interface {name!r}", st) for name, st in self.interface_states.items()]
        parts = [f"{where} " + ", ".join(f"{s} ×{list(st).count(s)}" for s in dict.fromkeys(st))
                 for where, st in lines[:3]]
        more = f", ... {len(lines) - 3} more" if len(lines) > 3 else ""
        return (f"StaticResult({self.status}: {'; '.join(parts) or 'no contact'}{more}, "
                f"equilibrium residual {self.equilibrium_residual:.1e})")

    def finish(self, t_states: float, t_start: float) -> "StaticResult":
        """Record the time of reading the states (since ``t_states``) and in all (since
        ``t_start``, ``time.perf_counter`` values); returns the result."""
        now = time.perf_counter()
        self.timings["states"] = now - t_states
        self.timings["total"] = now - t_start
        return self

    def split_lcp(self, x) -> dict:
        """Physical quantities of an LCP solution ``x`` of ``(lcp_matrix, lcp_q)``:
        ``r_n`` (normal set), ``r_t`` (friction set), ``beta_plus``, ``beta_minus``, ``lam``,
        ``alpha``, with ``normal``/``friction`` = the contact ids (rows of ``layout["contacts"]``)."""
        lay = self.layout
        x = np.asarray(x, dtype=float)
        s = lay["scale"]
        out = {k: x[lay[k]] / s for k in ("r_n", "beta_plus", "beta_minus")}
        out["r_t"] = out["beta_plus"] - out["beta_minus"]
        out["lam"] = x[lay["lam"]]
        out["alpha"] = x[lay["alpha_plus"]] - x[lay["alpha_minus"]]
        out["normal"], out["friction"] = lay["normal"], lay["friction_set"]
        return out

    def summary(self) -> str:
        head = f"static equilibrium: {self.status}"
        if self.message:
            head += f" — {self.message}"
        lines = [head]
        if self.states:
            lines.append("  base: " + " ".join(self.states))
        for name, st in self.interface_states.items():
            lines.append(f"  interface above {name!r}: " + " ".join(st))
        lines.extend(f"  - {g}" for g in self.guarantees)
        return "\n".join(lines)
