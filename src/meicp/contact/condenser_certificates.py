"""The certificates of a condensation (:mod:`.condenser`): that the lattice is held once the
contact DOFs are (K̃_FF ≻ 0, by an LDLᵀ inertia), a certified lower bound τ of
λ_min(K̃_FF, M̃_FF), SLEPc's estimate that places the σ-windows, solves with K̃_FF refined on a
nearby factor, and the measured error of MUMPS' Schur complement.  Collective on ``comm``."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..petsc.eigen import solve_ghep
from ..petsc.inertia import INERTIA_OPTIONS, diagonal_scale, rounding_margin
from ..petsc.mat import destroying, mat_from_scipy
from ..petsc.schur import MumpsFactor
from .condensation import PencilPieces, from_bordered_schur
from .rayleigh import pencil_is_negative

#: the Schur complement's measured relative error is charged this many times over
PROBE_SAFETY = 100.0
#: floor of the charged relative error of a Schur complement (MUMPS' backward error level)
SCHUR_ERROR_FLOOR = 1e-13
#: SLEPc options of the estimate of λ_min(K̃_FF, M̃_FF) (half of it is certified): two digits
#: are plenty — a tighter tolerance costs solves for the same τ (docs/benchmarks-notes.md)
TAU_EPS = {"eps_tol": 1e-2, "eps_ncv": 6, "eps_purify": False}
#: iterative refinement steps of a solve with K̃_FF on a nearby factor (:func:`refined_solve`)
REFINE_STEPS = 4


def held_factor(comm, KFF, MFF, *, pad=None) -> tuple[MumpsFactor | None, float | None, str]:
    """One MUMPS LDLᵀ of K̃_FF − 2η·D (D = diag|K̃_FF|, η the rounding margin of
    :func:`~meicp.petsc.inertia.rounding_margin`) and the proof its inertia gives: every pivot
    positive means K̃_FF − 2ηD ≻ 0 up to the factorisation's rounding (one η), so K̃_FF ≻ ηD ≻ 0
    — the lattice is held once the contact DOFs are — and, with a diagonal M̃_FF,
    τ = η·min(D/M̃_FF) ≤ λ_min(K̃_FF, M̃_FF).  Returns ``(factor, τ, "")`` (τ 0 for a
    non-diagonal mass), or ``(None, None, why)`` when not proved (the factor destroyed).
    ``pad``: the factored matrix padded to node blocks first (:mod:`meicp.lattice.node_blocks`)."""
    eta = rounding_margin(KFF.shape[0])
    d = diagonal_scale(KFF)
    shifted = (KFF - sp.diags(2 * eta * d)).tocsr()
    factor = MumpsFactor(comm, shifted if pad is None else pad(shifted), symmetric=True, options=INERTIA_OPTIONS)
    negative, zero, _ = factor.inertia()
    if negative or zero:
        factor.destroy()
        return None, None, (f"K̃_FF is not proved positive definite ({negative + zero} pivot(s) of K̃_FF − 2η·diag "
                            f"(η = {eta:.1e}) not positive): the lattice is not held once the contact DOFs are")
    m = MFF.diagonal()
    diagonal = (MFF - sp.diags(m)).count_nonzero() == 0 and m.size and m.min() > 0
    return factor, float(eta * np.min(d / m)) if diagonal else 0.0, ""


def estimate_lambda_min(factor: MumpsFactor, MFF) -> float:
    """SLEPc's estimate of λ_min(K̃_FF, M̃_FF) by shift-and-invert on ``factor`` (of
    :func:`held_factor`: its 2ηD shift is far below the estimate's tolerance); 0 when SLEPc
    fails — an estimate places windows, it proves nothing."""
    with destroying(mat_from_scipy(factor.pcomm, MFF)) as (Mp,):
        try:
            pairs = solve_ghep(factor.A, Mp, nev=1, target=0.0, options=TAU_EPS, ksp=factor.ksp)
        except Exception:  # noqa: BLE001 — no estimate: windows split by the certified τ
            return 0.0
        for v in pairs.vectors:
            v.destroy()
        return max(float(pairs.values[0]), 0.0)


def refined_solve(factor, KFF, steps: int = REFINE_STEPS):
    """Solves with K̃_FF itself from a nearby factor (``factor.solve``): that of K̃_FF − 2ηD
    (:func:`held_factor`), each step dividing the error by about λ_min(K̃_FF)/(2η·max D) (≈ 10⁶
    on the lattices measured), or the Schur series' block-low-rank one of K̃_FF
    (:class:`~.condenser.InteriorSolve`); a few steps of iterative refinement reach rounding, and it
    stops when the residual no longer shrinks."""
    def solve(rhs: np.ndarray) -> np.ndarray:
        x = factor.solve(rhs)
        last = np.inf
        for _ in range(steps):
            r = rhs - KFF @ x
            size = float(np.abs(r).max(initial=0.0))
            if size == 0.0 or size >= 0.5 * last:
                break
            last = size
            x = x + factor.solve(r)
        return x
    return solve


def certified_tau(comm, KFF, MFF, *, pad=None) -> tuple[float | None, str]:
    """A certified lower bound τ > 0 of λ_min(K̃_FF, M̃_FF) that the solves' error bounds can
    use: half a SLEPc estimate, proved by the inertia of τM̃_FF − K̃_FF
    (:func:`~meicp.contact.rayleigh.pencil_is_negative`), which also proves K̃_FF ≻ 0.
    ``(None, why)`` when not certified.  ``pad``: as for :func:`held_factor`."""
    pad = pad or (lambda H: H)
    with destroying(mat_from_scipy(comm, pad(KFF)), mat_from_scipy(comm, MFF)) as (Kp, Mp):
        try:
            # half the estimate is certified below: a loose tolerance, a short basis and no
            # purification of the vector are enough (TAU_EPS; docs/benchmarks-notes.md)
            pairs = solve_ghep(Kp, Mp, nev=1, target=0.0, options=TAU_EPS)
            est = float(pairs.values[0])
            for v in pairs.vectors:
                v.destroy()
        except Exception as exc:  # noqa: BLE001 — no estimate means no proof, not an error
            first = (str(exc).strip().splitlines() or [type(exc).__name__])[0]  # not PETSc's whole stack
            return None, f"λ_min(K̃_FF, M̃_FF) not estimated ({first}): the condensation is not certified"
        if not est > 0:
            return None, (f"K̃_FF is not positive definite (λ_min ≈ {est:.2e}): the lattice is not held once the "
                          "contact DOFs are, the condensation is undefined")
    tau = 0.5 * est
    why = tau_inertia(comm, KFF, MFF, tau, pad=pad)
    return (tau, "") if not why else (None, why)


def tau_inertia(comm, KFF, MFF, tau: float, *, pad=None) -> str:
    """"" when the inertia of τM̃_FF − K̃_FF (:func:`~meicp.contact.rayleigh.pencil_is_negative`)
    proves τ < λ_min(K̃_FF, M̃_FF) (hence K̃_FF ≻ 0), else why not.  ``pad``: as for
    :func:`held_factor`.  Collective."""
    shifted = (tau * MFF - KFF).tocsr()
    shifted = shifted if pad is None else pad(shifted)
    with destroying(mat_from_scipy(comm, shifted), mat_from_scipy(comm, MFF)) as (Ap, Mp):
        sign = pencil_is_negative(Ap, Mp, symmetric=True)  # K̃_FF symmetrised, M̃_FF = Q̃ᵀMQ̃
    if sign is None or sign.proved is not True:
        return f"τ = {tau:.3e} ≤ λ_min(K̃_FF, M̃_FF) not certified ({'' if sign is None else sign.reason})"
    return ""


def schur_error(comm, pieces: PencilPieces, solve_KFF, *, schur) -> tuple[float, np.ndarray]:
    """MUMPS' Schur complement X of the σ = 0 bordered matrix and its relative error, measured
    along three probes v (ones, two seeded random): ‖(Ĝ − G)v‖ / (‖v‖·max|Ĝ|) with Gv from
    ``solve_KFF`` (solves with K̃_FF refined against it); charged ×PROBE_SAFETY, at least
    SCHUR_ERROR_FLOOR.  ``schur``: σ → X, e.g. :meth:`~.condenser.Condenser.schur_at`.  Returns
    ``(relative error, X)``."""
    X = schur(0.0)
    G = from_bordered_schur(pieces, 0.0, X, 0.0).G()
    J, F = pieces.J, pieces.F
    rng = np.random.default_rng(14)
    V = np.column_stack([np.ones(J.size), rng.standard_normal((J.size, 2))])
    # H(0) = K̃ + N with N in the rows J only: H_FJ = K̃_FJ = K̃_JFᵀ (rows J sliced, not all of H(0))
    K_J, H_J = pieces.Kt[J].tocsc(), (pieces.Kt[J] + pieces.N[J]).tocsc()
    XF = solve_KFF(K_J[:, F].T @ V)
    GV = H_J[:, J] @ V - H_J[:, F] @ XF
    rel = np.linalg.norm(G @ V - GV, axis=0) / (np.linalg.norm(V, axis=0) * max(np.abs(G).max(), 1e-300))
    return float(max(PROBE_SAFETY * rel.max(), SCHUR_ERROR_FLOOR)), X
