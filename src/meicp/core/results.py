"""Result base shared by every solver.

A result is *successful* only when its certificate passes: ``success`` is derived from
``status`` and never set independently, so a solver cannot report a solution whose
residual failed.
"""

from __future__ import annotations

from dataclasses import dataclass, field

#: the status of a certified solution; every other status is a failure
SOLVED = "solved"


@dataclass
class Result:
    """Fields every solver result has.

    status: ``"solved"`` when certified; otherwise a short word for what happened
        (``"max_iterations"``, ``"ray_termination"``, ``"infeasible"``, ``"certificate_failed"``...).
    message: one sentence for a person, saying what happened and what it implies.
    iterations: the solver's own iteration count (pivots, Newton steps, outer steps).
    residual: the certificate, relative to the data's scale (see each solver's docs).
    timings: wall-clock seconds per phase.
    """

    status: str = "not_run"
    message: str = ""
    iterations: int = 0
    residual: float = float("nan")
    timings: dict = field(default_factory=dict)

    @property
    def success(self) -> bool:
        return self.status == SOLVED
