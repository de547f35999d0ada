"""Pictures of the lattice: layers coloured, bonds, boundary conditions and contacts
(:func:`plot_lattice`); a divergence mode on the deformed lattice (:func:`plot_mode`);
contact states and forces along each contact line (:func:`plot_contacts`).

Drawn with Matplotlib's Agg canvas directly (no pyplot, no global backend change).  Small
lattices show every bond and node; large ones (more than ``max_bonds`` bonds) show each
layer and embedded band as a filled region, so the picture costs the same at 10^6 DOFs.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..core.errors import ProblemError
from ..lattice.assembly import as_model
from ..lattice.model import LatticeModel

INTERFACE_COLOUR = "0.35"
#: characters of a scene's title shown in a picture's heading, and of a layer's name in a
#: legend: a scene file may hold megabytes of title, and Matplotlib sizes the canvas to its
#: text (a 10 kB title asked for a 124,492-pixel-wide image and failed; 3 MB never finished)
TITLE_CHARACTERS = 120
NAME_CHARACTERS = 40


def plain(text, limit: int = TITLE_CHARACTERS) -> str:
    """Text from a scene as Matplotlib should draw it: on one line, at most ``limit``
    characters (cut with "…"), and ``$`` drawn as itself rather than starting mathtext (an
    unbalanced or bad formula in a title raised ValueError while saving)."""
    text = " ".join(str(text).split())
    if len(text) > limit:
        text = text[:limit - 1] + "…"
    return text.replace("$", r"\$")


def _corners(model: LatticeModel, j0: float, j1: float, i0: float, i1: float) -> np.ndarray:
    """Parallelogram covering node rows j0..j1 and columns i0..i1 (inclusive), half a spacing out."""
    a, s = model.spacing, model.shear
    pts = []
    for i, j in ((i0 - 0.5, j0 - 0.5), (i1 + 0.5, j0 - 0.5), (i1 + 0.5, j1 + 0.5), (i0 - 0.5, j1 + 0.5)):
        pts.append((a * (i + s * j), a * j))
    return np.array(pts)


def plot_lattice(scene, path, *, title: str | None = None, max_bonds: int = 60000,
                 dpi: int = 150) -> Path:
    """Draw the lattice of ``scene`` (a Scene or a LatticeModel) to the PNG ``path``."""
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

    handles = [Patch(facecolor=colours[k], label=f"{plain(m.name, NAME_CHARACTERS)}: k = {m.stiffness:g}, "
                     f"ρ = {m.density:g}" + (" (embedded)" if m.kind == "embedded" else ""))
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
                                  label=f"frictional interface above {plain(itf.below, NAME_CHARACTERS)}, "
                                        f"μ = {itf.friction:g}"))

    xs = model.positions(0, 1)[:, 0]
    xt = model.positions(ny - 1, ny)[:, 0]
    ax.set_xlim(min(xs.min(), xt.min()) - a, max(xs.max(), xt.max()) + a)
    ax.set_ylim(-1.0 * a, a * (ny - 1) + a)
    ax.set_aspect("equal")
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    name = _scene_name(model, title)
    ax.set_title(f"{name}: {nx} × {ny} nodes, {model.n_dofs:,} DOFs"
                 + (f", shear {model.shear:g}" if model.shear else ""))
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    fig.tight_layout()
    return _save(fig, path, dpi)


# --------------------------------------------------------------------------- mode shapes

#: contact states (docs/design.md §7.1): marker, colour and legend label used by every plot
STATE_STYLE = {
    "stick": ("s", "tab:blue", "stick"),
    "slip+": (">", "tab:red", "slip+ (impending slip in +x)"),
    "slip-": ("<", "tab:orange", "slip− (impending slip in −x)"),
    "separated": ("o", "0.55", "separated"),
    "grazing": ("D", "tab:purple", "grazing"),
}


def display_scale(scene, x, fraction: float = 0.15) -> float:
    """The factor ``s`` that makes the largest node displacement of ``s·x`` equal to
    ``fraction`` of the lattice height (one spacing for a single row); 0 for a zero mode."""
    model = as_model(scene)
    disp = np.asarray(x, dtype=float).reshape(model.n_nodes, 2)
    peak = float(np.sqrt((disp ** 2).sum(axis=1)).max()) if disp.size else 0.0
    height = model.spacing * max(model.ny - 1, 1)
    return fraction * height / peak if peak > 0 and np.isfinite(peak) else 0.0


def _wire(model: LatticeModel, max_bonds: int):
    """Node pairs to draw and the material of each: every bond of a small lattice; for a
    large one, the rows and columns of a subsampled grid (about 100 lines each way), so the
    picture costs the same at 10^6 DOFs."""
    if 4 * model.nx * model.ny <= max_bonds:
        ends, _, _ = model.bonds()
        mat = model.material()
        same = mat[ends[:, 0]] == mat[ends[:, 1]]
        return ends, mat[ends[:, 0]], same, True
    nx, ny = model.nx, model.ny
    si, sj = max(1, nx // 100), max(1, ny // 100)
    cols = np.unique(np.r_[np.arange(0, nx, si), nx - 1])
    rows = np.unique(np.r_[np.arange(0, ny, sj), ny - 1])
    pairs = []
    for j in rows:  # horizontal polylines through the sampled columns
        a = j * nx + cols
        pairs.append(np.stack([a[:-1], a[1:]], axis=1))
    cut = np.flatnonzero(model.cut_above)
    for i in cols:  # vertical polylines, broken at frictional interfaces
        r = np.unique(np.r_[rows, cut, cut + 1])
        r = r[r < ny]
        a, b = r[:-1], r[1:]
        keep = ~((b == a + 1) & model.cut_above[a])
        pairs.append(np.stack([a[keep] * nx + i, b[keep] * nx + i], axis=1))
    ends = np.concatenate(pairs).astype(np.int64)
    mat = model.material()
    return ends, mat[ends[:, 0]], mat[ends[:, 0]] == mat[ends[:, 1]], False


def _save(fig, path: Path, dpi: int) -> Path:
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp.png")
    try:
        fig.savefig(tmp, dpi=dpi, bbox_inches="tight")
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
    return path


def _scene_name(model: LatticeModel, title):
    s = model.scene
    return plain(title or s.title or (Path(s.source).stem if s.source else "lattice"))


def plot_mode(scene, path, mode=None, *, stable: bool | None = None, title: str | None = None,
              fraction: float = 0.15, n_modes: int | None = None, max_bonds: int = 60000,
              dpi: int = 150, heading: str | None = None) -> Path:
    """Draw a divergence mode on the deformed lattice to the PNG ``path``.

    ``mode``: anything with ``sigma``, ``growth_rate``, ``x`` (natural numbering, length
    n_dofs), ``support`` and optionally ``interface_support`` (a :class:`~meicp.contact.result.Mode`),
    or None.  The reference lattice is drawn faint, the deformed one ``reference + s·x``
    coloured by material, with ``s`` = :func:`display_scale` (largest displacement =
    ``fraction`` of the lattice height); the contact nodes whose slip is active in the mode
    are ringed.  Without a mode: the reference lattice, titled "stable" (``stable=True``) or
    "no certified mode" otherwise.  ``heading``: what the mode is, instead of "fastest
    divergence mode, σ = ..." (a flutter mode's real part, for instance).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.collections import LineCollection
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch, Rectangle

    model = as_model(scene)
    path = Path(path)
    if not path.parent.is_dir():
        raise ProblemError(f"output directory {str(path.parent)!r} does not exist")
    a, nx = model.spacing, model.nx
    colours = [f"C{k % 10}" for k in range(len(model.materials))]
    ref = model.positions()
    disp = np.zeros_like(ref)
    scale = 0.0
    if mode is not None:
        x = np.asarray(mode.x, dtype=float)
        if x.shape != (model.n_dofs,):
            raise ProblemError(f"mode shape has shape {x.shape}, expected ({model.n_dofs},)")
        scale = display_scale(model, x, fraction)
        disp = scale * x.reshape(-1, 2)
    cur = ref + disp
    ends, seg_mat, same, detailed = _wire(model, max_bonds)

    allpts = np.concatenate([ref, cur])
    lo, hi = allpts.min(axis=0), allpts.max(axis=0)
    width = hi[0] - lo[0] + 2 * a
    height = hi[1] - lo[1] + 2.5 * a
    fig_w = 10.0
    fig_h = float(np.clip(0.6 * fig_w * height / width + 1.4, 2.8, 11.0))
    fig = Figure(figsize=(fig_w, fig_h))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    lw = 1.2 if ends.shape[0] < 2000 else 0.5
    handles = []
    if mode is not None:
        ax.add_collection(LineCollection(ref[ends], colors="0.75", linewidths=0.6 * lw,
                                         linestyles="-", alpha=0.8, zorder=1))
        handles.append(Line2D([], [], color="0.75", lw=0.8, label="reference lattice"))
    seg_colours = [colours[m] if ok else INTERFACE_COLOUR for m, ok in zip(seg_mat, same)]
    ax.add_collection(LineCollection(cur[ends], colors=seg_colours, linewidths=lw, zorder=2))
    if detailed and model.n_nodes <= 5000:
        mat = model.material()
        ax.scatter(cur[:, 0], cur[:, 1], s=max(2.0, min(24.0, 3000.0 / model.n_nodes)),
                   c=[colours[m] for m in mat], edgecolors="k", linewidths=0.3, zorder=3)
    handles += [Patch(facecolor=colours[k], label=f"{plain(m.name, NAME_CHARACTERS)}: k = {m.stiffness:g}, "
                                                  f"ρ = {m.density:g}")
                for k, m in enumerate(model.materials)]
    if not np.all(same):
        handles.append(Line2D([], [], color=INTERFACE_COLOUR, label="bond between materials"))
    for itf in model.scene.frictional_interfaces():  # drawn where it is in the reference
        r = int(model.layer_rows[itf.index][1]) - 0.5
        xs = np.array([-0.5, nx - 0.5]) * a + model.shear * a * r
        ax.plot(xs, [a * r, a * r], color="red", lw=1.5, ls="-.", alpha=0.6, zorder=1)
        handles.append(Line2D([], [], color="red", lw=1.5, ls="-.", alpha=0.6,
                              label=f"frictional interface above {plain(itf.below, NAME_CHARACTERS)}, "
                                    f"μ = {itf.friction:g}"))
    if model.boundary.bottom == "contact":
        ax.add_patch(Rectangle((lo[0] - 0.5 * a, -0.75 * a), hi[0] - lo[0] + a, 0.45 * a,
                               facecolor="0.85", edgecolor="k", hatch="///", lw=0.8, zorder=0))
        mu = model.scene.contact.friction if model.scene.contact else float("nan")
        handles.append(Patch(facecolor="0.85", edgecolor="k", hatch="///",
                             label=f"rigid rough base, μ = {mu:g}"))
    if mode is not None:
        ring = [np.asarray(mode.support, dtype=np.int64).ravel()]
        for name, sup in (getattr(mode, "interface_support", None) or {}).items():
            try:
                k = model.scene.layer_index(name)
            except KeyError:
                continue
            _, upper = model.interface_node_pairs(k)
            ring.append(upper[np.asarray(sup, dtype=np.int64).ravel()])
        ring = np.concatenate(ring)
        if ring.size:
            ax.scatter(cur[ring, 0], cur[ring, 1], s=90, facecolors="none", edgecolors="red",
                       linewidths=1.4, zorder=4)
            handles.append(Line2D([], [], ls="", marker="o", mfc="none", mec="red", ms=9,
                                  label="sliding in this mode" if heading else "active slip in this mode"))
    ax.set_xlim(lo[0] - a, hi[0] + a)
    ax.set_ylim(min(lo[1], 0.0) - 1.0 * a, hi[1] + a)
    ax.set_aspect("equal")
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    name = _scene_name(model, title)
    if mode is not None:
        head = f"{name}: " + (heading or f"fastest divergence mode found, σ = {float(mode.sigma):.6g}, "
                                         f"growth rate λ = {mode.growth_rate:.6g}")
        sub = (f"deformed = reference + {scale:.3g}·x (largest displacement {100 * fraction:.0f}% "
               f"of the height)" if scale > 0 else "zero mode shape")
        if n_modes is not None and n_modes > 1:
            sub += f"; {n_modes} modes in all"
    elif stable:
        head, sub = f"{name}: stable", "no divergence mode (σ ≥ 0) from this contact state"
    else:
        head, sub = f"{name}: no certified divergence mode", "the search was inconclusive"
    ax.set_title(f"{head}\n{sub}", fontsize=10)
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    fig.tight_layout()
    return _save(fig, path, dpi)


# --------------------------------------------------------------------------- contact lines

@dataclass
class ContactLine:
    """What :func:`plot_contacts` draws for one contact line (the base or a frictional
    interface): per column, the state (None = unknown), the static forces and gap/slip
    when known (None otherwise), and the columns active in the fastest mode."""

    label: str
    friction: float
    states: list | None = None
    r_n: np.ndarray | None = None
    r_t: np.ndarray | None = None
    gap: np.ndarray | None = None
    slip: np.ndarray | None = None
    support: np.ndarray | None = None
    #: displacement scale (e.g. max |u| of the static solution): gap and slip below 1e-6 of
    #: it are round-off and the panel's range does not zoom in on them
    scale: float | None = None


def plot_contacts(scene, path, lines, *, title: str | None = None, dpi: int = 150) -> Path:
    """Contact states and forces along each contact line to the PNG ``path``.

    One band per line: the state of each column as coloured markers (x = column index; the
    columns active in the fastest mode ringed), and below it, when the static equilibrium is
    known, ``r_n``, ``r_t`` and the Coulomb cone ``|r_t| ≤ μ r_n`` (shaded), then the gap and
    the slip when known."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    model = as_model(scene)
    path = Path(path)
    if not path.parent.is_dir():
        raise ProblemError(f"output directory {str(path.parent)!r} does not exist")
    if not lines:
        raise ProblemError("plot_contacts needs at least one contact line")
    nx = model.nx
    cols = np.arange(nx)
    panels = []  # (line index, kind, height)
    for k, line in enumerate(lines):
        panels.append((k, "states", 1.0))
        if line.r_n is not None or line.r_t is not None:
            panels.append((k, "forces", 2.4))
        if line.gap is not None or line.slip is not None:
            panels.append((k, "kinematics", 1.6))
    heights = [h for _, _, h in panels]
    fig = Figure(figsize=(10.0, min(1.0 + 1.1 * sum(heights), 30.0)))
    FigureCanvasAgg(fig)
    axes = fig.subplots(len(panels), 1, sharex=True, squeeze=False,
                        gridspec_kw={"height_ratios": heights})[:, 0]
    ms = float(np.clip(2500.0 / nx, 4.0, 80.0))
    for ax, (k, kind, _) in zip(axes, panels):
        line = lines[k]
        if kind == "states":
            seen = []
            states = list(line.states) if line.states is not None else [None] * nx
            for state, (marker, colour, label) in STATE_STYLE.items():
                on = np.array([s == state for s in states], dtype=bool)
                if on.any():
                    ax.scatter(cols[on], np.zeros(on.sum()), marker=marker, s=ms, c=colour,
                               edgecolors="k", linewidths=0.4, zorder=3)
                    seen.append(Line2D([], [], ls="", marker=marker, color=colour, mec="k",
                                       label=f"{label} ×{int(on.sum())}"))
            unknown = np.array([s is None for s in states], dtype=bool)
            if unknown.any():
                ax.scatter(cols[unknown], np.zeros(unknown.sum()), marker="x", s=ms, c="0.4", zorder=3)
                seen.append(Line2D([], [], ls="", marker="x", color="0.4",
                                   label=f"state unknown ×{int(unknown.sum())}"))
            if line.support is not None and np.size(line.support):
                sup = np.asarray(line.support, dtype=np.int64).ravel()
                ax.scatter(sup, np.zeros(sup.size), s=3.2 * ms, facecolors="none", edgecolors="k",
                           linewidths=1.2, zorder=4)
                seen.append(Line2D([], [], ls="", marker="o", mfc="none", mec="k", ms=9,
                                   label=f"active in fastest mode ×{sup.size}"))
            ax.set_yticks([])
            ax.set_ylim(-1, 1)
            ax.set_title(f"{plain(line.label)}, μ = {line.friction:g}", fontsize=10, loc="left")
            ax.legend(handles=seen, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8,
                      frameon=False)
        elif kind == "forces":
            hs = []
            if line.r_n is not None:
                rn = np.asarray(line.r_n, dtype=float)
                env = line.friction * rn
                ax.fill_between(cols, -env, env, color="0.85", step=None, zorder=1)
                ax.plot(cols, env, color="0.45", ls="--", lw=0.9, zorder=2)
                ax.plot(cols, -env, color="0.45", ls="--", lw=0.9, zorder=2)
                ax.plot(cols, rn, color="tab:blue", marker="o", ms=3, lw=1.2, zorder=3)
                hs += [Line2D([], [], color="tab:blue", marker="o", ms=3, label="r_n (normal)"),
                       Line2D([], [], color="0.45", ls="--", label="±μ r_n (Coulomb cone)")]
            if line.r_t is not None:
                ax.plot(cols, np.asarray(line.r_t, dtype=float), color="tab:red", marker="s", ms=3,
                        lw=1.2, zorder=3)
                hs.append(Line2D([], [], color="tab:red", marker="s", ms=3, label="r_t (tangential)"))
            ax.axhline(0.0, color="k", lw=0.5)
            ax.set_ylabel("reaction")
            ax.legend(handles=hs, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
        else:
            hs = []
            if line.gap is not None:
                ax.plot(cols, np.asarray(line.gap, dtype=float), color="tab:green", marker="^", ms=3, lw=1.2)
                hs.append(Line2D([], [], color="tab:green", marker="^", ms=3, label="gap g"))
            if line.slip is not None:
                ax.plot(cols, np.asarray(line.slip, dtype=float), color="tab:purple", marker="v",
                        ms=3, lw=1.2)
                hs.append(Line2D([], [], color="tab:purple", marker="v", ms=3, label="slip"))
            ax.axhline(0.0, color="k", lw=0.5)
            vals = [np.abs(np.asarray(v, dtype=float)) for v in (line.gap, line.slip) if v is not None]
            peak = max((float(v.max()) for v in vals if v.size), default=0.0)
            floor = 1e-6 * (line.scale if line.scale else model.spacing)
            if peak < floor:
                ax.set_ylim(-floor, floor)
            ax.set_ylabel("displacement")
            ax.legend(handles=hs, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    axes[-1].set_xlabel("column i")
    axes[-1].set_xlim(-0.7, nx - 0.3)
    if nx <= 40:
        axes[-1].set_xticks(cols)
    fig.suptitle(f"{_scene_name(model, title)}: contact states" +
                 (" and forces" if any(p[1] == "forces" for p in panels) else ""), fontsize=11)
    fig.tight_layout()
    return _save(fig, path, dpi)
