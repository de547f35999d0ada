"""The benchmarks' scene: two bonded layers, a soft one (k = 1, ρ = 1) under a stiff one
(k = 5, ρ = 2), as in ``data/scenes/two_layers.toml`` — built in one place, checked by the
same parser as a scene file."""

from __future__ import annotations

import math

from meicp.io.scene import scene_from_dict


def two_layer_scene(nx: int, rows: tuple[int, int], *, mu: float | None = None, states="slip+",
                    shear: float = 0.0, load=None, spacing: float = 1.0, stiffness=(1.0, 5.0),
                    density=(1.0, 2.0), top: str = "fixed", bottom: str = "contact", sides: str = "free",
                    interface: dict | None = None, solver: dict | None = None, petsc: dict | None = None,
                    title: str = ""):
    """A :class:`~meicp.scene.Scene`: ``nx`` columns, ``rows = (lower, upper)`` node rows of
    layer A (``stiffness[0]``, ``density[0]``) under layer B; boundary ``top`` / ``bottom`` /
    ``sides`` (left and right).  On a rough base (``bottom = "contact"``) the contacts have
    friction ``mu`` and ``states`` (one state, a list, or ``"solve"``).  ``load``: the
    prescribed top-row displacement ``(ux, uy)``; ``interface``: the A/B interface's table
    (e.g. ``{"kind": "frictional", "friction": 0.3, "states": "stick"}``); ``solver``,
    ``petsc``: the scene's ``[solver]`` and ``[petsc]`` tables."""
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


def lattice_shape(dofs: int) -> tuple[int, int]:
    """``(nx, ny)`` with nx = 2·ny and about ``dofs`` DOFs; 10^6 exactly is 1000 × 500 (the
    lattice of data/scenes/extensive.toml)."""
    if dofs == 1_000_000:
        return 1000, 500
    ny = max(2, 2 * round(math.sqrt(dofs / 4) / 2))
    return 2 * ny, ny


def halves(ny: int) -> tuple[int, int]:
    """``ny`` rows split into (lower, upper), the lower layer the thinner when ny is odd."""
    return ny // 2, ny - ny // 2
