"""The critical friction (``meicp.critical_friction``): the smallest μ at which a σ = 0
divergence mode exists, as a certified bracket (docs/critical-friction.md).

Modules by concern: :mod:`.result` (the answer, :class:`CriticalFriction`), :mod:`.enumerated`
(the EiCP in μ condensed and enumerated, up to ``limits.CRITICAL_J`` pairs), :mod:`.bracket` (beyond:
a proved lower end and a certified mode), :mod:`.bisection` (the cross-check on the σ-problem)
and :mod:`.solve` (the driver)."""

from .result import CriticalFriction
from .solve import critical_friction, friction_pencils

__all__ = ["CriticalFriction", "critical_friction", "friction_pencils"]
