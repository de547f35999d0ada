"""The flutter searches' targets from a scene's contact-strip proxy (:mod:`.proxy`; docs/flutter.md
§4): its dense flutter modes localised at the contact (slip waves along it, whose σ hardly
depends on the lattice's size), those of its whole depth on a shallow scene, and where a
search goes when a target fails."""

from __future__ import annotations

import numpy as np

from ..core import limits
from .damped import damped_flutter
from .flutter_dense import dense_flutter
from .flutter_verdict import PencilFlutter
from .problem import pencil
from .proxy import proxy_of
from .result import growth_frequency

#: the search's targets per scene (below limits.FLUTTER_SEARCH_LARGE retained DOFs)
SEARCH_TARGETS = 3
#: the share of a proxy mode's energy in the rows next to the contact (PROXY_NEAR_ROWS) for it
#: to count as contact-localised
PROXY_LOCALISED = 0.6
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


def depth_used(n: int) -> bool:
    """Whether the search of a pencil of ``n`` retained DOFs takes the whole-depth proxy's
    targets (already moved up off their cluster): below ``limits.FLUTTER_OFF_CLUSTER_FROM``,
    from where every target is moved up anyway (a shallow scene that large was not measured)."""
    return n < limits.FLUTTER_OFF_CLUSTER_FROM


def depth_note(scene, lines, n: int) -> str:
    """The evidence's words on the whole-depth proxy's targets, "" when there are none."""
    if not depth_used(n) or proxy_of(scene, lines, whole_depth=True)[0] is None:
        return ""
    return f" and its whole depth ({scene.ny} rows; those targets moved up off their cluster)"


def _growth(mode) -> float:
    return growth_frequency(mode.sigma)[0]


def _dense_modes(proxy) -> tuple[PencilFlutter, object]:
    """The proxy's own dense flutter analysis and its reduced system (a lattice of its own,
    serial, small by construction: dense whatever FLUTTER_DENSE_MAX says).  A damped scene's
    proxy is damped too: its modes are those of its quadratic pencil (σ = λ²)."""
    with pencil(proxy) as pen:
        if pen.A is None:
            return PencilFlutter(False), pen.maps
        found = damped_flutter(pen, dense_max=pen.maps.retained.size) if pen.damped else dense_flutter(pen.A, pen.B)
        return found, pen.maps


def proxy_targets(scene, lines, count: int = SEARCH_TARGETS, *, with_verdict: bool = False, depth: bool = True):
    """Up to ``count`` targets, at least 0.1|σ| apart: σ of the proxy's fastest
    contact-localised flutter modes (all its modes when none is localised), and for a shallow
    scene the fastest modes of its whole-depth proxy (:func:`~.proxy.proxy_of`) moved up
    off their cluster (:func:`off_cluster`) — the fastest of all first, by the proxies'
    growth; [] without a proxy.  ``lines``: the scene's contact lines with their states
    resolved (a pencil's ``lines``).  ``with_verdict``: ``(targets, flutter)``, flutter the
    strip proxy's own dense verdict (None also without a proxy).  ``depth=False``: the strip
    proxy's targets alone (the benchmark's comparison)."""
    proxy, near = proxy_of(scene, lines)
    if proxy is None:
        return ([], None) if with_verdict else []
    found, red = _dense_modes(proxy)

    def near_contact(x):
        energy = (np.abs(red.Q @ x) ** 2).reshape(proxy.ny, proxy.nx, 2).sum(axis=(1, 2))
        return energy[near].sum() / energy.sum()

    # (growth of the proxy's mode, target): the strip's modes where they are
    candidates = [(_growth(m), m.sigma) for m in
                  ([m for m in found.modes if near_contact(m.x) >= PROXY_LOCALISED] or found.modes)]
    whole = proxy_of(scene, lines, whole_depth=True)[0] if depth else None
    if whole is not None:
        # a shallow lattice's fastest modes can span its depth (issue 29: three layers of 6
        # rows, the strip's one target at growth 0.0045, the lattice's fastest 0.0154 near the
        # whole-depth proxy's 0.0080 — found from above it, not from it: docs/flutter.md §4)
        deep, _ = _dense_modes(whole)
        candidates += [(_growth(m), off_cluster(m.sigma, 0)) for m in deep.modes]
    candidates.sort(key=lambda c: -c[0])
    targets = []
    for _, sigma in candidates:
        if all(abs(sigma - t) > 0.1 * abs(t) for t in targets):
            targets.append(sigma)
        if len(targets) == count:
            break
    return (targets, found.flutter) if with_verdict else targets
