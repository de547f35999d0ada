"""A picture of the lattice: layers coloured, bonds, boundary conditions and contacts.

Drawn with Matplotlib's Agg canvas directly (no pyplot, no global backend change).  Small
lattices show every bond and node; large ones (more than ``max_bonds`` bonds) show each
layer and embedded band as a filled region, so the picture costs the same at 10^6 DOFs.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..core.errors import ProblemError
from ..lattice.assembly import as_model
from ..lattice.model import LatticeModel

INTERFACE_COLOUR = "0.35"


def _corners(model: LatticeModel, j0: float, j1: float, i0: float, i1: float) -> np.ndarray:
    """Parallelogram covering node rows j0..j1 and columns i0..i1 (inclusive), half a spacing out."""
    a, s = model.spacing, model.shear
    pts = []
    for i, j in ((i0 - 0.5, j0 - 0.5), (i1 + 0.5, j0 - 0.5), (i1 + 0.5, j1 + 0.5), (i0 - 0.5, j1 + 0.5)):
        pts.append((a * (i + s * j), a * j))
    return np.array(pts)


def plot_lattice(scene, path, *, title: str | None = None, max_bonds: int = 60000,
                 dpi: int = 150) -> Path:
    """Draw the lattice of ``scene`` (Scene, LatticeModel or path) to the PNG ``path``."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.collections import LineCollection
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch, Polygon, Rectangle

    model = as_model(scene)
    path = Path(path)
    if not path.parent.is_dir():
        raise ProblemError(f"output directory {str(path.parent)!r} does not exist")
    a, nx, ny = model.spacing, model.nx, model.ny
    colours = [f"C{k % 10}" for k in range(len(model.materials))]

    width = a * (nx - 1 + abs(model.shear) * (ny - 1)) + 2 * a
    height = a * (ny - 1) + 2.5 * a
    fig_w = 10.0
    fig_h = float(np.clip(0.6 * fig_w * height / width + 1.1, 2.5, 11.0))
    fig = Figure(figsize=(fig_w, fig_h))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)

    n_bonds_est = 4 * nx * ny
    detailed = n_bonds_est <= max_bonds
    # filled regions: layers, then embedded bands on top
    for k, (r0, r1) in enumerate(model.layer_rows):
        ax.add_patch(Polygon(_corners(model, r0, r1 - 1, 0, nx - 1), closed=True,
                             facecolor=colours[k], alpha=0.18 if detailed else 0.75, lw=0))
    for r in model.regions:
        ax.add_patch(Polygon(_corners(model, r.j0, r.j1 - 1, r.i0, r.i1 - 1), closed=True,
                             facecolor=colours[r.material], alpha=0.3 if detailed else 0.9,
                             edgecolor=colours[r.material], lw=1.0))
    if detailed:
        ends, _, _ = model.bonds()
        pos = model.positions()
        mat = model.material()
        same = mat[ends[:, 0]] == mat[ends[:, 1]]
        seg_colours = [colours[m] if ok else INTERFACE_COLOUR for m, ok in zip(mat[ends[:, 0]], same)]
        lw = 1.2 if ends.shape[0] < 2000 else 0.5
        ax.add_collection(LineCollection(pos[ends], colors=seg_colours, linewidths=lw, zorder=2))
        if model.n_nodes <= 5000:
            ax.scatter(pos[:, 0], pos[:, 1], s=max(2.0, min(30.0, 3000.0 / model.n_nodes)),
                       c=[colours[m] for m in mat], edgecolors="k", linewidths=0.4, zorder=3)

    handles = [Patch(facecolor=colours[k], label=f"{m.name}: k = {m.stiffness:g}, ρ = {m.density:g}"
                     + (" (embedded)" if m.kind == "embedded" else ""))
               for k, m in enumerate(model.materials)]
    if detailed and not np.all(same):
        handles.append(Line2D([], [], color=INTERFACE_COLOUR, label="bond between materials"))

    # boundary conditions along each side
    def side_line(side):
        p = model.positions()
        idx = model.side_nodes(side)
        return p[idx]

    styles = {"fixed": ("k", "-", 3.5), "fixed_x": ("tab:purple", "--", 3.0),
              "fixed_y": ("tab:brown", ":", 3.0)}
    seen = set()
    for side in ("bottom", "top", "left", "right"):
        kind = getattr(model.boundary, side)
        if kind in styles:
            c, ls, w = styles[kind]
            pts = side_line(side)
            off = {"bottom": (0, -0.25), "top": (0, 0.25), "left": (-0.25, 0), "right": (0.25, 0)}[side]
            ax.plot(pts[:, 0] + off[0] * a, pts[:, 1] + off[1] * a, color=c, ls=ls, lw=w, zorder=4,
                    solid_capstyle="butt")
            if kind not in seen:
                label = {"fixed": "fixed (u = 0)", "fixed_x": "fixed x (u_x = 0)",
                         "fixed_y": "fixed y (u_y = 0)"}[kind]
                handles.append(Line2D([], [], color=c, ls=ls, lw=w, label=label))
                seen.add(kind)
    if model.boundary.bottom == "contact":
        x0 = -0.5 * a
        x1 = a * (nx - 0.5)
        ax.add_patch(Rectangle((x0, -0.75 * a), x1 - x0, 0.45 * a, facecolor="0.8", edgecolor="k",
                               hatch="///", lw=0.8, zorder=1))
        mu = model.scene.contact.friction if model.scene.contact else float("nan")
        handles.append(Patch(facecolor="0.8", edgecolor="k", hatch="///",
                             label=f"rigid rough base, μ = {mu:g}"))
    for itf in model.scene.interfaces:
        if not itf.bonded:
            r = int(model.layer_rows[itf.index][1]) - 0.5
            xs = np.array([-0.5, nx - 0.5]) * a + model.shear * a * r
            ax.plot(xs, [a * r, a * r], color="red", lw=2.0, ls="-.", zorder=4)
            handles.append(Line2D([], [], color="red", lw=2.0, ls="-.",
                                  label=f"frictional interface above {itf.below}, μ = {itf.friction:g}"))

    xs = model.positions(0, 1)[:, 0]
    xt = model.positions(ny - 1, ny)[:, 0]
    ax.set_xlim(min(xs.min(), xt.min()) - a, max(xs.max(), xt.max()) + a)
    ax.set_ylim(-1.0 * a, a * (ny - 1) + a)
    ax.set_aspect("equal")
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    name = title or model.scene.title or (Path(model.scene.source).stem if model.scene.source else "lattice")
    ax.set_title(f"{name}: {nx} × {ny} nodes, {model.n_dofs:,} DOFs"
                 + (f", shear {model.shear:g}" if model.shear else ""))
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    fig.tight_layout()
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp.png")
    try:
        fig.savefig(tmp, dpi=dpi, bbox_inches="tight")
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
    return path
