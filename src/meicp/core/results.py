"""Result base shared by every solver.

A result is *successful* only when its certificate passes: ``success`` is derived from
``status`` and never set independently, so a solver cannot report a solution whose
residual failed.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

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


#: a repr is a line for a person; the whole content stays in the fields
REPR_ITEMS = 6


def brief(values, limit: int = REPR_ITEMS) -> str:
    """A vector for a repr: every entry up to ``limit`` of them (``[1 0 2]``), else the first
    ones and the length (``[0.1 0.2 0.3 ... (1200 values)]``)."""
    if values is None:
        return "None"
    a = np.ravel(np.asarray(values))
    shown = " ".join(f"{v:.4g}" if isinstance(v, (float, np.floating)) else str(v) for v in a[:limit].tolist())
    return f"[{shown}]" if a.size <= limit else f"[{shown} ... ({a.size} values)]"


def brief_text(text: str, limit: int = 80) -> str:
    """A message for a repr: its first ``limit`` characters."""
    text = " ".join(str(text).split())
    return text if len(text) <= limit else text[:limit - 1] + "…"
