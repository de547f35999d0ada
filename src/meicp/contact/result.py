"""What :func:`meicp.analyze` returns (docs/design.md §10.2): divergence modes and verdict, flutter
modes and verdict (docs/flutter.md), each with its evidence, contact states, timings; and the
summary table ``meicp solve`` prints."""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core.json_values import json_ready
from ..core.results import Result, brief
from ..scene import STATES

#: one character per contact state, for the compact per-column strip of the summary
GLYPHS = dict(zip(STATES, "|><o~"))
#: show the per-column strip up to this many columns
STRIP_MAX = 100
#: modes listed in a summary
SUMMARY_MODES = 10
#: the proofs that leave no mode unfound: the enumeration of every support (undamped or
#: damped) and the proofs that there is none (a grazing branch's); only where every branch's
#: proof is one of them is the first mode listed the fastest — a search, or a method named by
#: the caller, finds some
ALL_MODES = ("enumerate", "quadratic-enumerate", "rayleigh-inertia", "condensed-pd", "condensed-windows",
             "rayleigh-window+condensed-windows", "damped-rayleigh", "all-held")
#: the verdict of a scene without contact (:mod:`meicp.contact.modal`)
MODAL_VERDICT = "NO CONTACT: modal analysis"


@dataclass
class Mode:
    """One divergence mode: σ = λ² ≥ 0 and its growth rate λ = √σ; or, in the modal
    analysis of a scene without contact, one vibration mode: σ = −ω² ≤ 0 and its angular
    frequency ω = √−σ (support empty).

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

    def __repr__(self) -> str:
        if self.sigma < 0:
            return f"Mode(σ={self.sigma:.6g}, ω={self.frequency:.6g}, residual {self.residual:.1e})"
        sup = "".join(f", interface {k!r} support {brief(v)}" for k, v in self.interface_support.items())
        return (f"Mode(σ={self.sigma:.6g}, growth rate {self.growth_rate:.6g}, support {brief(self.support)}"
                f"{sup}, residual {self.residual:.1e})")

    @property
    def frequency(self) -> float:
        """Angular frequency ω = √−σ of an oscillating mode (σ < 0); 0 for σ ≥ 0."""
        return float(np.sqrt(max(-self.sigma, 0.0)))

    def to_dict(self) -> dict:
        """Everything but the shape ``x``, as JSON-ready values (numbers as
        :mod:`meicp.core.json_values` writes them)."""
        return json_ready({"sigma": self.sigma, "growth_rate": self.growth_rate, "frequency": self.frequency,
                           "residual": self.residual, "support": np.ravel(self.support),
                           "interface_support": {k: np.ravel(v) for k, v in self.interface_support.items()}})


@dataclass
class FlutterMode:
    """One flutter mode of steady sliding (docs/flutter.md): a non-real eigenvalue σ of the
    sliding pencil, reported once per conjugate pair (Im σ > 0).  λ = √σ (principal branch):
    the motion grows as exp(growth_rate·t) and oscillates at the angular ``frequency``.

    x: the complex mode shape in natural DOF numbering (length 2·nx·ny, ‖x‖₂ = 1, largest
    entry real positive; fixed and sticking DOFs 0).  residual: backward error
    ‖Ax − σBx‖ / ((‖A‖₁ + |σ|‖B‖₁)‖x‖) on the retained DOFs (a mode above
    :data:`meicp.contact.flutter_verdict.RESIDUAL_TOL` is never reported).  support: the base's
    sliding contact nodes of the pencil (columns, left to right); interface_support the same
    per frictional interface.  radius: how far rounding may move σ (dense path: the
    first-order bound n·u·(‖A‖ + |σ|‖B‖)·κ; large-scale path: the margin used instead of
    the unknown κ); |Im σ| exceeds it, so σ is not real.  branch: the grazing branch
    (``separated`` / ``sliding ...``; empty without grazing contacts).  found_by: the method.
    """

    sigma: complex
    x: np.ndarray
    residual: float
    support: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    interface_support: dict = field(default_factory=dict)
    radius: float = float("nan")
    branch: str = ""
    found_by: str = ""

    @property
    def growth_rate(self) -> float:
        return growth_frequency(self.sigma)[0]

    def __repr__(self) -> str:
        return (f"FlutterMode(σ={_complex(self.sigma)}, growth rate {self.growth_rate:.6g}, "
                f"frequency {self.frequency:.6g}, residual {self.residual:.1e})")

    @property
    def frequency(self) -> float:
        return growth_frequency(self.sigma)[1]

    def to_dict(self) -> dict:
        """Everything but the shape ``x``, as JSON-ready values (numbers as
        :mod:`meicp.core.json_values` writes them)."""
        return json_ready({"sigma_real": self.sigma.real, "sigma_imag": self.sigma.imag,
                           "growth_rate": self.growth_rate, "frequency": self.frequency, "residual": self.residual,
                           "radius": self.radius, "support": np.ravel(self.support),
                           "interface_support": {k: np.ravel(v) for k, v in self.interface_support.items()},
                           "branch": self.branch, "found_by": self.found_by})


def growth_frequency(sigma) -> tuple[float, float]:
    """(Re λ, |Im λ|) of λ = √σ without cancellation: for Re σ < 0 the growth rate is
    |Im σ| / (2|Im λ|) (``sqrt((|σ| + Re σ)/2)`` loses every digit when |Im σ| ≪ |Re σ|)."""
    s = complex(sigma)
    r = abs(s)
    if s.real >= 0:
        g = float(np.sqrt(0.5 * (r + s.real)))
        return g, (abs(s.imag) / (2 * g) if g > 0 else 0.0)
    f = float(np.sqrt(0.5 * (r - s.real)))
    return abs(s.imag) / (2 * f), f


@dataclass
class InstabilityResult(Result):
    """Result of :func:`meicp.analyze`.

    analysis: ``"instability"`` (a scene with contact: the divergence verdict) or
        ``"modal"`` (no contact: the lowest vibration modes, :mod:`meicp.contact.modal`).
    modes: certified divergence modes, fastest (largest σ) first; in a modal analysis the
        vibration modes (σ = −ω² ≤ 0), lowest frequency first.
    divergence: False when no σ ≥ 0 solution exists and that is proved (``evidence`` says
        how); True when a certified divergence mode exists; None when the search was
        inconclusive (:attr:`divergence_failure` says why when a solver failed).
    flutter: True when a certified flutter mode of steady sliding exists, False when its
        absence is proved (dense QZ of the whole spectrum, or symmetry), None when undecided
        or not analysed (``flutter_evidence`` says which).
    stable: True only when divergence and flutter are both False; False when either is
        True; else None.  In a modal analysis: the modal verdict.  ``status`` is
        ``"inconclusive"`` (success False) only when ``stable`` is None because a solver
        failed: a certified flutter mode answers the question (UNSTABLE, status ``solved``)
        even when the divergence search failed, which then stays undecided.
    evidence: one sentence on what the divergence search covered and what it proves.
    flutter_modes: certified :class:`FlutterMode` s, fastest found (largest growth rate) first;
        ``flutter_modes[0]`` is *the* fastest only when ``flutter_growth.exact``.
    flutter_evidence: what the flutter analysis searched and what it proves.
    flutter_growth: the certified bracket of the fastest flutter growth rate
        (:class:`~meicp.contact.flutter_growth.FlutterGrowth`: ``lower`` from a certified mode,
        ``upper`` proved — no flutter mode grows faster — or None, ``exact``); None when
        flutter was not analysed.
    states: the base's contact nodes, left to right, from stick | slip+ | slip- | separated |
        grazing; interface_states: the same per frictional interface (lower layer's name).
    static: the static equilibrium result when states were solved for (else None).
    proofs: what stands behind the divergence verdict, one
        :class:`~meicp.contact.divergence.DivergenceProof` per MEiCP (grazing case): ``test``
        (``enumerate``, ``rayleigh-inertia``, ``rayleigh-window+condensed-…``,
        ``certified-mode``, or ``""`` when nothing was proved), ``statement``, and for the
        large-problem path ``sigma_window`` (the σ-interval proved free of modes, or None),
        ``supports_visited``, ``eigen_solves``; an undecided one also ``stable_friction``
        (contact line → the μ up to which these states are proved stable) and
        ``stable_friction_scale`` (that μ over the scene's) (:mod:`meicp.contact.divergence`,
        :mod:`meicp.contact.friction_range`).  :meth:`to_dict` writes each as its
        ``to_dict()``.
    eicp: the raw :class:`~meicp.eicp.problem.EiCPResult` of each MEiCP solved, one per
        grazing case, in the order of :func:`~meicp.contact.maps.grazing_cases` (None for a
        case with every DOF held: nothing to solve); empty when no MEiCP was reached.
    sizes: DOF counts (all, retained, complementarity).
    damping: the damping the analysis used (:class:`~meicp.contact.damped.DampingUsed`: each
        material's viscosity, ``[damping] mass``), None for an undamped scene; damped, σ = λ²
        and ``growth_rate`` = λ of the quadratic problem (docs/damping.md).
    critical_friction: the critical friction stored beside the result (results.h5 of
        ``meicp solve --critical-friction``, read back by :func:`meicp.load_results`);
        ``analyze`` leaves it None (:func:`meicp.critical_friction` computes it); a
        :class:`~meicp.contact.critical_friction.result.CriticalFrictionFailed` when that
        computation failed (its error, no value).

    ``repr()`` is one line (the verdict and the fastest modes); everything is in the fields,
    ``summary()`` and ``to_dict()``.
    """

    analysis: str = "instability"
    modes: list = field(default_factory=list)
    stable: bool | None = None
    evidence: str = ""
    divergence: bool | None = None
    flutter: bool | None = None
    flutter_modes: list = field(default_factory=list)
    flutter_evidence: str = ""
    flutter_growth: object = None
    states: list = field(default_factory=list)
    interface_states: dict = field(default_factory=dict)
    static: object = None
    eicp: list = field(default_factory=list)
    proofs: list = field(default_factory=list)
    sizes: dict = field(default_factory=dict)
    critical_friction: object = None
    damping: object = None

    def __repr__(self) -> str:
        head = self.verdict if self.success else f"FAILED ({self.status}), {self.verdict}"
        n, m = len(self.modes), len(self.flutter_modes)
        plural = {1: ""}
        dofs = f", {self.sizes['dofs']:,} DOFs" if "dofs" in self.sizes else ""
        if self.modal:
            low = f", lowest ω={self.modes[0].frequency:.4g}" if n else ""
            return f"InstabilityResult({head}: {n} vibration mode{plural.get(n, 's')}{low}{dofs})"
        divergence = {True: "divergence", False: "no divergence"}.get(self.divergence, "divergence undecided")
        if n:
            divergence += f" σ={self.modes[0].sigma:.4g} ({n} mode{plural.get(n, 's')})"
        flutter = {True: "flutter", False: "no flutter"}.get(self.flutter, "flutter undecided")
        if m:
            flutter += f" growth {self.flutter_modes[0].growth_rate:.4g} ({m} mode{plural.get(m, 's')})"
        mu = ("" if self.critical_friction is None else f", μ_c {float(self.critical_friction):.6g}"
              if isinstance(self.critical_friction, float) else f", μ_c {self.critical_friction}")
        return f"InstabilityResult({head}: {divergence}, {flutter}{mu}{dofs})"

    @property
    def modal(self) -> bool:
        return self.analysis == "modal"

    def compose_verdict(self) -> None:
        """``stable`` from ``divergence`` and ``flutter``: True only when both are excluded."""
        parts = (self.divergence, self.flutter)
        self.stable = False if True in parts else (True if all(p is False for p in parts) else None)

    def _failed_search(self):
        """The first MEiCP whose solver failed when divergence is undecided, else None."""
        if self.divergence is not None:
            return None
        return next((e for e in self.eicp if e is not None and not e.success and e.status != "no_solution"), None)

    @property
    def divergence_failure(self) -> str | None:
        """Why the divergence search was inconclusive — the message of the first MEiCP whose
        solver failed — or None (divergence decided, or undecided with what was proved and no
        failure).  Set whether or not flutter decided the verdict."""
        e = self._failed_search()
        return None if e is None else (e.message or f"{e.method}: {e.status}")

    @property
    def divergence_verdict(self) -> str:
        """DIVERGENCE, NO DIVERGENCE or DIVERGENCE UNDECIDED, the last with "(search
        inconclusive: enumerate ended undecided)" when a solver failed (the reason is in the
        evidence: not repeated on this line)."""
        text = {True: "DIVERGENCE", False: "NO DIVERGENCE"}.get(self.divergence, "DIVERGENCE UNDECIDED")
        e = self._failed_search()
        return text if e is None else f"{text} (search inconclusive: {e.method or 'the solver'} ended {e.status})"

    @property
    def flutter_verdict(self) -> str:
        return {True: "FLUTTER", False: "NO FLUTTER"}.get(self.flutter, "FLUTTER UNDECIDED")

    @property
    def verdict(self) -> str:
        """STABLE, UNSTABLE or UNDECIDED (the verdict alone, whatever ``status``); NO CONTACT
        for a modal analysis (no friction, hence no frictional instability)."""
        if self.modal:
            return MODAL_VERDICT
        return {True: "STABLE", False: "UNSTABLE"}.get(self.stable, "UNDECIDED")

    def to_dict(self) -> dict:
        """The result as JSON-ready values, keyed like its attributes (``meicp solve --json``):
        analysis, verdict, stable, divergence, flutter, status, success, message, evidence,
        divergence_failure (None, or why the divergence search was inconclusive), flutter_evidence,
        flutter_growth (``{lower, upper, exact, evidence}``, upper None when unbounded),
        proofs (a σ-window [0, ∞) as ``[0.0, null]`` with ``sigma_window_infinite: [0, 1]``:
        :mod:`meicp.core.json_values`), modes (each :meth:`Mode.to_dict`, no shapes), flutter_modes (each
        :meth:`FlutterMode.to_dict`), states, interface_states, sizes, timings, and the
        static equilibrium's status when states were solved for; ``damping`` (first) when
        the scene is damped."""
        static = self.static
        damping = {} if self.damping is None else {"damping": self.damping.to_dict()}
        return damping | {
            "analysis": self.analysis, "verdict": self.verdict, "stable": self.stable,
            "divergence": self.divergence, "flutter": self.flutter,
            "status": self.status, "success": self.success, "message": self.message,
            "evidence": self.evidence, "divergence_failure": self.divergence_failure,
            "iterations": int(self.iterations),
            "proofs": [json_ready(p.to_dict()) for p in self.proofs],
            "modes": [m.to_dict() for m in self.modes],
            "flutter_evidence": self.flutter_evidence,
            "flutter_growth": None if self.flutter_growth is None else self.flutter_growth.to_dict(),
            "flutter_modes": [m.to_dict() for m in self.flutter_modes],
            "states": list(self.states),
            "interface_states": {str(k): list(v) for k, v in self.interface_states.items()},
            "sizes": {str(k): int(v) for k, v in self.sizes.items()},
            "timings": json_ready(self.timings),
            "static": None if static is None else {
                "status": getattr(static, "status", None), "success": bool(getattr(static, "success", False)),
                "message": getattr(static, "message", "")},
        }

    def summary(self) -> str:
        lines = [f"{self.verdict}: {self.evidence}"]
        if not self.modal:
            lines = [self.verdict, f"  divergence: {self.divergence_verdict}: {self.evidence}"]
        if self.damping is not None:
            lines.insert(1, f"  damping: {self.damping.describe()}")
        for k, m in enumerate(self.modes[:SUMMARY_MODES]):
            if self.modal:
                lines.append(f"  mode {k}: σ = {m.sigma:.10g}, angular frequency ω = {m.frequency:.6g}, "
                             f"residual {m.residual:.1e}")
                continue
            lines.append(f"  mode {k}: σ = {m.sigma:.10g}, growth rate λ = {m.growth_rate:.6g}, "
                         f"slipping nodes {m.support.tolist()}, residual {m.residual:.1e}")
        if len(self.modes) > SUMMARY_MODES:
            lines.append(f"  ... {len(self.modes) - SUMMARY_MODES} more modes")
        if not self.modal:
            lines.append(f"  flutter: {self.flutter_verdict}: {self.flutter_evidence}")
            if self.flutter_growth is not None:
                lines.append(f"  flutter growth rate: {self.flutter_growth.describe()}")
            for k, m in enumerate(self.flutter_modes[:SUMMARY_MODES]):
                lines.append(f"  flutter mode {k}: σ = {_complex(m.sigma)}, growth rate {m.growth_rate:.6g}, "
                             f"frequency {m.frequency:.6g}, residual {m.residual:.1e}")
            if len(self.flutter_modes) > SUMMARY_MODES:
                lines.append(f"  ... {len(self.flutter_modes) - SUMMARY_MODES} more flutter modes")
        return "\n".join(lines)

    def summary_rows(self, scene, *, ranks: int = 1) -> list[tuple[str, str]]:
        """The (key, text) rows of the table ``meicp solve`` prints for ``scene``: the scene and
        its sizes, the states of each contact line, the verdict, its evidence, the modes (a
        mode table row has key ``""``) and the timings."""
        rows = []
        name = scene.title or (Path(scene.source).stem if scene.source else "scene")
        rows.append(("scene", name + (f"  ({scene.source})" if scene.source else "")))
        size_text = ", ".join(f"{k} {v:,}" if isinstance(v, int) else f"{k} {v}" for k, v in self.sizes.items())
        rows.append(("lattice", f"{scene.nx} × {scene.ny} nodes, {scene.n_dofs:,} DOFs"
                     + (f" ({size_text})" if size_text else "") + f", {ranks} rank{'s' if ranks != 1 else ''}"))
        if scene.boundary.bottom == "contact":
            rows.append(("base", f"{scene.nx} contact nodes, μ = {scene.contact.friction:g}: "
                                 f"{states_compact(self.states)}{_strip(self.states)}"))
        for itf in scene.frictional_interfaces():
            st = list(self.interface_states.get(itf.below) or [])
            rows.append((f"interface {itf.below}", f"{scene.nx} contact pairs, μ = {itf.friction:g}: "
                                                   f"{states_compact(st)}{_strip(st)}"))
        if self.damping is not None:
            rows.append(("damping", self.damping.describe()))
        verdict = self.verdict
        if not self.success:
            verdict = f"FAILED ({self.status})" + ("" if self.stable is None else f", last verdict {verdict}")
        rows.append(("verdict", verdict))
        if not self.modal:
            rows.append(("divergence", self.divergence_verdict))
        if self.evidence:
            rows.append(("evidence", self.evidence))
        if self.message and self.message != self.evidence:
            rows.append(("message", self.message))
        if self.modes and self.modal:
            n = len(self.modes)
            rows.append(("modes", f"{n} certified vibration mode{'s' if n != 1 else ''} (σ = −ω², lowest "
                                  f"frequency first)"))
            rows.append(("", f"  {'#':>3}  {'σ':>14}  {'frequency ω':>14}  {'residual':>9}"))
            for k, m in enumerate(self.modes[:SUMMARY_MODES]):
                rows.append(("", f"  {k:>3}  {m.sigma:>14.8g}  {m.frequency:>14.8g}  {m.residual:>9.1e}"))
            if n > SUMMARY_MODES:
                rows.append(("", f"  ... {n - SUMMARY_MODES} more (all in results.h5)"))
        elif self.modes:
            n = len(self.modes)
            # a search finds some modes, not all: its fastest is not proved the fastest
            every = all(p.test in ALL_MODES for p in self.proofs)
            order = "fastest first" if every else "fastest found first, not proved the fastest"
            rows.append(("modes", f"{n} certified divergence mode{'s' if n != 1 else ''} (σ = λ², {order})"))
            rows.append(("", f"  {'#':>3}  {'σ':>14}  {'growth rate λ':>14}  {'support':>8}  {'residual':>9}"))
            for k, m in enumerate(self.modes[:SUMMARY_MODES]):
                sup = int(np.size(m.support)) + sum(int(np.size(v)) for v in m.interface_support.values())
                rows.append(("", f"  {k:>3}  {m.sigma:>14.8g}  {m.growth_rate:>14.8g}  {sup:>8d}  {m.residual:>9.1e}"))
            if n > SUMMARY_MODES:
                rows.append(("", f"  ... {n - SUMMARY_MODES} more (all in results.h5)"))
        else:
            rows.append(("modes", "none"))
        if not self.modal:
            rows.append(("flutter", self.flutter_verdict))
            if self.flutter_evidence:
                rows.append(("flutter evidence", self.flutter_evidence))
            if self.flutter_growth is not None:
                rows.append(("flutter growth", self.flutter_growth.describe()))
            if self.flutter_modes:
                n = len(self.flutter_modes)
                fastest = ("fastest first" if self.flutter_growth is not None and self.flutter_growth.exact
                           else "fastest found first, not proved the fastest")
                rows.append(("flutter modes", f"{n} certified flutter mode{'s' if n != 1 else ''} "
                                              f"(σ complex, λ = √σ, {fastest})"))
                rows.append(("", f"  {'#':>3}  {'σ':>30}  {'growth Re λ':>12}  {'freq. |Im λ|':>12}  "
                                 f"{'residual':>9}"))
                for k, m in enumerate(self.flutter_modes[:SUMMARY_MODES]):
                    rows.append(("", f"  {k:>3}  {_complex(m.sigma):>30}  {m.growth_rate:>12.6g}  "
                                     f"{m.frequency:>12.6g}  {m.residual:>9.1e}"))
                if n > SUMMARY_MODES:
                    rows.append(("", f"  ... {n - SUMMARY_MODES} more (all in results.h5)"))
        if self.timings:
            rows.append(("timings", ", ".join(f"{k} {seconds(float(v))}" for k, v in self.timings.items())))
        return rows


def _complex(z: complex) -> str:
    return f"{z.real:.10g} {'+' if z.imag >= 0 else '−'} {abs(z.imag):.6g}i"


def states_compact(states) -> str:
    """``slip+ ×12, stick ×3`` (in the order of docs/design.md §7.1's table); "unknown" when empty."""
    if not states:
        return "unknown"
    counts = Counter(states)
    order = list(GLYPHS) + sorted(set(counts) - set(GLYPHS))
    return ", ".join(f"{s} ×{counts[s]}" for s in order if counts[s])


def _strip(states) -> str:
    if not states or len(states) > STRIP_MAX:
        return ""
    return "  [" + "".join(GLYPHS.get(s, "?") for s in states) + "]"


def seconds(t: float) -> str:
    """A duration for people: milliseconds below a second."""
    return f"{t * 1e3:.1f} ms" if t < 1 else f"{t:.2f} s"
