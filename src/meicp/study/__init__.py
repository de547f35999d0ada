"""Studies of a scene across a parameter: :func:`sweep` (``meicp sweep``) analyses it at
every value of a grid and writes a table, a summary and a stability map; the parameter is
named by key and set by :func:`scene_with` (:mod:`meicp.study.parameters`).

    import meicp
    result = meicp.sweep("data/scenes/two_layers.toml", "friction", "0:3:13", out="out/two_layers-sweep")
    result.divergence_onset.describe()   # μ_c ∈ (1.75, 2]: divergence proved absent at 1.75, ...
"""

from .parameters import parameter_keys, parse_values, scene_with
from .result import Onset, SweepResult, SweepRow
from .driver import sweep

__all__ = ["sweep", "SweepResult", "SweepRow", "Onset", "scene_with", "parameter_keys", "parse_values"]
