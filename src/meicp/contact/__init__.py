"""Contact: states (prescribed or from the static frictional equilibrium), the MEiCP maps and
pencil, the instability analysis and the critical friction (docs/design.md §6–§8).

Modules, from the bottom up: ``lines`` (the contact lines: node pairs, μ, states),
``maps`` (states → Q̃, P̃₀, P̃₁, μ), ``static`` (the static equilibrium, a package),
``problem`` (a scene → its pencil A = −P̃KQ̃, B = P̃MQ̃: :func:`pencil`), ``instability``
(``analyze``: the divergence verdict), ``critical_friction`` (a package; the function is
:func:`meicp.critical_friction`), ``result``.  They take a :class:`~meicp.scene.Scene`;
:mod:`meicp` also reads scene files.
"""

from .instability import analyze
from .problem import Pencil, pencil
from .result import InstabilityResult, Mode
from .static import StaticResult, static_equilibrium

__all__ = ["analyze", "pencil", "Pencil", "static_equilibrium", "InstabilityResult", "Mode", "StaticResult"]
