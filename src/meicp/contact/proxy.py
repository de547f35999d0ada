"""Contact-strip proxies of a scene (docs/flutter.md §4): a small lattice cut around its one
sliding contact line — the base strip, or the strip around one frictional interface — whose
dense spectrum tells the large-scale searches where to start: the flutter searches' targets
(:mod:`.flutter_proxy`) and the divergence search's first shift (:func:`rightmost_real`).
A shallow scene also has the same strip with every row (:func:`proxy_of` ``whole_depth``):
its fastest flutter modes may span the depth.
The modes that matter there are localised at the contact (slip waves, a sliding layer's
buckling), so their σ hardly depends on the lattice's size."""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.linalg as sl

from ..core.errors import ProblemError
from .lines import BASE, ContactState, state_names
from .problem import pencil

#: contact-strip proxy: columns and rows, and the rows next to the contact (a mode localised
#: there is the proxy's contact mode)
PROXY_NX = 32
PROXY_ROWS = 8
PROXY_NEAR_ROWS = 3
#: a scene of at most this many node rows also gets a proxy of its whole depth
#: (:func:`proxy_of` ``whole_depth``; 32 × 24 nodes: about 1,500 DOFs, a few seconds of dense QR)
DEPTH_PROXY_ROWS = 24


def _take_rows(layers, budget: int) -> list:
    """The layers met in order, each cut to the rows left of ``budget``, until it is spent."""
    kept, left = [], budget
    for layer in layers:
        if left <= 0:
            break
        kept.append(dataclasses.replace(layer, rows=min(layer.rows, left)))
        left -= kept[-1].rows
    return kept


def strip_proxy(scene, base_states, rows: int = PROXY_ROWS):
    """The contact-strip proxy: the bottom ``rows`` rows (the cut held fixed; ``rows`` ≥ the
    scene's: the whole depth, the scene's own boundary) and :data:`PROXY_NX` columns from the
    middle of the base, with the base's resolved states.  None when the scene has no base
    contact, a frictional interface or an embedded band."""
    if scene.contact is None or scene.embedded or any(i.kind == "frictional" for i in scene.interfaces):
        return None
    nx = min(scene.nx, PROXY_NX)
    kept = _take_rows(scene.layers, rows)
    cut = sum(layer.rows for layer in kept) < scene.ny
    start = (len(base_states) - nx) // 2
    return dataclasses.replace(
        scene, lattice=dataclasses.replace(scene.lattice, nx=nx), layers=tuple(kept),
        interfaces=tuple(i for i in scene.interfaces if i.index < len(kept) - 1),
        boundary=dataclasses.replace(scene.boundary, top="fixed") if cut else scene.boundary,
        contact=dataclasses.replace(scene.contact, states=tuple(state_names(base_states[start:start + nx]))))


def _shallow(scene) -> bool:
    """More node rows than the strip's :data:`PROXY_ROWS` and at most :data:`DEPTH_PROXY_ROWS`:
    a scene whose fastest flutter modes may span its depth, not the rows next to the contact."""
    return PROXY_ROWS < scene.ny <= DEPTH_PROXY_ROWS


def sliding_window(states, width: int) -> int:
    """The first column of the ``width`` consecutive contacts with the most slipping ones (the
    middlemost such window): where a proxy of a partly sticking contact line is cut."""
    sliding = np.array([ContactState(s).slip_sign != 0 for s in states], dtype=int)
    counts = np.convolve(sliding, np.ones(width, dtype=int), mode="valid")
    best = np.flatnonzero(counts == counts.max())
    middle = (len(states) - width) / 2
    return int(best[np.argmin(np.abs(best - middle))])


def interface_proxy(scene, line, side: int = PROXY_ROWS // 2):
    """The interface-strip proxy of a frictional interface ``line`` (states resolved): the
    ``side`` rows on each side of it (a cut held fixed; ``side`` ≥ the scene's rows: the whole
    depth, the scene's own boundary) and :data:`PROXY_NX` columns where most of its contacts
    slip, with their states.  None when the scene has a rigid base contact, an embedded band,
    or another frictional interface within those rows."""
    if scene.contact is not None or scene.embedded:
        return None
    index = next(i.index for i in scene.interfaces if i.kind == "frictional" and i.below == line.name)
    below = _take_rows(reversed(scene.layers[:index + 1]), side)[::-1]
    above = _take_rows(scene.layers[index + 1:], side)
    first = index + 1 - len(below)  # the scene's index of the proxy's first layer
    kept = tuple(below + above)
    interfaces = tuple(dataclasses.replace(i, index=i.index - first) for i in scene.interfaces
                       if first <= i.index < first + len(kept) - 1)
    if sum(i.kind == "frictional" for i in interfaces) != 1:
        return None
    nx = min(scene.nx, PROXY_NX)
    start = sliding_window(line.states, nx)
    states = tuple(state_names(line.states[start:start + nx]))
    interfaces = tuple(dataclasses.replace(i, states=states) if i.index == index - first else i for i in interfaces)
    cut_below = sum(layer.rows for layer in below) < sum(layer.rows for layer in scene.layers[:index + 1])
    cut_above = sum(layer.rows for layer in above) < sum(layer.rows for layer in scene.layers[index + 1:])
    boundary = dataclasses.replace(scene.boundary, bottom="fixed" if cut_below else scene.boundary.bottom,
                                   top="fixed" if cut_above else scene.boundary.top)
    return dataclasses.replace(scene, lattice=dataclasses.replace(scene.lattice, nx=nx), layers=kept,
                               interfaces=interfaces, boundary=boundary, load=None)


def proxy_of(scene, lines, *, whole_depth: bool = False):
    """(proxy scene, its rows next to the contact) for the one sliding contact line of a scene,
    or (None, None): the base strip, else the strip around the one sliding frictional
    interface.  ``whole_depth``: the same strip with every row of a shallow scene
    (:func:`_shallow`; (None, None) for others) — its fastest flutter modes may span the depth."""
    if whole_depth and not _shallow(scene):
        return None, None
    sliding = [line for line in lines if any(ContactState(s).slip_sign for s in line.states)]
    base = next((line for line in lines if line.name == BASE), None)
    if base is not None:
        rows = scene.ny if whole_depth else PROXY_ROWS
        proxy = strip_proxy(scene, list(base.states), rows)
        return proxy, (None if proxy is None else np.arange(min(PROXY_NEAR_ROWS, proxy.ny)))
    if len(sliding) != 1:
        return None, None
    proxy = interface_proxy(scene, sliding[0], scene.ny if whole_depth else PROXY_ROWS // 2)
    if proxy is None:
        return None, None
    index = next(i.index for i in proxy.interfaces if i.kind == "frictional")
    top_of_lower = sum(layer.rows for layer in proxy.layers[:index + 1])
    # a shallow scene's strip may have fewer rows on either side than PROXY_NEAR_ROWS
    return proxy, np.arange(max(top_of_lower - PROXY_NEAR_ROWS + 1, 0), min(top_of_lower + PROXY_NEAR_ROWS - 1, proxy.ny))


#: a proxy's real σ counts as above 0 beyond this multiple of max|A|/max|B| (a free lattice's
#: rigid motion comes out at ±1e-14 of that scale)
POSITIVE = 1e-8


def rightmost_real(scene, lines) -> float | None:
    """The largest real eigenvalue σ > 0 (beyond :data:`POSITIVE`) of the proxy's sliding
    pencil (A, B) — its fastest divergence-like mode (dense, serial: a few hundred DOFs); 0.0
    when it has no real σ above 0 (a free top's rigid motion at rounding level included) and
    every contact in it slides, as on every scene where that was measured; None without an
    estimate (no proxy, a grazing, sticking or separated contact in it, a failed eigen-solve).  A damped
    scene's proxy gives its undamped pencil's.  Where the divergence search starts, or whether
    a short one is made at all, never a proof of anything; on several ranks the caller
    computes it on one (:func:`~meicp.contact.on_root.on_root`): what it gives must be the
    same on all."""
    proxy, _ = proxy_of(scene, lines)
    if proxy is None or any(ContactState.GRAZING in line.states for line in lines):
        return None  # a grazing contact's proxy needs a case per tangential choice: no estimate
    try:
        with pencil(proxy) as pen:
            if pen.A is None:
                return None
            A, B = pen.A.toarray(), pen.B.toarray()
        with np.errstate(all="ignore"):
            values = sl.eigvals(A, B)
    except (ProblemError, np.linalg.LinAlgError, ValueError):
        return None
    values = values[np.isfinite(values)]
    if not values.size or not np.all(np.isfinite(A)):
        return None
    real = values.real[np.abs(values.imag) <= 1e-8 * np.maximum(1.0, np.abs(values))]
    top = float(real.max(initial=0.0))
    scale = np.abs(A).max() / max(np.abs(B).max(), 1e-300)
    if top > POSITIVE * scale:
        return top
    return 0.0 if _all_sliding(proxy) else None


def _all_sliding(proxy) -> bool:
    """Every contact of the proxy's one contact line slides (its base, or its frictional
    interface)."""
    if proxy.contact is not None:
        states = proxy.contact.states
    else:
        states = next(i.states for i in proxy.interfaces if i.kind == "frictional")
    return isinstance(states, tuple) and all(ContactState(s).slip_sign != 0 for s in states)


__all__ = ["DEPTH_PROXY_ROWS", "PROXY_NEAR_ROWS", "PROXY_NX", "PROXY_ROWS", "interface_proxy", "proxy_of",
           "rightmost_real", "sliding_window", "strip_proxy"]
