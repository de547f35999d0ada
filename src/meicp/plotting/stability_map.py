"""The stability map of a sweep (:func:`plot_stability_map`): the growth rates of divergence
and flutter against the parameter swept, each value's verdicts marked, and the onsets shaded
as the brackets the grid gives.  Drawn on Matplotlib's Agg canvas (no pyplot)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..core.errors import ProblemError
from .lattice import _save

#: the longest title drawn (a scene title may be any length)
TITLE_CHARS = 90
COLOURS = {"divergence": "C0", "flutter": "C1"}


def _array(values) -> np.ndarray:
    return np.array([np.nan if v is None else float(v) for v in values], dtype=float)


def plot_stability_map(path, values, *, divergence, growth, flutter, flutter_growth, flutter_bound=None,
                       onsets=(), xlabel: str = "parameter", title: str = "", marks=(), dpi: int = 130) -> Path:
    """Draw a sweep's stability map to the PNG ``path``.

    Parameters
    ----------
    path : str or Path
        The PNG to write (its directory must exist).
    values : sequence of float
        The parameter's values, one per point.
    divergence, flutter : sequence of bool or None
        Each point's verdicts (None: undecided).
    growth : sequence of float or None
        λ = √σ of the fastest divergence mode (None without one).
    flutter_growth, flutter_bound : sequence of float or None
        Re λ of the fastest flutter mode found (a lower bound), and an upper bound on every
        flutter mode's Re λ where one is proved.
    onsets : sequence of (kind, lower, upper, name)
        Brackets to shade: ``kind`` "divergence" or "flutter", ``lower`` None when open.
    marks : sequence of (value, label)
        Extra vertical lines (e.g. a certified critical friction).

    Returns
    -------
    Path
        ``path``.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    path = Path(path)
    if not path.parent.is_dir():
        raise ProblemError(f"output directory {str(path.parent)!r} does not exist")
    x = _array(values)
    order = np.argsort(x)
    x = x[order]
    div = [divergence[k] for k in order]
    flu = [flutter[k] for k in order]
    # a verdict proved absent draws at 0; certified draws its growth; undecided leaves a gap
    g_div = np.array([0.0 if d is False else g for d, g in zip(div, _array(growth)[order])])
    g_flu = np.array([0.0 if f is False else g for f, g in zip(flu, _array(flutter_growth)[order])])
    bound = _array(flutter_bound if flutter_bound is not None else [None] * len(x))[order]

    fig = Figure(figsize=(8.5, 4.8))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    ax.plot(x, g_div, "o-", ms=3.5, color=COLOURS["divergence"],
            label="divergence: growth λ = √σ of the fastest mode found (0: proved absent)")
    # filled: the whole spectrum bounds every flutter mode's growth by the one found (it is the
    # fastest); hollow: the fastest *found*, a lower bound
    proved = np.isfinite(bound)
    ax.plot(x, g_flu, "-", color=COLOURS["flutter"])
    ax.plot(x[proved], g_flu[proved], "s", ms=3.5, color=COLOURS["flutter"],
            label="flutter: growth Re λ of the fastest mode (0: proved absent)")
    if (~proved).any():
        ax.plot(x[~proved], g_flu[~proved], "s", ms=4, mfc="none", color=COLOURS["flutter"],
                label="flutter: growth of the fastest mode found (a lower bound)")
    top = np.nanmax(np.concatenate([g_div, g_flu, [0.0]]))
    above = proved & (np.isnan(g_flu) | (bound > g_flu + 1e-3 * max(top, 1e-300)))
    if above.any():
        ax.plot(x[above], bound[above], "v", ms=4, color=COLOURS["flutter"], alpha=0.6,
                label="flutter: proved upper bound on the growth (rounding)")
    for kind, flags, y in (("divergence", div, g_div), ("flutter", flu, g_flu)):
        undecided = np.array([f is None for f in flags])
        if undecided.any():
            ax.plot(x[undecided], np.zeros(undecided.sum()), "x", ms=6, color=COLOURS[kind],
                    label=f"{kind} undecided")
    for kind, lower, upper, name in onsets:
        left = x[0] if lower is None else lower
        ax.axvspan(left, upper, color=COLOURS[kind], alpha=0.12, lw=0)
        ax.axvline(upper, color=COLOURS[kind], ls=":", lw=1)
        text = f"{name} ≤ {upper:.4g}" if lower is None else f"{name} ∈ ({lower:.4g}, {upper:.4g}]"
        ax.plot([], [], color=COLOURS[kind], alpha=0.3, lw=6, label=f"{text} (bracket from the grid)")
    for k, (value, label) in enumerate(marks):
        ax.axvline(value, color="0.3", ls=("--", "-.", ":")[k % 3], lw=1, label=label)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("growth rate (1/time)")
    if len(title) > TITLE_CHARS:
        title = title[:TITLE_CHARS - 1] + "…"
    ax.set_title(title, fontsize=10)
    ax.set_ylim(bottom=min(0.0, ax.get_ylim()[0]))
    ax.legend(fontsize=7.5, loc="upper left")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return _save(fig, path, dpi)
