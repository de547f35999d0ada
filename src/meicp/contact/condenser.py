"""The condensation of one contact state's pencil onto its complementarity DOFs, on MUMPS and
certified: the pieces of :mod:`.condensation` from a lattice and its maps, a proof that the
lattice is held once the contact DOFs are (K̃_FF ≻ 0), and the condensed G(σ) with an error
bound, for :mod:`.divergence_proof` and :mod:`.critical_friction`.

Two ways (``method``):

* ``"solves"``: one MUMPS Cholesky of H_FF(σ) per σ and |J| right-hand sides; the error is
  *bounded* from the residuals and a certified τ ≤ λ_min(K̃_FF, M̃_FF) (half a SLEPc estimate,
  proved by one MUMPS inertia).  Needs a diagonal M̃_FF.
* ``"schur"``: MUMPS' Schur complement of the bordered matrix (:meth:`PencilPieces.bordered`)
  onto J and |J| extra rows, one factorisation per σ; it has no residual, so its error is
  *measured* once, at σ = 0, along three probe vectors with a separate MUMPS factor of K̃_FF,
  and charged ``PROBE_SAFETY`` times over (a measurement, not a bound).

``"auto"``: solves while |F|·|J| ≤ ``SOLVES_LIMIT`` and the mass is diagonal, else Schur.
Collective on ``comm`` (every rank holds the SciPy pieces; MUMPS factors them distributed).
"""
from __future__ import annotations

import time
from contextlib import nullcontext

import numpy as np
import scipy.sparse as sp

from ..core.threads import dense_phase
from ..lattice.assembly import assemble_scipy
from ..petsc.eigen import solve_ghep
from ..petsc.inertia import nonnegative_count, pencil_is_negative, rounding_margin
from ..petsc.mat import destroying, mat_from_scipy
from ..petsc.schur import MumpsFactor, dense_schur, mumps_factor
from .condensation import Condensed, PencilPieces, condense, from_bordered_schur, pieces_of

#: ``method="auto"`` condenses by solves (rigorous error bound) while |F|·|J| stays below this
SOLVES_LIMIT = 2e7
#: the Schur complement's measured relative error is charged this many times over
PROBE_SAFETY = 100.0
#: floor of the charged relative error of a Schur complement (MUMPS' backward error level)
SCHUR_ERROR_FLOOR = 1e-13
#: SLEPc options of the estimate of λ_min(K̃_FF, M̃_FF) (half of it is certified)
TAU_EPS = {"eps_tol": 1e-3, "eps_ncv": 6, "eps_purify": False}


class Condenser:
    """``Condenser(comm, model, maps, friction=...)`` (K, M: the lattice's SciPy matrices if
    already assembled): the split pencil (``pieces``) and
    :meth:`at` (σ) → :class:`~.condensation.Condensed`.  After :meth:`prepare`, ``ready`` says
    whether the condensation is certified usable and ``why`` says why not; ``tau`` is the
    certified λ_min bound (None for the Schur method without windows).  Collective."""

    def __init__(self, comm, model, maps, *, friction: str = "scene", method: str = "auto", K=None, M=None):
        if method not in ("auto", "schur", "solves"):
            raise ValueError(f"method must be 'auto', 'schur' or 'solves', got {method!r}")
        if K is None or M is None:
            K, M = assemble_scipy(model)
        self.comm = comm
        self.pieces: PencilPieces = pieces_of(K, M, maps, friction=friction)
        F, J = self.pieces.F, self.pieces.J
        if method == "auto":
            method = "solves" if F.size * J.size <= SOLVES_LIMIT and self._diagonal_FF() else "schur"
        self.method = method
        self.tau: float | None = None
        self.relative_error: float | None = None
        self.ready, self.why = False, "not prepared"
        self.seconds: dict = {}
        self._schur0: Condensed | None = None
        self._factor0: MumpsFactor | None = None

    def __enter__(self) -> "Condenser":
        return self

    def __exit__(self, *exc) -> None:
        self.destroy()

    def destroy(self) -> None:
        """Free the kept MUMPS factor of K̃_FF (collective)."""
        if self._factor0 is not None:
            self._factor0.destroy()
            self._factor0 = None

    def _diagonal_FF(self) -> bool:
        MFF = self.pieces.Mt[self.pieces.F][:, self.pieces.F]
        return (MFF - sp.diags(MFF.diagonal())).count_nonzero() == 0

    def prepare(self, *, need_tau: bool, keep_factor: bool = False) -> bool:
        """Prove K̃_FF ≻ 0 (and τ when ``need_tau`` or the solves method need it) and, for the
        Schur method, measure its error (keeping G(0) and, with ``keep_factor``, the factor of
        K̃_FF for :meth:`factor_FF`).  Returns ``ready``."""
        t = time.perf_counter()
        F = self.pieces.F
        KFF = self.pieces.Kt[F][:, F].tocsr()
        MFF = self.pieces.Mt[F][:, F].tocsr()
        # the Schur method's probe needs a factor of K̃_FF: factored first, the τ estimate's
        # shift-and-invert reuses it (one factorisation of K̃_FF, not two)
        factor = (MumpsFactor(self.comm, KFF, symmetric=True)
                  if F.size and self.method == "schur" and need_tau else None)
        try:
            if F.size == 0:
                self.tau, self.ready, self.why = np.inf, True, ""
            elif need_tau or self.method == "solves":
                self.tau, self.why = certified_tau(self.comm, KFF, MFF, factor=factor)
                self.ready = self.tau is not None
            else:
                self.ready, self.why = held(self.comm, KFF)
            self.seconds["held"] = time.perf_counter() - t
            if self.ready and self.method == "schur":
                t = time.perf_counter()
                if factor is None:
                    factor = MumpsFactor(self.comm, KFF, symmetric=True)
                self.relative_error, X = schur_error(self.comm, self.pieces, factor.solve)
                if keep_factor:
                    self._factor0, factor = factor, None
                self._schur0 = from_bordered_schur(self.pieces, 0.0, X, self.relative_error)
                self.seconds["probe"] = time.perf_counter() - t
        finally:
            if factor is not None:
                factor.destroy()
        return self.ready

    def at(self, sigma: float, *, xi: bool = True) -> Condensed:
        """G(σ) = S + R (and the Ξ blocks) with its error.  Collective."""
        if self.method == "solves":
            return condense(self.pieces, sigma, mumps_factor(self.comm), tau=self.tau, xi=xi)
        if sigma == 0 and self._schur0 is not None:
            return self._schur0
        H, rows = self.pieces.bordered(sigma)
        return from_bordered_schur(self.pieces, sigma, dense_schur(self.comm, H, rows, symmetric=True),
                                   self.relative_error)

    def error_text(self) -> str:
        if self.method == "solves":
            return "condensation error bounded from the MUMPS solves' residuals"
        return (f"condensation by MUMPS' Schur complement, error measured ({self.relative_error:.1e} relative, "
                "charged; a measurement, not a bound)")

    def factor_FF(self, sigma: float = 0.0):
        """A MUMPS factor of H_FF(σ) as a context manager giving the solve, e.g. to lift x_J
        (the kept factor of K̃_FF at σ = 0, left open for :meth:`destroy`)."""
        if sigma == 0 and self._factor0 is not None:
            return nullcontext(self._factor0.solve)
        F = self.pieces.F
        return MumpsFactor(self.comm, (sigma * self.pieces.Mt + self.pieces.Kt)[F][:, F], symmetric=True)


def held(comm, KFF) -> tuple[bool, str]:
    """Whether K̃_FF ≻ 0 is proved: one MUMPS inertia of −K̃_FF + η·diag (rounding margin η)."""
    with destroying(mat_from_scipy(comm, (-KFF).tocsr())) as (A,):
        count = nonnegative_count(A, rounding_margin(KFF.shape[0]))
    if count == 0:
        return True, ""
    return False, (f"K̃_FF is not proved positive definite ({count} eigenvalue(s) of the diagonally scaled −K̃_FF "
                   "within rounding of 0 or above): the lattice is not held once the contact DOFs are")


def certified_tau(comm, KFF, MFF, *, factor: MumpsFactor | None = None) -> tuple[float | None, str]:
    """A certified lower bound τ > 0 of λ_min(K̃_FF, M̃_FF): half a SLEPc estimate, proved by
    the inertia of τM̃_FF − K̃_FF (:func:`~meicp.petsc.inertia.pencil_is_negative`), which
    also proves K̃_FF ≻ 0.  ``factor``: a :class:`MumpsFactor` of K̃_FF that the estimate's
    shift-and-invert reuses.  ``(None, why)`` when not certified."""
    owned = factor is None
    Kp = mat_from_scipy(comm, KFF) if owned else factor.A
    with destroying(mat_from_scipy(comm, MFF)) as (Mp,):
        try:
            # half the estimate is certified below: a loose tolerance, a short basis and no
            # purification of the vector are enough (3·10⁵ DOFs: 0.47 s instead of 1.17 s)
            pairs = solve_ghep(Kp, Mp, nev=1, target=0.0, options=TAU_EPS, ksp=None if owned else factor.ksp)
            est = float(pairs.values[0])
            for v in pairs.vectors:
                v.destroy()
        except Exception as exc:  # noqa: BLE001 — no estimate means no proof, not an error
            first = (str(exc).strip().splitlines() or [type(exc).__name__])[0]  # not PETSc's whole stack
            return None, f"λ_min(K̃_FF, M̃_FF) not estimated ({first}): the condensation is not certified"
        finally:
            if owned:
                Kp.destroy()
        if not est > 0:
            return None, (f"K̃_FF is not positive definite (λ_min ≈ {est:.2e}): the lattice is not held once the "
                          "contact DOFs are, the condensation is undefined")
        tau = 0.5 * est
        with destroying(mat_from_scipy(comm, (tau * MFF - KFF).tocsr())) as (Ap,):
            sign = pencil_is_negative(Ap, Mp, symmetric=True)  # K̃_FF symmetrised, M̃_FF = Q̃ᵀMQ̃
    if sign is None or sign.proved is not True:
        return None, f"τ = {tau:.3e} ≤ λ_min(K̃_FF, M̃_FF) not certified ({'' if sign is None else sign.reason})"
    return tau, ""


def schur_error(comm, pieces: PencilPieces, solve_KFF) -> tuple[float, np.ndarray]:
    """MUMPS' Schur complement X of the σ = 0 bordered matrix and its relative error, measured
    along three probes v (ones, two seeded random): ‖(Ĝ − G)v‖ / (‖v‖·max|Ĝ|) with Gv from
    ``solve_KFF`` (a separate factor of K̃_FF); charged ×PROBE_SAFETY, at least
    SCHUR_ERROR_FLOOR.  Returns ``(relative error, X)``."""
    H, rows = pieces.bordered(0.0)
    X = dense_schur(comm, H, rows, symmetric=True)
    G = from_bordered_schur(pieces, 0.0, X, 0.0).G()
    J, F = pieces.J, pieces.F
    rng = np.random.default_rng(14)
    V = np.column_stack([np.ones(J.size), rng.standard_normal((J.size, 2))])
    H0 = pieces.H(0.0).tocsr()
    XF = solve_KFF(H0[F][:, J] @ V)
    GV = H0[J][:, J] @ V - H0[J][:, F] @ XF
    rel = np.linalg.norm(G @ V - GV, axis=0) / (np.linalg.norm(V, axis=0) * max(np.abs(G).max(), 1e-300))
    return float(max(PROBE_SAFETY * rel.max(), SCHUR_ERROR_FLOOR)), X


def on_root(comm, fn):
    """``fn()`` run on rank 0 and its result broadcast; an exception raised there is raised on
    every rank (no rank left waiting).  Serial: just ``fn()``.  ``fn`` is a dense phase: its
    BLAS threads are bounded (:mod:`meicp.core.threads`).  Collective."""
    if comm is None or comm.Get_size() == 1:
        with dense_phase():
            return fn()
    outcome = None
    if comm.Get_rank() == 0:
        try:
            with dense_phase():
                outcome = (True, fn())
        except Exception as exc:  # noqa: BLE001 — re-raised below, on every rank
            outcome = (False, exc)
    ok, value = comm.bcast(outcome, root=0)
    if not ok:
        raise value
    return value

