"""Ready-made scenes for tests, benchmarks and studies.

:func:`two_layer_scene` builds the project's one example lattice — two bonded layers, a
soft one (k = 1, ρ = 1) under a stiff one (k = 5, ρ = 2), as in
``data/scenes/two_layers.toml`` — at any size, through the same parser as a scene file, so a
built scene is checked exactly as a written one (a study across μ changes it with
:meth:`~meicp.scene.Scene.with_friction`).  :mod:`meicp.examples.failure_map`
holds the failure map's small problems and their brute-force references.

    from meicp.examples import two_layer_scene
    scene = two_layer_scene(60, (2, 2), mu=1.5, states="slip+", shear=0.5)
"""

from __future__ import annotations

from ..io.scene import scene_from_dict
from ..scene import Scene

__all__ = ["two_layer_scene"]


def two_layer_scene(nx: int, rows: tuple[int, int], *, mu: float | None = None, states="slip+",
                    shear: float = 0.0, load=None, spacing: float = 1.0, stiffness=(1.0, 5.0),
                    density=(1.0, 2.0), top: str = "fixed", bottom: str = "contact", sides: str = "free",
                    interface: dict | None = None, solver: dict | None = None, petsc: dict | None = None,
                    title: str = "") -> Scene:
    """A :class:`~meicp.scene.Scene`: ``nx`` columns, ``rows = (lower, upper)`` node rows of
    layer A (``stiffness[0]``, ``density[0]``) under layer B; boundary ``top`` / ``bottom`` /
    ``sides`` (left and right).  On a rough base (``bottom = "contact"``) the contacts have
    friction ``mu`` and ``states`` (one state, a list, or ``"solve"``).  ``load``: the
    prescribed top-row displacement ``(ux, uy)``; ``interface``: the A/B interface's table
    (e.g. ``{"kind": "frictional", "friction": 0.3, "states": "stick"}``); ``solver``,
    ``petsc``: the scene's ``[solver]`` and ``[petsc]`` tables.

    ``two_layer_scene(5, (2, 2), mu=3.0, load=(0.06, -0.1), petsc={"eps_tol": 1e-10})`` is
    ``data/scenes/two_layers.toml`` (tests/test_examples.py checks it)."""
    lower, upper = rows
    d = {"lattice": {"nx": nx, "spacing": spacing, "shear": shear},
         "layers": [{"name": "A", "rows": lower, "stiffness": stiffness[0], "density": density[0]},
                    {"name": "B", "rows": upper, "stiffness": stiffness[1], "density": density[1]}],
         "boundary": {"top": top, "bottom": bottom, "left": sides, "right": sides}}
    if title:
        d["title"] = title
    if bottom == "contact":
        d["contact"] = {"friction": mu, "states": states}
    if load is not None:
        d["load"] = {"top_displacement": list(load)}
    if interface:
        d["interfaces"] = [dict(below="A", **interface)]
    if solver:
        d["solver"] = dict(solver)
    if petsc:
        d["petsc"] = dict(petsc)
    return scene_from_dict(d, source=title or f"two-layer lattice {nx} x {lower + upper}")
