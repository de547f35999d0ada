"""The divergence verdict of one MEiCP and the proof behind it, as values."""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class DivergenceProof:
    """What stands behind a divergence verdict.

    test: ``"enumerate"`` (or the method asked for by name), ``"rayleigh-inertia"``,
    ``"condensed-pd"``, ``"condensed-windows"``, ``"rayleigh-window+condensed-windows"``,
    ``"certified-mode"``, ``"all-held"``, the damped lattice's ``"quadratic-enumerate"`` and
    ``"damped-rayleigh"`` (:mod:`meicp.contact.damped_rayleigh`), ``"damped-condensed-windows"``
    (:mod:`meicp.contact.damped_windows`), ``"proportional-damping"``
    (:mod:`meicp.contact.damped_proportional`: the undamped verdict decides), or ``""`` when nothing was
    proved.  statement: the
    sentence saying what was proved (or why not).  supports_visited: supports the search
    (or the enumeration) visited; None when nothing was solved.  The window procedure
    (:func:`~.driver.window_verdict`) also records sigma_window (the σ-interval proved free
    of modes, or None: none proved) and eigen_solves (SLEPc solves of its searches); both are
    None on the other paths.  margin: the condensed proof's smallest certified margin, when
    a condensed proof decided.  stable_friction_scale and stable_friction: on an undecided
    verdict of the window procedure, the μ up to which these contact states are proved free
    of divergence, over the scene's and per contact line (:mod:`..friction_range`)."""

    test: str
    statement: str
    supports_visited: int | None = None
    sigma_window: tuple | None = None
    eigen_solves: int | None = None
    margin: float | None = None
    stable_friction_scale: float | None = None
    stable_friction: dict | None = field(default=None, hash=False)

    @property
    def windowed(self) -> bool:
        """Whether the window procedure made this proof (it then states its σ-window)."""
        return self.eigen_solves is not None

    def to_dict(self) -> dict:
        """The proof as the keys results.json and results.h5 have always had: the window
        procedure's ``test, statement, sigma_window, supports_visited, eigen_solves``, the
        others' ``test, [supports_visited,] statement``; then ``margin`` and the friction
        range where they were established."""
        if self.windowed:
            out = {"test": self.test, "statement": self.statement, "sigma_window": self.sigma_window,
                   "supports_visited": self.supports_visited, "eigen_solves": self.eigen_solves}
        else:
            out = {"test": self.test}
            if self.supports_visited is not None:
                out["supports_visited"] = self.supports_visited
            out["statement"] = self.statement
        if self.margin is not None:
            out["margin"] = self.margin
        if self.stable_friction_scale is not None:
            out["stable_friction_scale"] = self.stable_friction_scale
            out["stable_friction"] = dict(self.stable_friction or {})
        return out


@dataclass(frozen=True)
class DivergenceVerdict:
    """The divergence verdict of one MEiCP (one grazing case).

    modes: its certified modes with σ ≥ lam_min (:class:`~meicp.contact.result.Mode`).
    stable: True (proved: no mode with σ ≥ 0), False (a certified mode with σ ≥ 0, listed or
    not), None (undecided).  evidence: the sentence ``analyze`` reports.  eicp: the raw
    :class:`~meicp.eicp.problem.EiCPResult` of the last search or enumeration (None when a
    proof needed none).  proof: the :class:`DivergenceProof`."""

    modes: list
    stable: bool | None
    evidence: str
    eicp: object
    proof: DivergenceProof

    def real_part_bound(self) -> tuple[float, str] | None:
        """``(γ, how)`` when the proof bounds every eigenvalue of the pencil, not only the
        MEiCP's solutions: a Rayleigh bound sym(A) − γ·sym(B) ≺ 0 gives Re σ < γ for each
        (x*Ax = σ·x*Bx with x complex); None otherwise (the flutter search's Bendixson bound
        uses it: :func:`~meicp.contact.flutter.search_flutter`)."""
        if self.proof.test == "rayleigh-inertia":
            return 0.0, "the divergence verdict's Rayleigh bound at 0: sym(A) ≺ 0"
        if self.proof.test == "rayleigh-window+condensed-windows" and self.proof.sigma_window:
            top = float(self.proof.sigma_window[1])
            return top, f"the divergence verdict's Rayleigh bound at σ_max = {top:.6g}"
        return None


def all_held() -> DivergenceVerdict:
    """The verdict of a pencil with no retained DOF: nothing can move."""
    text = "every DOF is held (fixed or sticking): no mode can exist"
    return DivergenceVerdict([], True, text, None, DivergenceProof("all-held", text))
