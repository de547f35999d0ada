"""Flutter of steady sliding (docs/flutter.md): non-real eigenvalues of the sliding pencil.

With the slipping contacts sliding on, the linearised motion is ``(σB − A)x = 0`` on the
retained DOFs: the MEiCP's pencil ``A = −P̃KQ̃``, ``B = P̃MQ̃`` with every slip row an
equality (the slip rate free in sign while sliding goes on).  A is nonsymmetric once μ > 0,
and a non-real σ gives λ = √σ with Re λ > 0: a growing oscillation.  Which contacts count:
slipping ones (base and frictional interfaces) slide, sticking ones are held, separated
ones are free; a grazing contact has no linearisation, so two branches bracket it
(:func:`grazing_branches`): ``separated`` and ``sliding`` — flutter is claimed only when
every branch has it, excluded only when none has it.

Two paths, both ending in :class:`~meicp.contact.result.FlutterMode` s with their
backward errors (a mode above :data:`RESIDUAL_TOL` is never reported):

- **dense** (retained DOFs ≤ :data:`~meicp.core.limits.FLUTTER_DENSE_MAX`): every eigenvalue by LAPACK (QR on
  D^{-1/2}AD^{-1/2} when B = D is diagonal, else QZ), each with the rounding radius
  ``r = n·u·(‖A‖₁ + |σ|‖B‖₁)·κ(σ)``, κ from the left and right eigenvectors: non-real when
  |Im σ| > r; certified real when |Im σ| ≤ r and its disk meets no other; else borderline.
  flutter = True with a certified non-real mode, False when every eigenvalue is certified
  real (a proof), None otherwise.  A symmetric A with symmetric positive definite B is
  proved flutter-free without QZ.
- **search** (larger): complex shift-and-invert (:mod:`meicp.petsc.flutter`) at targets
  taken from a dense *contact-strip proxy* of the scene (the fastest modes are slip waves
  along the contact, whose σ hardly depends on the lattice's size), or on a λ-line when
  no proxy exists.  It can prove flutter (a certified mode), never its absence: flutter is
  True or None, and the evidence says which disks of the σ-plane were searched.
"""

from __future__ import annotations

import dataclasses
import itertools
import logging
import time

import numpy as np
import scipy.linalg as sl
import scipy.sparse as sp

from ..core import limits
from ..core.comm import available_memory_on, mpi_comm
from ..core.matrix import is_petsc_mat, to_dense
from ..core.validation import as_flag
from ..petsc.flutter import SlidingPencilOps, complex_shift_solve
from ..petsc.mat import mat_from_scipy
from .damped import damped_flutter
from .flutter_growth import FlutterGrowth, combine_growths, dense_growth, search_growth
from .flutter_verdict import RESIDUAL_TOL, FlutterCandidate, FlutterVerdict, PencilFlutter, RejectedPair
from .lines import BASE, ContactState, state_names
from .on_root import on_root
from .problem import pencil, pencil_of
from .result import FlutterMode, growth_frequency

log = logging.getLogger("meicp")

#: large-scale path: |Im σ| must exceed MARGIN·η·(‖A‖₁/‖B‖₁ + |σ|) (η the backward error)
#: to count as non-real; MARGIN stands for the unknown condition number (κ ≤ 1.1e3 measured
#: on the dense cases)
MARGIN = 1e6
#: large-scale path defaults: proxy targets, eigenpairs per target, Krylov basis
SEARCH_TARGETS = 3
SEARCH_NEV = 4
SEARCH_NCV = 16
#: contact-strip proxy: columns, rows, and the share of a proxy mode's energy in the rows
#: next to the contact for it to count as contact-localised
PROXY_NX = 32
PROXY_ROWS = 8
PROXY_LOCALISED = 0.6
PROXY_NEAR_ROWS = 3
#: a σ within this relative distance of an earlier one is the same eigenvalue
SAME = 1e-9
#: a target whose pairs all fail the residual gate sits inside a cluster of ill-conditioned
#: flutter eigenvalues (shift-and-invert then returns pseudo-pairs next to it); it is moved up
#: off the cluster by OFF_CLUSTER·max(Im τ, 0.05|τ|) per try, at most OFF_CLUSTER_TRIES times:
#: one such move certified the cluster's top edge where it was measured
#: (docs/benchmarks-notes.md, "OFF_CLUSTER")
OFF_CLUSTER = 0.5
OFF_CLUSTER_TRIES = 1
OFF_CLUSTER_NCV = 16
#: an interface-strip proxy's target at that size is searched where it is, for one eigenpair
#: with a basis of INTERFACE_NCV: on the seeds' scene (extensive_interface.toml) coarsened to
#: 3·10⁵ DOFs, 1 restart and 38 s against 6 restarts and 66 s moved off with OFF_CLUSTER_NCV
#: (docs/benchmarks-notes.md, "INTERFACE_NCV")
INTERFACE_NCV = 24
#: SLEPc restarts at a target that may still be moved off its cluster, and at the last one
#: (SLEPc's own default before either was named).  A cap of 40 before a move was tried and
#: did not pay: on a lattice outside the benchmark family the target it left converged in
#: fewer restarts than the next one up needed (docs/benchmarks-notes.md, "SEARCH_RESTARTS")
SEARCH_RESTARTS = 500
LAST_RESTARTS = 500
#: from limits.FLUTTER_SEARCH_LARGE retained DOFs the shifted pencil is factored block-low-rank at this
#: dropping tolerance (MUMPS CNTL(7)): faster, with the certified pairs' backward errors as
#: without it (docs/benchmarks-notes.md, "LOW_RANK_TOL")
LOW_RANK_TOL = 1e-10
#: from limits.FLUTTER_SEARCH_LARGE retained DOFs SLEPc converges the pairs to LARGE_EPS_TOL,
#: and solves again to STRICT_EPS_TOL only when none then passes the residual gate on (A, B):
#: SLEPc's residual is that of the shifted inverse, which the backward error on (A, B) shrinks
#: (on extensive_interface.toml one restart at 1e-8 gave a pair at 2.7e-11, where 1e-10 took
#: two: docs/benchmarks-notes.md, "LARGE_EPS_TOL")
LARGE_EPS_TOL = 1e-8
STRICT_EPS_TOL = 1e-10
#: the bracket of a pencil proved flutter-free: no non-real eigenvalue at all
NO_FLUTTER = FlutterGrowth(0.0, 0.0, "no flutter (a proof)")


def _norm1(M: np.ndarray) -> float:
    return float(np.abs(M).sum(axis=0).max()) if M.size else 0.0


def _fastest_first(modes: list) -> list:
    return sorted(modes, key=lambda m: (-growth_frequency(m.sigma)[0], -abs(m.sigma.imag)))


def _normalise(x: np.ndarray) -> np.ndarray:
    """‖x‖₂ = 1 with its largest entry real positive (a canonical phase)."""
    x = np.asarray(x, dtype=complex)
    k = int(np.argmax(np.abs(x)))
    return x / (x[k] / abs(x[k]) * np.linalg.norm(x)) if x[k] != 0 else x


def backward_error(A, B, sigma: complex, x: np.ndarray, norm_A: float, norm_B: float) -> float:
    """‖Ax − σBx‖₂ / ((‖A‖₁ + |σ|‖B‖₁)‖x‖₂) (A, B dense or SciPy), evaluated on A/‖A‖₁ and
    B/‖B‖₁ so that extreme scales do not overflow; inf when it still cannot be evaluated
    (such a pair is never certified)."""
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        x = x / np.linalg.norm(x)
        ratio = norm_B / norm_A
        r = (A @ x) / norm_A - (sigma * ratio) * ((B @ x) / norm_B)
        value = np.linalg.norm(r) / (1.0 + abs(sigma) * ratio)
    return float(value) if np.isfinite(value) and np.isfinite(ratio) and ratio > 0 else float("inf")


def _symmetric_definite(A: np.ndarray, B: np.ndarray) -> bool:
    if not (np.array_equal(A, A.T) and np.array_equal(B, B.T)):
        return False
    try:
        np.linalg.cholesky(B)
    except np.linalg.LinAlgError:
        return False
    return True


def dense_flutter(A, B, *, residual_tol: float = RESIDUAL_TOL, radius_factor: float | None = None) -> PencilFlutter:
    """Every flutter mode of the pencil (A, B) (NumPy or SciPy, serial) and the verdict, a
    proof either way unless borderline (module docstring).  ``radius_factor``: the multiple
    of u·(‖A‖ + |σ|‖B‖)·κ that counts as rounding (default n)."""
    A = A.toarray() if sp.issparse(A) else np.asarray(A, dtype=float)
    B = B.toarray() if sp.issparse(B) else np.asarray(B, dtype=float)
    n = A.shape[0]
    if n == 0:
        return PencilFlutter(False, evidence="no retained DOF: nothing can move (a proof)", complete=True,
                             growth=NO_FLUTTER)
    if _symmetric_definite(A, B):
        return PencilFlutter(False, evidence="symmetric A and symmetric positive definite B: every σ is real "
                                             "(no friction coupling reaches the retained DOFs) — a proof",
                             complete=True, growth=NO_FLUTTER)
    if not (np.all(np.isfinite(A)) and np.all(np.isfinite(B))):
        return PencilFlutter(None, evidence="the pencil has entries that are not finite: undecided",
                             growth=FlutterGrowth(0.0, None, "entries not finite: no bound"))
    try:
        with np.errstate(over="ignore", invalid="ignore", divide="ignore", under="ignore"):
            return _dense_spectrum(A, B, residual_tol, radius_factor)
    except (np.linalg.LinAlgError, ValueError) as exc:  # QZ did not converge, or NaN came out
        return PencilFlutter(None, evidence=f"the dense eigen-solve (LAPACK) failed ({exc}): undecided",
                             growth=FlutterGrowth(0.0, None, "the dense eigen-solve failed: no bound"))


def _dense_spectrum(A: np.ndarray, B: np.ndarray, residual_tol: float, radius_factor) -> PencilFlutter:
    n = A.shape[0]
    norm_A, norm_B = _norm1(A), _norm1(B)
    d = np.diag(B)
    if np.all(d > 0) and np.count_nonzero(B) == np.count_nonzero(d):
        s = 1.0 / np.sqrt(d)
        C = s[:, None] * A * s[None, :]
        w, VL, VR = sl.eig(C, left=True, right=True)
        X = s[:, None] * VR
        kappa = (np.linalg.norm(VL, axis=0) * np.linalg.norm(VR, axis=0)
                 / np.maximum(np.abs(np.einsum("ij,ij->j", VL.conj(), VR)), 1e-300))
        scale = _norm1(C) + np.abs(w)
        infinite = np.zeros(n, dtype=bool)
        how = "dense QR of D^-1/2 A D^-1/2 (B = D diagonal)"
    else:
        (alpha, beta), VL, VR = sl.eig(A, B, left=True, right=True, homogeneous_eigvals=True)
        # infinite: β at the rounding level of B *relative to* α on A's scale (|σ|·‖B‖ beyond
        # ‖A‖/(n·u)); without the norms a change of units (K ×1e7, M ÷1e7, every σ ×1e14) made
        # every finite σ past 1/(n·u) "infinite" and the dense path proved flutter absent
        infinite = np.abs(beta) * norm_A <= n * np.finfo(float).eps * np.abs(alpha) * norm_B
        w = np.where(infinite, np.inf, alpha / np.where(infinite, 1.0, beta))
        X = VR
        kappa = (np.linalg.norm(VL, axis=0) * np.linalg.norm(VR, axis=0)
                 / np.maximum(np.abs(np.einsum("ij,ij->j", VL.conj(), B @ VR)), 1e-300))
        scale = norm_A + np.where(infinite, 0.0, np.abs(w)) * norm_B
        how = "dense QZ of (A, B)"
    factor = float(n) if radius_factor is None else radius_factor
    radius = np.where(infinite, np.inf, factor * (np.finfo(float).eps / 2) * scale * kappa)
    radius = np.where(np.isfinite(radius), radius, np.inf)  # no bound: never certified either way
    unresolved = ~infinite & ~np.isfinite(w)
    finite = ~infinite & ~unresolved
    nonreal = finite & (np.abs(w.imag) > radius)
    near_axis = finite & ~nonreal
    certified_real = np.zeros(n, dtype=bool)
    fin = np.flatnonzero(finite)
    order = fin[np.argsort(w[fin].real)]
    re = w[order].real
    reach = radius[order].max() if order.size else 0.0
    for i in np.flatnonzero(near_axis):  # certified when its disk meets no other eigenvalue's disk
        lo = np.searchsorted(re, w[i].real - radius[i] - reach, "left")
        hi = np.searchsorted(re, w[i].real + radius[i] + reach, "right")
        near = order[lo:hi]
        near = near[near != i]
        certified_real[i] = not np.any(np.abs(w[near] - w[i]) <= radius[near] + radius[i])
    borderline = (near_axis & ~certified_real) | unresolved
    modes, rejected = [], []
    for i in np.flatnonzero(nonreal & (w.imag > 0)):
        res = backward_error(A, B, complex(w[i]), X[:, i], norm_A, norm_B)
        if res <= residual_tol:
            modes.append(FlutterCandidate(complex(w[i]), _normalise(X[:, i]), res, float(radius[i]), how))
        else:
            rejected.append(RejectedPair(complex(w[i]), res))
    counts = {"eigenvalues": n, "nonreal_pairs": int(nonreal.sum()) // 2,
              "certified_real": int(certified_real.sum()), "borderline": int(borderline.sum()),
              "infinite": int(infinite.sum()), "rejected": len(rejected)}
    flutter = True if modes else (None if borderline.any() or rejected else False)
    infinite_note = f", {int(infinite.sum())} infinite (not modes)" if infinite.any() else ""
    rejected_note = (f", {len(rejected)} non-real pair(s) failing the residual gate {residual_tol:g} "
                     "(not reported)" if rejected else "")
    evidence = (f"{how} of all {n} eigenvalues{infinite_note}: {counts['nonreal_pairs']} non-real pair(s), "
                f"{counts['certified_real']} certified real, {counts['borderline']} borderline "
                f"(non-reality at rounding level){rejected_note}"
                + (" — a proof" if flutter is not None else ": undecided"))
    growth = dense_growth(w, radius, ~infinite & ~certified_real, modes, how)
    return PencilFlutter(flutter, _fastest_first(modes), evidence, complete=True, counts=counts, rejected=rejected,
                         growth=growth)


def lambda_line_targets(growth: float, frequencies) -> list[complex]:
    """Targets σ = (g + iω)² on the vertical line Re λ = g of the λ-plane: a sweep that needs
    no proxy (the large-scale path without one, and the benchmark's independent check)."""
    return [complex((growth + 1j * w) ** 2) for w in frequencies]


def off_cluster(tau: complex, attempt: int) -> complex:
    """The target tried after ``attempt`` + 1 failed ones at ``tau``: moved up, away from the
    real axis, by OFF_CLUSTER·max(Im τ, 0.05|τ|)·2^attempt (the fastest flutter modes of a
    cluster are those of largest Im σ, on its top edge)."""
    return tau + 1j * OFF_CLUSTER * max(tau.imag, 0.05 * abs(tau)) * 2 ** attempt


def _real_part_bound(ops: SlidingPencilOps, given: tuple | None) -> tuple[float | None, str]:
    """``(γ, how)``: Re σ ≤ γ for every eigenvalue of a pencil with a diagonal B — the
    caller's certified bound or Gershgorin's on the scaled symmetric part, the smaller."""
    gershgorin = (ops.real_part_bound(), "Gershgorin's discs of D^-1/2 sym(A) D^-1/2")
    return gershgorin if given is None or given[0] >= gershgorin[0] else given


def search_flutter(A, B, targets, comm=None, *, nev: int = SEARCH_NEV, ncv: int | None = SEARCH_NCV,
                   tol: float = 1e-12, residual_tol: float = RESIDUAL_TOL, options: dict | None = None,
                   why_targets: str = "", off_cluster_tries: int = OFF_CLUSTER_TRIES,
                   low_rank: float | None = None, strict_tol: float | None = None,
                   real_bound: tuple | None = None) -> PencilFlutter:
    """Flutter modes of (A, B) (PETSc Mats, or SciPy distributed here over ``comm``) near the
    complex ``targets``: True with certified modes, else None — never a proof of absence.
    A target whose converged pairs all fail the residual gate is retried off the cluster
    (:func:`off_cluster`), at most ``off_cluster_tries`` times.  ``low_rank``: the MUMPS
    block-low-rank tolerance of the factor (None: full rank).  ``tol``: SLEPc's; with
    ``strict_tol``, a solve none of whose pairs passes the residual gate is made again at
    ``strict_tol`` before the target counts as failed.  ``real_bound``: ``(γ, how)``, a
    certified Re σ < γ for every eigenvalue known to the caller (the divergence verdict's
    Rayleigh bound), used when it is below Gershgorin's; with the skew-part bound it bounds
    the growth from above (:func:`~.flutter_growth.search_growth`).  Collective."""
    own = not is_petsc_mat(A)
    if own:
        comm = mpi_comm(comm)
        A, B = mat_from_scipy(comm, A), mat_from_scipy(comm, B)
    try:
        with SlidingPencilOps(A, B) as ops:
            if ops.symmetric_with_diagonal_mass():
                return PencilFlutter(False, evidence="symmetric A and diagonal positive B: every σ is real — "
                                                     "a proof", growth=NO_FLUTTER)
            bound = ops.skew_bound()
            real_max, real_how = _real_part_bound(ops, real_bound) if bound is not None else (None, "")
            modes, rejected, disks, borderline, moved = [], [], [], 0, []
            for tau in targets:
                tau = complex(tau)
                tau = tau.conjugate() if tau.imag < 0 else tau
                for attempt in range(off_cluster_tries + 1):
                    last = attempt == off_cluster_tries
                    pairs, info = complex_shift_solve(ops, tau, nev=nev, ncv=ncv, tol=tol, low_rank=low_rank,
                                                      max_it=LAST_RESTARTS if last else SEARCH_RESTARTS,
                                                      options=options, gate=residual_tol, strict_tol=strict_tol)
                    passed = sum(res <= residual_tol for _, _, res in pairs)
                    disks.append((tau, info["radius"], len(pairs), passed, info["iterations"]))
                    for sigma, x, res in pairs:
                        margin = MARGIN * res * (ops.norm_A / ops.norm_B + abs(sigma))
                        if res > residual_tol:
                            rejected.append(RejectedPair(sigma, res))
                        elif abs(sigma.imag) > margin:
                            if not any(abs(sigma - m.sigma) <= SAME * abs(m.sigma) for m in modes):
                                modes.append(FlutterCandidate(sigma, _normalise(x), res, margin,
                                                              f"shift-invert at τ = {tau:.6g}"))
                        elif sigma.imag != 0:
                            borderline += 1
                    # nothing certified — pseudo-pairs, or none converged within the restarts — is
                    # what a target inside a cluster of ill-conditioned eigenvalues gives
                    if passed or last:
                        break
                    moved.append((tau, off_cluster(tau, attempt)))
                    log.info("flutter: no pair at τ = %s passed the residual gate (%d converged in %d restarts); "
                             "retrying off the cluster at τ = %s", f"{tau:.6g}", len(pairs), info["iterations"],
                             f"{moved[-1][1]:.6g}")
                    tau = moved[-1][1]
    finally:
        if own:
            A.destroy()
            B.destroy()
    counts = {"targets": len(disks), "rejected": len(rejected), "borderline": borderline, "moved": len(moved)}
    text = "; ".join(f"|σ − ({t.real:.4g}{t.imag:+.4g}i)| ≤ {r:.3g} ({k} σ, {p} passing the residual gate, "
                     f"{it} restarts)" for t, r, k, p, it in disks)
    off = "".join(f"; no pair near τ = {a.real:.4g}{a.imag:+.4g}i passed the residual gate (pseudo-pairs or none "
                  f"converged, as shift-and-invert gives inside a cluster of ill-conditioned eigenvalues), so the "
                  f"target moved off it to {b.real:.4g}{b.imag:+.4g}i" for a, b in moved)
    evidence = (f"complex shift-and-invert at {len(disks)} target(s){why_targets}{off}: the eigenvalues SLEPc "
                    f"converged in {text}"
                    + (f"; |Im σ| ≤ {bound:.4g} everywhere (skew-part bound)" if bound is not None else "")
                    + (f"; {len(rejected)} pair(s) failed the residual gate {residual_tol:g}" if rejected else ""))
    if modes:
        evidence += (": flutter is proved by the certified mode(s); that the fastest found is the fastest "
                     "is not (not a proof of the growth rate)")
    else:
        evidence += ": no certified flutter mode there — not a proof that none exists (undecided)"
    rectangle = None if bound is None or real_max is None else (real_max, bound, real_how)
    growth = search_growth(modes, "shift-and-invert computes only the eigenvalues near its targets", rectangle)
    return PencilFlutter(True if modes else None, _fastest_first(modes), evidence, counts=counts, rejected=rejected,
                         growth=growth)


# -- the scene level: branches, proxy, the choice of path -------------------------------------

def _sliding_signs(states) -> list:
    signs = sorted({s for s in states if s.slip_sign}, key=lambda s: -s.slip_sign)
    return signs if len(signs) == 1 else [ContactState.SLIP_PLUS, ContactState.SLIP_MINUS]


def grazing_branches(lines) -> list[tuple[str, list]]:
    """[(label, contact lines with every grazing state replaced)]: one entry labelled ""
    without grazing contacts; else ``separated`` (the open side: free) and ``sliding`` (the
    loaded side: v_n = 0 and the friction row in the sliding direction of that contact line —
    the sign its slipping contacts share, each sign in turn when they disagree or none
    slips)."""
    GRAZING = ContactState.GRAZING

    def replaced(line, state):
        return line.in_states(tuple(state if s is GRAZING else s for s in line.states))

    if not any(GRAZING in line.states for line in lines):
        return [("", list(lines))]
    branches = [("separated", [replaced(line, ContactState.SEPARATED) for line in lines])]
    choices = [_sliding_signs(line.states) if GRAZING in line.states else [None] for line in lines]
    for choice in itertools.product(*choices):
        branch = [line if sign is None else replaced(line, sign) for line, sign in zip(lines, choice)]
        label = "sliding " + ",".join(f"{line.name}:{c.value}" for line, c in zip(lines, choice) if c is not None)
        branches.append((label, branch))
    return branches


def combine_branches(flags) -> bool | None:
    """Flutter over grazing branches: True if every branch has it, False if none can."""
    flags = list(flags)
    if all(f is True for f in flags):
        return True
    if all(f is False for f in flags):
        return False
    return None


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


def proxy_targets(scene, lines, count: int = SEARCH_TARGETS) -> list[complex]:
    """Up to ``count`` targets: σ of the proxy's fastest contact-localised flutter modes, at
    least 0.1|σ| apart (all its modes when none is localised); [] without a proxy.  ``lines``:
    the scene's contact lines with their states resolved (a pencil's ``lines``)."""
    proxy, near = _proxy_of(scene, lines)
    if proxy is None:
        return []
    with pencil(proxy) as pen:  # a lattice of its own, PROXY_NX × PROXY_ROWS, serial
        red = pen.maps
        found = dense_flutter(pen.A, pen.B) if pen.A is not None else PencilFlutter(False)

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
    return targets


def pencil_flutter(pen, scene, comm=None, *, dense_max: int | None = None, options: dict | None = None,
                   targets=None, **search) -> PencilFlutter:
    """The flutter analysis of one sliding pencil ``pen`` (a
    :class:`~meicp.contact.problem.Pencil`, every contact state resolved): dense up to
    ``dense_max`` retained DOFs (on rank 0, broadcast), else the search at ``targets`` (default:
    the proxy's, else a λ-line).  Collective."""
    comm = mpi_comm(comm)
    n = int(pen.maps.retained.size)
    if n == 0:
        return PencilFlutter(False, evidence="every DOF is held: nothing can move (a proof)", complete=True,
                             growth=NO_FLUTTER)
    if pen.damped:  # the quadratic pencil: dense only so far (ProblemError past dense_max)
        return damped_flutter(pen, comm, dense_max=dense_max)
    if n <= (limits.FLUTTER_DENSE_MAX if dense_max is None else dense_max):
        A, B = (to_dense(pen.A), to_dense(pen.B)) if pen.distributed else (pen.A, pen.B)
        return on_root(comm, lambda: dense_flutter(A, B))
    need = limits.FLUTTER_SEARCH_BYTES_PER_DOF * n
    memory, where = available_memory_on(comm, need)
    if memory is not None and need > memory:
        return PencilFlutter(None, evidence=(
            f"not searched: the complex shift-and-invert of {n:,} retained DOFs needs about {need / 2**30:.1f} GiB "
            f"more, {memory / 2**30:.1f} GiB is available on {where}: undecided"),
            growth=FlutterGrowth(0.0, None, "not searched (memory): no bound"))
    why = ""
    if targets is None:
        count = 1 if n >= limits.FLUTTER_SEARCH_LARGE else SEARCH_TARGETS
        targets = proxy_targets(scene, pen.lines, count)
        why = f" from a {PROXY_NX}-column, {PROXY_ROWS}-row contact-strip proxy (dense QZ)"
        interface = not any(line.name == BASE for line in pen.lines)
        if targets and n >= limits.FLUTTER_OFF_CLUSTER_FROM and interface:
            search.setdefault("nev", 1)
            search.setdefault("ncv", INTERFACE_NCV)
            why += f", searched at its σ for {search['nev']} eigenpair(s) with a basis of {search['ncv']}"
        elif targets and n >= limits.FLUTTER_OFF_CLUSTER_FROM:
            moved = [off_cluster(t, 0) for t in targets]
            why += (f", each moved up off its cluster before the first solve ({n:,} ≥ "
                    f"{limits.FLUTTER_OFF_CLUSTER_FROM:,} retained "
                    "DOFs: the proxy's σ lies inside a cluster of ill-conditioned eigenvalues at this size): "
                    + ", ".join(f"{t.real:.4g}{t.imag:+.4g}i → {m.real:.4g}{m.imag:+.4g}i"
                                for t, m in zip(targets, moved)))
            targets = moved
            search.setdefault("ncv", OFF_CLUSTER_NCV)
        if not targets:
            targets = lambda_line_targets(0.05, np.linspace(0.5, 2.5, 3))
            why = " on the λ-line Re λ = 0.05, ω = 0.5 … 2.5 (no proxy for this scene)"
    if n >= limits.FLUTTER_SEARCH_LARGE:
        search.setdefault("nev", 2)
        search.setdefault("ncv", 12)
        search.setdefault("tol", LARGE_EPS_TOL)
        search.setdefault("strict_tol", STRICT_EPS_TOL)
        search.setdefault("low_rank", LOW_RANK_TOL)
    return search_flutter(pen.A, pen.B, targets, comm, options=options, why_targets=why, **search)


def _to_mode(candidate: FlutterCandidate, maps, branch: str) -> FlutterMode:
    u = maps.Q @ candidate.x
    support, interface = [], {}
    for name, idx, kind in maps.pair_of:
        if kind == "t":
            (support if name == "base" else interface.setdefault(name, [])).append(idx)
    return FlutterMode(candidate.sigma, _normalise(u), candidate.residual, np.unique(np.array(support, dtype=np.int64)),
                       {k: np.unique(v) for k, v in interface.items()}, candidate.radius, branch, candidate.found_by)


def analyze_flutter(lattice, lines, scene, *, pencil=None, static=None, options: dict | None = None,
                    **kwargs) -> FlutterVerdict:
    """The flutter verdict of a scene's steady sliding: one pencil per grazing branch, reduced
    from the assembled ``lattice`` (:class:`~meicp.petsc.assembly.LatticeMatrices`;
    ``pencil``: the MEiCP's own, reused when no contact grazes), the verdicts combined.
    Collective on the lattice's communicator."""
    comm = lattice.comm
    t0 = time.perf_counter()
    verdicts, modes, evidences, growths = [], [], [], []
    for label, branch in grazing_branches(lines):
        own = pencil is None or label
        pen = pencil_of(lattice, branch, (), static) if own else pencil
        try:
            part = pencil_flutter(pen, scene, comm, options=options, **kwargs)
            modes += [_to_mode(m, pen.maps, label) for m in part.modes]
        finally:
            if own:
                pen.destroy()
        verdicts.append(part.flutter)
        growths.append(part.growth)
        evidences.append((f"[{label}] " if label else "") + part.evidence)
    modes.sort(key=lambda m: (-m.growth_rate, -abs(m.sigma.imag)))
    evidence = " | ".join(evidences)
    if len(verdicts) > 1:
        evidence = ("grazing contacts, bracketed by a separated and a sliding branch (flutter only if every "
                    "branch has it): " + evidence)
    return FlutterVerdict(combine_branches(verdicts), modes, evidence, time.perf_counter() - t0,
                          combine_growths(growths))


def flutter_asked(scene, flutter) -> bool:
    """Whether to decide flutter: ``flutter`` checked (True or False; None: the scene's
    ``[solver] flutter``), a ProblemError naming it otherwise."""
    flag = as_flag(flutter, "flutter", allow_none=True)
    return bool(scene.solver.flutter) if flag is None else flag


def not_analysed(reason: str) -> FlutterVerdict:
    """The verdict when flutter was not looked at (``flutter=False`` in ``analyze``)."""
    return FlutterVerdict(None, [], f"not analysed ({reason}): undecided")


__all__ = ["RESIDUAL_TOL", "FlutterCandidate", "FlutterVerdict", "PencilFlutter", "RejectedPair",
           "analyze_flutter", "dense_flutter", "grazing_branches", "lambda_line_targets", "pencil_flutter",
           "proxy_targets", "search_flutter"]
