"""Damped lattices (docs/damping.md, docs/design.md §7.4): the dense references of the
damped divergence and flutter verdicts, and the refusal of every path not built for damping.

With the lattice's damping C (Kelvin–Voigt dashpots per bond, plus ``α·M``), modes
``u = u₀ + e^{λt}v`` give ``(λ²M + λC + K)v = w``; in the MEiCP's coordinates
``y = (λ²B + λD − A)x`` with ``D = P̃CQ̃``.

- **Divergence**: the quadratic MEiCP with real λ ≥ 0 (λ the growth rate, σ = λ² reported
  as for the undamped model), enumerated over every support
  (:func:`meicp.eicp.quadratic.solve_quadratic_eicp`): complete, each mode certified, so no
  solution is a proof.  sym(D) may be indefinite (the friction rows of P̃), so the undamped
  Rayleigh bound is not used.
- **Flutter** of steady sliding: every eigenvalue of the quadratic sliding pencil by the
  dense companion linearisation (:func:`meicp.eicp.quadratic.quadratic_spectrum`), each with
  its rounding radius r: a mode with Re λ > r, |Im λ| > r and a backward error below
  :data:`~meicp.contact.flutter_verdict.RESIDUAL_TOL` is certified flutter; an eigenvalue with
  Re λ < −r decays and one within r of the real axis whose disk meets no other's is real;
  anything else is borderline (undecided).

The divergence is enumerated where the enumeration's limits allow; past them damping
proportional to stiffness and mass (``C = cK + αM``) makes it the undamped MEiCP of the same
pencil, decided by the undamped verdict (:mod:`.damped_proportional`); any other damping: the damped
Rayleigh bound (:mod:`.damped_rayleigh`, one LDLᵀ inertia) may prove that no λ ≥ 0 exists,
the undamped modes followed to the damped problem (:mod:`.damped_modes`) may find certified
ones, the condensed λ-windows (:mod:`.damped_windows`) may prove there are none, and otherwise
it is *undecided*, so that the damped flutter search at scale
(:mod:`.damped_search`, past ``FLUTTER_DENSE_MAX`` retained DOFs) can still prove the lattice
unstable.  Every other path that would leave C
out (the modal analysis, the critical friction, the window procedure, a named divergence
method) is a ProblemError saying so (:func:`refuse`), never an undamped answer.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np
import scipy.sparse as sp

from ..core import limits
from ..core.comm import mpi_comm
from ..core.errors import ProblemError
from ..core.matrix import to_dense
from ..eicp.quadratic import QuadraticSpectrum, quadratic_spectrum, solve_quadratic_eicp
from .divergence.enumeration import check_enumeration_size, enumeration_is_small
from .divergence.modes import mode_of
from .divergence.verdict import DivergenceProof, DivergenceVerdict
from .flutter_growth import FlutterGrowth
from .flutter_verdict import RESIDUAL_TOL, FlutterCandidate, PencilFlutter, RejectedPair
from .damped_modes import followed_modes
from .damped_proportional import proportional_damping, proportional_divergence
from .damped_rayleigh import damped_rayleigh_bound
from .damped_windows import prove_no_damped_divergence
from .on_root import on_root

log = logging.getLogger("meicp")



@dataclass(frozen=True)
class DampingUsed:
    """The damping a result was computed with: each layer's and band's viscosity (0 when
    none), each bonded interface's own (those that give one), ``[damping] mass``."""

    viscosity: dict
    interface_viscosity: dict
    mass: float

    @classmethod
    def of(cls, scene) -> "DampingUsed | None":
        if not scene.damped:
            return None
        eta = {m.name: float(m.viscosity or 0.0) for m in scene.layers + scene.embedded}
        itf = {i.below: float(i.viscosity) for i in scene.interfaces if i.bonded and i.viscosity is not None}
        return cls(eta, itf, float(scene.damping.mass) if scene.damping else 0.0)

    def describe(self) -> str:
        parts = [f"η({k}) = {v:g}" for k, v in self.viscosity.items()]
        parts += [f"η(interface above {k}) = {v:g}" for k, v in self.interface_viscosity.items()]
        if self.mass:
            parts.append(f"C += {self.mass:g}·M")
        return "Kelvin–Voigt damping: " + ", ".join(parts)

    def to_dict(self) -> dict:
        return {"viscosity": dict(self.viscosity), "interface_viscosity": dict(self.interface_viscosity),
                "mass": self.mass}


def refuse(scene, what: str) -> None:
    """ProblemError when ``scene`` is damped: ``what`` (a path without damping) would drop C."""
    if scene.damped:
        raise ProblemError(f"{what} is not supported with damping yet (the scene has "
                           f"{DampingUsed.of(scene).describe()}); it would leave the damping out. Built so far: "
                           "meicp.analyze on scenes small enough for the dense damped references "
                           "(docs/damping.md)")


def damping_matrix(pen) -> sp.csr_matrix:
    """``D = P̃ C Q̃`` of a pencil (SciPy, on every rank: the damped paths are dense)."""
    if not pen.distributed:
        return pen.damping()
    maps = pen.maps
    return (maps.P @ pen.lattice.damping() @ maps.Q).tocsr()


def _dense(pen) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Dense A, B, D on every rank (collective: a distributed pencil is gathered)."""
    return to_dense(pen.A), to_dense(pen.B), damping_matrix(pen).toarray()


# -- divergence ----------------------------------------------------------------------------------


def damped_divergence(pen, scene, comm, method, lam_min: float, tol: float, options) -> DivergenceVerdict:
    """The divergence verdict of a damped pencil: the quadratic MEiCP enumerated (modes with
    σ = λ² ≥ lam_min listed; the verdict is about every λ ≥ 0).  Past the enumeration's
    limits (method ``"auto"``) the damped Rayleigh bound, else the undamped modes followed to
    the damped problem (:mod:`.damped_modes`), else the condensed λ-windows
    (:mod:`.damped_windows`), else undecided; ProblemError when another
    method is asked for, or ``"enumerate"`` past its limits.  Collective."""
    red = pen.maps
    r, n_j = int(red.retained.size), int(red.J.size)
    if method not in (None, "auto", "enumerate"):
        raise ProblemError(f"method {method!r} is not supported with damping yet: the damped divergence is "
                           "decided by enumeration of the quadratic MEiCP (method 'auto' or 'enumerate')")
    if method == "enumerate":
        check_enumeration_size(n_j, r, options)
    elif not enumeration_is_small(r, n_j):
        proportional = proportional_damping(pen.model)
        if proportional is not None:  # exactly the undamped MEiCP (:mod:`.damped_proportional`)
            return proportional_divergence(pen, scene, comm, proportional, lam_min, tol, options)
        # past the enumeration: the damped Rayleigh bound may prove stability; else undecided,
        # not an error — the damped flutter search may still prove the lattice unstable
        proved, statement = damped_rayleigh_bound(pen)
        log.info("damped divergence: %s", statement)
        if proved:
            return DivergenceVerdict([], True, statement, None, DivergenceProof("damped-rayleigh", statement))
        modes, followed = followed_modes(pen, scene, comm, tol, options)
        if modes:
            listed = [m for m in modes if lam_min == 0 or m.sigma >= lam_min]
            growth = ", ".join(f"{np.sqrt(m.sigma):.6g}" for m in modes[:3])
            text = (f"{len(modes)} certified damped divergence mode(s), growth rate λ = {growth} ({statement}; "
                    f"{followed})")
            return DivergenceVerdict(listed, False, text, None, DivergenceProof("quadratic-followed",
                                                                                "certified mode(s)"))
        windows = prove_no_damped_divergence(pen, comm, tol=tol)
        log.info("damped divergence: %s (%s)", windows.statement,
                 ", ".join(f"{k} {v:.1f} s" for k, v in windows.seconds.items()))
        if windows.proved:
            text = f"{windows.statement} ({statement}; {followed}: no damped mode found)"
            return DivergenceVerdict([], True, text, None, DivergenceProof(
                "damped-condensed-windows", windows.statement, sigma_window=(0.0, float("inf"))))
        text = (f"undecided: damped divergence with {r} retained DOFs and {n_j} complementarity pairs is past the "
                f"dense enumeration's limits ({limits.ENUMERATE_N} DOFs, {limits.ENUMERATE_J} pairs, 2^|J|·r³ ≤ "
                f"{limits.ENUMERATE_FLOPS:g}); {statement}; {followed}: no damped mode found, which proves nothing; "
                f"{windows.statement} (docs/damping.md)")
        return DivergenceVerdict([], None, text, None, DivergenceProof("", text))
    max_j = options.get("max_j") if method == "enumerate" else None

    A, B, D = _dense(pen)  # collective when the pencil is distributed
    res = on_root(mpi_comm(comm), lambda: solve_quadratic_eicp(A, B, D, red.J, lam_min=0.0, tol=tol, max_j=max_j))
    found = [mode_of(SimpleNamespace(lam=s.sigma, x=s.x, support=s.support, residual=s.residual), red)
             for s in res.solutions]
    listed = [m for m in found if lam_min == 0 or m.sigma >= lam_min]
    note = (f"; {len(found) - len(listed)} with σ = λ² < lam_min = {lam_min:g} not listed"
            if len(listed) < len(found) else "")
    head = f"quadratic MEiCP (λ²B + λD − A), enumeration of all {res.supports} supports"

    def verdict(modes, stable, evidence, test, statement):
        return DivergenceVerdict(modes, stable, evidence, res, DivergenceProof(test, statement, res.supports))

    if found:
        growth = ", ".join(f"{max(s.lam, 0.0):.6g}" for s in res.solutions[:3])  # 0 within rounding: ≥ 0
        return verdict(listed, False, f"{head}: {len(found)} damped divergence mode(s), growth rate λ = {growth}"
                       f"{note}", "quadratic-enumerate", "certified mode(s)")
    if res.status == "no_solution":
        text = f"{head}: no real λ ≥ 0 (a proof)"
        return verdict([], True, text, "quadratic-enumerate", text)
    text = f"{head} found no mode, but this is not a proof ({res.status}): {res.message}"
    return verdict([], None, text, "", text)


# -- flutter ---------------------------------------------------------------------------------------


def damped_flutter(pen, comm=None, *, dense_max: int | None = None) -> PencilFlutter:
    """The flutter analysis of one damped sliding pencil (every retained DOF free, slip rows
    as equalities), dense: ProblemError past ``dense_max`` (default ``FLUTTER_DENSE_MAX``)
    retained DOFs.  Collective."""
    n = int(pen.maps.retained.size)
    limit = limits.FLUTTER_DENSE_MAX if dense_max is None else dense_max
    if n > limit:
        raise ProblemError(f"damped flutter with {n} retained DOFs is past the dense limit of {limit} "
                           "(limits.FLUTTER_DENSE_MAX, or flutter_dense_max): the damped flutter search at scale "
                           "is :func:`meicp.contact.damped_search.search_damped_flutter` (docs/damping.md)")
    A, B, D = _dense(pen)  # collective when the pencil is distributed
    return on_root(mpi_comm(comm), lambda: classify_spectrum(quadratic_spectrum(A, B, D)))


def classify_spectrum(spec: QuadraticSpectrum, residual_tol: float = RESIDUAL_TOL) -> PencilFlutter:
    """The flutter verdict from a whole quadratic spectrum with radii (module docstring)."""
    lam, r = spec.lam, spec.radius
    finite = np.isfinite(lam) & np.isfinite(r)
    infinite = ~np.isfinite(lam)
    decays = finite & (lam.real + r < 0)
    near_axis = finite & (np.abs(lam.imag) <= r)
    real = np.zeros(lam.size, dtype=bool)
    for i in np.flatnonzero(near_axis & ~decays):  # real when its disk meets no other eigenvalue's
        others = np.flatnonzero(finite)
        others = others[others != i]
        real[i] = not np.any(np.abs(lam[others] - lam[i]) <= r[others] + r[i])
    growing = finite & (lam.real > r) & (np.abs(lam.imag) > r)
    excluded = decays | real
    modes, rejected = [], []
    for i in np.flatnonzero(growing & (lam.imag > 0)):
        if spec.residual[i] <= residual_tol:
            sigma = complex(lam[i]) ** 2
            modes.append(FlutterCandidate(sigma, spec.x[:, i], float(spec.residual[i]),
                                          float(2 * abs(lam[i]) * r[i] + r[i] ** 2), spec.how))
        else:
            rejected.append(RejectedPair(complex(lam[i]) ** 2, float(spec.residual[i])))
    undecided = finite & ~excluded & ~growing
    unresolved = ~finite & ~infinite
    flutter = True if modes else (None if undecided.any() or unresolved.any() or rejected else False)
    modes.sort(key=lambda m: -np.sqrt(m.sigma).real)
    counts = {"eigenvalues": int(lam.size), "growing_pairs": int((growing & (lam.imag > 0)).sum()),
              "certified_real": int(real.sum()), "decaying": int((decays & ~real).sum()),
              "borderline": int(undecided.sum()), "infinite": int(infinite.sum()), "rejected": len(rejected)}
    evidence = (f"{spec.how}, all {lam.size} eigenvalues λ: {counts['growing_pairs']} non-real pair(s) with Re λ > 0, "
                f"{counts['certified_real']} certified real, {counts['decaying']} decaying (Re λ < 0), "
                f"{counts['borderline']} borderline (within rounding of the real or imaginary axis)"
                + (f", {counts['infinite']} infinite (not modes)" if infinite.any() else "")
                + (f", {len(rejected)} failing the residual gate {residual_tol:g}" if rejected else "")
                + (" — a proof" if flutter is not None else ": undecided"))
    return PencilFlutter(flutter, modes, evidence, complete=True, counts=counts, rejected=rejected,
                         growth=_growth(lam, r, excluded | infinite, modes, spec.how))


def _growth(lam, r, excluded, modes, how: str) -> FlutterGrowth:
    """The certified bracket of the fastest damped flutter growth Re λ: below, the fastest
    certified mode less its radius; above, Re λ + r over every eigenvalue that may be a
    growing non-real one (0: no flutter, a proof)."""
    candidates = ~excluded & np.isfinite(lam)
    upper = max([0.0] + [float(v) for v in (lam.real + r)[candidates]])
    lower = max([0.0] + [float(np.sqrt(m.sigma).real) - _lam_radius(m) for m in modes])
    if upper == 0.0:
        return FlutterGrowth(0.0, 0.0, f"{how}: every eigenvalue real or decaying — no flutter (a proof)")
    return FlutterGrowth(max(lower, 0.0), upper, f"{how}: no eigenvalue that may be non-real grows faster than "
                                                 f"{upper:.10g}; the fastest certified mode at least {lower:.10g}")


def _lam_radius(mode) -> float:
    """The λ-radius r of a candidate whose σ-radius is 2|λ|r + r²."""
    a = abs(np.sqrt(mode.sigma))
    return float(-a + np.sqrt(a * a + mode.radius))
