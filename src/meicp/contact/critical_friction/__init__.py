"""The critical friction (``meicp.critical_friction``): the friction at which the first
instability starts — the smaller of the divergence onset (a σ = 0 mode) and the flutter onset
(a non-real σ of the sliding pencil) — as a certified bracket (docs/critical-friction.md).

Modules by concern: :mod:`.result` (the answer, :class:`CriticalFriction`, and each onset's
:class:`Onset`), :mod:`.enumerated` (the EiCP in μ condensed and enumerated, up to
``limits.CRITICAL_J`` pairs), :mod:`.bracket` (beyond: a proved lower end and a certified
mode), :mod:`.bisection` (the cross-check on the σ-problem), :mod:`.flutter_onset` (μ_f: an
interval cover and a certified flutter mode) and :mod:`.solve` (the driver)."""

from .result import CriticalFriction, CriticalFrictionFailed, Onset
from .solve import critical_friction, friction_pencils

__all__ = ["CriticalFriction", "CriticalFrictionFailed", "Onset", "critical_friction", "friction_pencils"]
