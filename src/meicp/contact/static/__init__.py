"""Static frictional equilibrium: the contact states behind ``states = "solve"`` (docs/design.md §6.3,
seed 002 §2).  The formulations, sign conventions and tolerances are derived in
``docs/static-equilibrium.md``; the modules follow its sections (``data``, ``condensed``,
``mixed``, ``states``), ``solve`` dispatches and ``result`` is what comes back."""

from .data import StaticData, body_force, prescribed_displacements
from .result import StaticResult
from .solve import TOL, static_equilibrium

__all__ = ["StaticResult", "StaticData", "static_equilibrium", "prescribed_displacements", "body_force",
           "TOL"]
