"""Contact-strip proxies of a scene (docs/flutter.md §4): a small lattice cut around its one
sliding contact line — the base strip, or the strip around one frictional interface —
whose dense flutter modes give the large-scale search its targets (the fastest modes are
slip waves along the contact, whose σ hardly depends on the lattice's size)."""

from __future__ import annotations

import dataclasses

import numpy as np

from .damped import damped_flutter
from .flutter_dense import dense_flutter
from .flutter_verdict import PencilFlutter
from .lines import BASE, ContactState, state_names
from .problem import pencil

#: the search's targets per scene (below limits.FLUTTER_SEARCH_LARGE retained DOFs)
SEARCH_TARGETS = 3
#: contact-strip proxy: columns, rows, and the share of a proxy mode's energy in the rows
#: next to the contact for it to count as contact-localised
PROXY_NX = 32
PROXY_ROWS = 8
PROXY_LOCALISED = 0.6
PROXY_NEAR_ROWS = 3
#: a target whose pairs all fail the residual gate sits inside a cluster of ill-conditioned
#: flutter eigenvalues (shift-and-invert then returns pseudo-pairs next to it); it is moved up
#: off the cluster by OFF_CLUSTER·max(Im τ, 0.05|τ|) per try, at most OFF_CLUSTER_TRIES times:
#: one such move certified the cluster's top edge where it was measured
#: (docs/benchmarks-notes.md, "OFF_CLUSTER")
OFF_CLUSTER = 0.5
OFF_CLUSTER_TRIES = 1
#: the targets where a scene has no proxy or its proxy no flutter mode: the λ-line Re λ = LINE_GROWTH at the angular
#: frequencies LINE_FREQUENCIES (σ = λ² for the undamped search)
LINE_GROWTH = 0.05
LINE_FREQUENCIES = (0.5, 1.5, 2.5)
LINE_WHY = (f" on the λ-line Re λ = {LINE_GROWTH:g}, ω = " + ", ".join(f"{w:g}" for w in LINE_FREQUENCIES)
            + " (the scene has no proxy, or its proxy no flutter mode)")


def off_cluster(tau: complex, attempt: int) -> complex:
    """The target tried after ``attempt`` + 1 failed ones at ``tau``: moved up, away from the
    real axis, by OFF_CLUSTER·max(Im τ, 0.05|τ|)·2^attempt (the fastest flutter modes of a
    cluster are those of largest Im σ, on its top edge)."""
    return tau + 1j * OFF_CLUSTER * max(tau.imag, 0.05 * abs(tau)) * 2 ** attempt


def _take_rows(layers, budget: int) -> list:
    """The layers met in order, each cut to the rows left of ``budget``, until it is spent."""
    kept, left = [], budget
    for layer in layers:
        if left <= 0:
            break
        kept.append(dataclasses.replace(layer, rows=min(layer.rows, left)))
        left -= kept[-1].rows
    return kept


def strip_proxy(scene, base_states):
    """The contact-strip proxy: the bottom :data:`PROXY_ROWS` rows (the cut held fixed) and
    :data:`PROXY_NX` columns from the middle of the base, with the base's resolved states.
    None when the scene has no base contact, a frictional interface or an embedded band."""
    if scene.contact is None or scene.embedded or any(i.kind == "frictional" for i in scene.interfaces):
        return None
    nx = min(scene.nx, PROXY_NX)
    kept = _take_rows(scene.layers, PROXY_ROWS)
    cut = sum(layer.rows for layer in kept) < scene.ny
    start = (len(base_states) - nx) // 2
    return dataclasses.replace(
        scene, lattice=dataclasses.replace(scene.lattice, nx=nx), layers=tuple(kept),
        interfaces=tuple(i for i in scene.interfaces if i.index < len(kept) - 1),
        boundary=dataclasses.replace(scene.boundary, top="fixed") if cut else scene.boundary,
        contact=dataclasses.replace(scene.contact, states=tuple(state_names(base_states[start:start + nx]))))


def sliding_window(states, width: int) -> int:
    """The first column of the ``width`` consecutive contacts with the most slipping ones (the
    middlemost such window): where a proxy of a partly sticking contact line is cut."""
    sliding = np.array([ContactState(s).slip_sign != 0 for s in states], dtype=int)
    counts = np.convolve(sliding, np.ones(width, dtype=int), mode="valid")
    best = np.flatnonzero(counts == counts.max())
    middle = (len(states) - width) / 2
    return int(best[np.argmin(np.abs(best - middle))])


def interface_proxy(scene, line):
    """The interface-strip proxy of a frictional interface ``line`` (states resolved): the
    :data:`PROXY_ROWS` // 2 rows on each side of it (a cut held fixed) and :data:`PROXY_NX`
    columns where most of its contacts slip, with their states.  None when the scene has a
    rigid base contact, an embedded band, or another frictional interface within those rows."""
    if scene.contact is not None or scene.embedded:
        return None
    index = next(i.index for i in scene.interfaces if i.kind == "frictional" and i.below == line.name)
    below = _take_rows(reversed(scene.layers[:index + 1]), PROXY_ROWS // 2)[::-1]
    above = _take_rows(scene.layers[index + 1:], PROXY_ROWS // 2)
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


def _proxy_of(scene, lines):
    """(proxy scene, its rows next to the contact) for the one sliding contact line of a scene,
    or (None, None): the base strip, else the strip around the one sliding frictional
    interface."""
    sliding = [line for line in lines if any(ContactState(s).slip_sign for s in line.states)]
    base = next((line for line in lines if line.name == BASE), None)
    if base is not None:
        return strip_proxy(scene, list(base.states)), np.arange(PROXY_NEAR_ROWS)
    if len(sliding) != 1:
        return None, None
    proxy = interface_proxy(scene, sliding[0])
    if proxy is None:
        return None, None
    index = next(i.index for i in proxy.interfaces if i.kind == "frictional")
    top_of_lower = sum(layer.rows for layer in proxy.layers[:index + 1])
    return proxy, np.arange(top_of_lower - PROXY_NEAR_ROWS + 1, top_of_lower + PROXY_NEAR_ROWS - 1)


def proxy_targets(scene, lines, count: int = SEARCH_TARGETS, *, with_verdict: bool = False):
    """Up to ``count`` targets: σ of the proxy's fastest contact-localised flutter modes, at
    least 0.1|σ| apart (all its modes when none is localised); [] without a proxy.  ``lines``:
    the scene's contact lines with their states resolved (a pencil's ``lines``).  A damped
    scene's proxy is damped too: its modes are those of its quadratic pencil (σ = λ²).
    ``with_verdict``: ``(targets, flutter)``, flutter the proxy's own dense verdict (None
    also without a proxy)."""
    proxy, near = _proxy_of(scene, lines)
    if proxy is None:
        return ([], None) if with_verdict else []
    with pencil(proxy) as pen:  # a lattice of its own, PROXY_NX × PROXY_ROWS, serial
        red = pen.maps
        if pen.A is None:
            found = PencilFlutter(False)
        else:
            # small by construction: dense whatever FLUTTER_DENSE_MAX says, as dense_flutter is
            found = (damped_flutter(pen, dense_max=pen.maps.retained.size) if pen.damped
                     else dense_flutter(pen.A, pen.B))

    def near_contact(x):
        energy = (np.abs(red.Q @ x) ** 2).reshape(proxy.ny, proxy.nx, 2).sum(axis=(1, 2))
        return energy[near].sum() / energy.sum()

    candidates = [m for m in found.modes if near_contact(m.x) >= PROXY_LOCALISED] or found.modes
    targets = []
    for m in candidates:
        if all(abs(m.sigma - t) > 0.1 * abs(t) for t in targets):
            targets.append(m.sigma)
        if len(targets) == count:
            break
    return (targets, found.flutter) if with_verdict else targets
