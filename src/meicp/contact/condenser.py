"""The condensation of one contact state's pencil onto its complementarity DOFs, on MUMPS and
certified: the pieces of :mod:`.condensation` from a lattice and its maps, a proof that the
lattice is held once the contact DOFs are (K̃_FF ≻ 0), and the condensed G(σ) with an error
bound, for :mod:`.divergence.condensed` and :mod:`.critical_friction`.

Two ways (``method``):

* ``"solves"``: one MUMPS Cholesky of H_FF(σ) per σ and |J| right-hand sides; the error is
  *bounded* from the residuals and a certified τ ≤ λ_min(K̃_FF, M̃_FF) (half a SLEPc estimate,
  proved by one MUMPS inertia).  Needs a diagonal M̃_FF.
* ``"schur"``: MUMPS' Schur complement of the bordered matrix (:meth:`PencilPieces.bordered`)
  onto J and |J| extra rows, one block-low-rank factorisation per σ
  (:data:`~meicp.petsc.schur.SCHUR_LOW_RANK`); it has no residual, so its error is
  *measured* once, at σ = 0, along three probe vectors solved with K̃_FF, and charged
  ``PROBE_SAFETY`` times over (a measurement, not a bound).  Everything else happens on the
  Schur complements' own MUMPS instance, one analysis for all of it
  (:meth:`Condenser._prepare_on_series`): the probe solves and SLEPc's estimate of λ_min use
  its interior block at σ = 0, which is K̃_FF, and one full-rank factorisation of its interior
  shifted by −t·M̃_FF − 2ηD proves by its inertia that the lattice is held and certifies the
  τ the σ-windows need (there were three factorisations with three analyses: K̃_FF, its
  inertia, τM̃_FF − K̃_FF).  Where no DMUMPS library of a known version loads
  (:func:`meicp.petsc.mumps_c.load`), PETSc's factors do it
  (:func:`~.condenser_certificates.held_factor`,
  :func:`~.condenser_certificates.estimate_lambda_min`, :meth:`Condenser.sharper_tau`: only
  this fallback uses them).

``"auto"``: solves while |F|·|J| ≤ ``limits.SOLVES_LIMIT`` and the mass is diagonal, else Schur.
Collective on ``comm`` (every rank holds the SciPy pieces, built from the lattice's K and M
read whole, :meth:`Condenser.of`; MUMPS factors them distributed).  The
certificates themselves are in :mod:`.condenser_certificates`.
"""
from __future__ import annotations

import logging
import time
from contextlib import nullcontext
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from ..core import limits
from ..lattice.node_blocks import NodeBlocks, node_of
from ..petsc.comm import to_petsc_comm
from ..petsc.eigen import inverse_estimate
from ..petsc.inertia import diagonal_scale, rounding_margin
from ..petsc.mumps_c import MumpsError
from ..petsc.options import SCHUR
from ..petsc.schur import MumpsFactor, mumps_factor, schur_series
from .condensation import Condensed, PencilPieces, condense, from_bordered_schur, pieces_of
from .condenser_certificates import (TAU_EPS, certified_tau, estimate_lambda_min, held_factor, refined_solve,
                                     schur_error, tau_inertia)

log = logging.getLogger("meicp")

#: MUMPS' INFOG(1) for a numerically singular matrix
SINGULAR = -10


class Condenser:
    """``Condenser(comm, maps, K, M, friction=...)`` (K, M: the lattice's SciPy matrices, whole
    on every rank; :meth:`of` takes them from a pencil): the split pencil (``pieces``) and
    :meth:`at` (σ) → :class:`~.condensation.Condensed`.  After :meth:`prepare`, ``ready`` says
    whether the condensation is certified usable and ``why`` says why not; ``tau`` is the
    certified λ_min bound (None for the Schur method without windows).  Collective."""

    def __init__(self, comm, maps, K, M, *, friction: str = "scene", method: str = "auto"):
        if method not in ("auto", "schur", "solves"):
            raise ValueError(f"method must be 'auto', 'schur' or 'solves', got {method!r}")
        self.comm = comm
        self.pieces: PencilPieces = pieces_of(K, M, maps, friction=friction)
        F, J = self.pieces.F, self.pieces.J
        # MUMPS orders whole nodes only when their DOFs share a pattern (lattice.node_blocks):
        # one padding for H_FF (every σ), one for the bordered matrix (its |J| extra rows alone)
        nodes = node_of(maps.retained)
        self.pad_FF = NodeBlocks(nodes[F]).pad
        self.pad_bordered = NodeBlocks(np.concatenate([nodes, nodes.max(initial=-1) + 1 + np.arange(J.size)])).pad
        if method == "auto":
            method = "solves" if F.size * J.size <= limits.SOLVES_LIMIT and self._diagonal_FF() else "schur"
        self.method = method
        self.tau: float | None = None
        self.relative_error: float | None = None
        self.ready, self.why = False, "not prepared"
        self.seconds: dict = {}
        self._schur0: Condensed | None = None
        self._series = None  # the Schur complements of 𝓗(σ), one MUMPS analysis for every σ
        self._factor0: MumpsFactor | None = None
        self._solve0 = None
        #: where the windows are split (:func:`~.divergence.cover.cover`): half SLEPc's estimate of
        #: λ_min(K̃_FF, M̃_FF), or the certified ``tau`` when that is larger (on the Schur
        #: series' instance, where half the estimate is certified, the two are equal)
        self.tau_scale: float | None = None

    @classmethod
    def of(cls, pencil, comm=None, **options) -> "Condenser":
        """The condenser of a :class:`~meicp.contact.problem.Pencil`'s maps, from its lattice's
        K and M whole on every rank (:meth:`~meicp.petsc.assembly.LatticeMatrices.whole`: the
        pencil's own when serial, a serial copy on each rank when distributed), dropped once the
        pieces are split off them.  ``comm``: the communicator MUMPS factors on (default the
        pencil's)."""
        K, M = pencil.lattice.whole()
        return cls(pencil.comm if comm is None else comm, pencil.maps, K, M, **options)

    def __enter__(self) -> "Condenser":
        return self

    def __exit__(self, *exc) -> None:
        self.destroy()

    def destroy(self) -> None:
        """Free the kept MUMPS factor of K̃_FF and the Schur complements' MUMPS instance
        (collective)."""
        if self._factor0 is not None:
            self._factor0.destroy()
            self._factor0 = None
        if self._series is not None:
            self._series.destroy()
            self._series = None
        self._solve0 = None  # its solves were the factor's or the series

    @cached_property
    def blocks_FF(self) -> tuple[sp.csr_matrix, sp.csr_matrix]:
        """``(K̃_FF, M̃_FF)``, sliced once: the held proof, the sharper τ and the choice of method
        all read them, and a slice is not free at scale (docs/benchmarks-notes.md)."""
        F = self.pieces.F
        return self.pieces.Kt[F][:, F].tocsr(), self.pieces.Mt[F][:, F].tocsr()

    def _diagonal_FF(self) -> bool:
        MFF = self.blocks_FF[1]
        return (MFF - sp.diags(MFF.diagonal())).count_nonzero() == 0

    def prepare(self, *, need_tau: bool, keep_factor: bool = False) -> bool:
        """Prove K̃_FF ≻ 0 (with a certified τ when ``need_tau`` or the solves method need it)
        and, for the Schur method, measure its error (keeping G(0) and, with ``keep_factor``,
        the factor of K̃_FF for :meth:`factor_FF`).  Returns ``ready``.

        The Schur method factors on the Schur series' own MUMPS instance, one analysis for
        everything (:meth:`_prepare_on_series`); where the series has no interior solves (the
        PETSc fallback), one factorisation of its own, :func:`held_factor`'s: its inertia is
        the proof that the lattice is held (and gives a certified τ > 0, tiny but enough for
        the windows' chords, whose σ-ends sit far above λ_min), SLEPc's estimate of λ_min that
        only places the windows reuses it, and the probe solves with K̃_FF by refining on it."""
        t = time.perf_counter()
        F = self.pieces.F
        KFF, MFF = self.blocks_FF
        factor = None
        try:
            if F.size == 0:
                self.tau, self.ready, self.why = np.inf, True, ""
            elif self.method == "solves":
                self.tau, self.why = certified_tau(self.comm, KFF, MFF, pad=self.pad_FF)
                self.ready = self.tau is not None
            elif getattr(self.series, "interior", False):
                return self._prepare_on_series(need_tau)
            else:
                factor, self.tau, self.why = held_factor(self.comm, KFF, MFF, pad=self.pad_FF)
                self.ready = factor is not None
                if self.ready and need_tau:
                    self.tau_scale = max(self.tau, 0.5 * estimate_lambda_min(factor, MFF))
            self.seconds["held"] = time.perf_counter() - t
            if self.ready and self.method == "schur":
                t = time.perf_counter()
                solve = refined_solve(factor, KFF)
                self.relative_error, X = schur_error(self.comm, self.pieces, solve, schur=self.schur_at)
                if keep_factor:
                    self._factor0, self._solve0, factor = factor, solve, None
                self._schur0 = from_bordered_schur(self.pieces, 0.0, X, self.relative_error)
                self.seconds["probe"] = time.perf_counter() - t
        finally:
            if factor is not None:
                factor.destroy()
        return self.ready

    def _prepare_on_series(self, need_tau: bool) -> bool:
        """:meth:`prepare` on the Schur series' MUMPS instance (its interior block is H_FF(σ)),
        one analysis for everything:

        * the proof: 𝓗(−t) with −2ηD added on F, factored full rank with null pivot detection;
          no negative or null pivot means K̃_FF − tM̃_FF ≻ ηD ≻ 0 up to the factorisation's
          rounding (one η, as in :func:`held_factor`): the lattice is held, and
          τ = t + η·min(D/M̃_FF) ≤ λ_min(K̃_FF, M̃_FF) is certified.  t = 0 without ``need_tau``;
          with it, half SLEPc's estimate of λ_min (and t = 0 where that fails);
        * 𝓗(0) factored (block low rank): G(0), and the interior solves with K̃_FF that
          measure its error along the probes (refined against K̃_FF), give the estimate, and
          are kept for :meth:`factor_FF`.

        Two factorisations (three where t = ½·estimate is not certified); the PETSc way made
        three, each with its analysis (held factor, G(0) and the sharper τ; the cost of each way
        is in docs/benchmarks-notes.md).
        The solves with K̃_FF are always kept (``keep_factor`` costs nothing here): used after
        the series has factored another matrix, they factor 𝓗(0) again first."""
        clock = time.perf_counter()
        series, pieces = self.series, self.pieces
        KFF, MFF = self.blocks_FF
        F = pieces.F
        eta = rounding_margin(F.size)
        d = diagonal_scale(KFF)
        m = MFF.diagonal()
        diagonal = bool(self._diagonal_FF() and m.size and m.min() > 0)
        shift = np.zeros(series.n)
        shift[F] = -2.0 * eta * d

        def held(t: float) -> bool:
            try:
                negative, null = series.factor(-t, diagonal=shift, exact=True)
            except MumpsError as error:  # e.g. more delayed pivots than the analysis foresaw
                if t == 0:               # (an estimate past λ_min: K̃_FF − tM̃_FF indefinite)
                    raise
                log.info("condenser: the factorisation at t = %.3g failed (%s); t = 0 next", t, error)
                return False
            if negative or null:
                self.ready, self.why = False, (
                    f"K̃_FF is not proved positive definite ({negative + null} pivot(s) of K̃_FF − 2η·diag (η = "
                    f"{eta:.1e}) not positive): the lattice is not held once the contact DOFs are")
                return False
            self.tau = t + (float(eta * np.min(d / m)) if diagonal else 0.0)
            self.ready, self.why = True, ""
            return True

        def lap(name):
            nonlocal clock
            now = time.perf_counter()
            self.seconds[name] = self.seconds.get(name, 0.0) + now - clock
            clock = now

        if not need_tau and not held(0.0):
            lap("held")
            return False
        lap("held")
        try:
            negative, _ = series.factor(0.0)
        except MumpsError as error:
            if error.code != SINGULAR:
                raise
            negative = -1
        if negative:  # the block-low-rank factor of K̃_FF: no proof either way, but no use
            self.ready, self.why = False, (
                "K̃_FF is not proved positive definite (" + ("numerically singular" if negative < 0 else
                                                            f"{negative} negative pivot(s)") +
                "): the lattice is not held once the contact DOFs are")
            lap("probe")
            return False
        X = series.schur_complement()
        interior = InteriorSolve(self.comm, series, F, 0.0)
        solve = refined_solve(interior, KFF)
        self.relative_error, _ = schur_error(self.comm, pieces, solve, schur=lambda _sigma: X)
        self._schur0 = from_bordered_schur(pieces, 0.0, X, self.relative_error)
        self._solve0 = solve
        lap("probe")
        if need_tau:
            estimate = 0.0
            if diagonal:
                estimate = inverse_estimate(to_petsc_comm(self.comm), interior.on_host, m, prefix=SCHUR,
                                            options=TAU_EPS)
            if not (estimate > 0 and held(0.5 * estimate)) and not held(0.0):
                lap("held")
                return False
            # where the windows are split: the certified τ, or half the estimate where that was
            # not certified (a placement, not a bound: an η-level τ would split at a tiny scale)
            self.tau_scale = max(self.tau, 0.5 * estimate)
            lap("held")
        return self.ready

    def sharper_tau(self) -> float:
        """Certify ``tau_scale`` as τ by one more inertia (of τM̃_FF − K̃_FF), for chords near
        σ = 0 where the tiny τ of :func:`held_factor` costs windows; returns the certified τ (the
        old one when this fails).  Collective."""
        if self.tau_scale is not None and self.tau is not None and self.tau_scale > self.tau:
            t = time.perf_counter()
            if not tau_inertia(self.comm, *self.blocks_FF, self.tau_scale, pad=self.pad_FF):
                self.tau = self.tau_scale
            self.seconds["tau"] = time.perf_counter() - t
        return self.tau

    def at(self, sigma: float, *, xi: bool = True) -> Condensed:
        """G(σ) = S + R (and the Ξ blocks) with its error.  Collective."""
        if self.method == "solves":
            factor = mumps_factor(self.comm)
            return condense(self.pieces, sigma, lambda H: factor(self.pad_FF(H)), tau=self.tau, xi=xi)
        if sigma == 0 and self._schur0 is not None:
            return self._schur0
        return from_bordered_schur(self.pieces, sigma, self.schur_at(sigma), self.relative_error)

    @property
    def series(self):
        """The Schur complements of 𝓗(σ), one MUMPS analysis for every σ
        (:func:`~meicp.petsc.schur.schur_series`), made at the first use.  Collective then."""
        if self._series is None:
            self._series = schur_series(self.comm, *self.padded_parts)
        return self._series

    def schur_at(self, sigma: float) -> np.ndarray:
        """MUMPS' Schur complement of 𝓗(σ) onto its Schur rows (dense, every rank).  Collective."""
        return self.series(sigma)

    @cached_property
    def padded_parts(self) -> tuple[sp.csr_matrix, sp.csr_matrix, np.ndarray]:
        """``(𝓗₀, 𝓗₁, rows)`` of the pieces' bordered matrix, both padded to node blocks on one
        pattern (the union of theirs), once."""
        H0, H1, rows = self.pieces.bordered_parts()
        self.pad_bordered((abs(H0) + abs(H1)).tocsr())  # the union of both patterns, padded
        return self.pad_bordered(H0), self.pad_bordered(H1), rows

    def error_text(self) -> str:
        if self.method == "solves":
            return "condensation error bounded from the MUMPS solves' residuals"
        return (f"condensation by MUMPS' Schur complement, error measured ({self.relative_error:.1e} relative, "
                "charged; a measurement, not a bound)")

    def factor_FF(self, sigma: float = 0.0):
        """A MUMPS factor of H_FF(σ) as a context manager giving the solve, e.g. to lift x_J
        (the kept factor of K̃_FF at σ = 0, left open for :meth:`destroy`)."""
        if sigma == 0 and self._solve0 is not None:
            return nullcontext(self._solve0)
        F = self.pieces.F
        H_FF = (sigma * self.pieces.Mt + self.pieces.Kt)[F][:, F]
        return MumpsFactor(self.comm, self.pad_FF(H_FF), symmetric=True)


class InteriorSolve:
    """Solves with H_FF(σ) on the Schur series' instance (its interior block), F the interior
    rows: :meth:`solve` takes and returns whole vectors or blocks on every rank (for
    :func:`refined_solve`), :meth:`on_host` on rank 0 only (for SLEPc's shell operator).  The
    series is factored at σ again first if it holds another matrix since."""

    def __init__(self, comm, series, F: np.ndarray, sigma: float):
        self.comm, self.series, self.F, self.sigma = comm, series, F, sigma

    def on_host(self, rhs: np.ndarray | None) -> np.ndarray | None:
        if self.series.factored[:2] != (self.sigma, False):
            self.series.factor(self.sigma)
        full = None
        if self.series.host:
            full = np.zeros((self.series.n,) + rhs.shape[1:])
            full[self.F] = rhs
        x = self.series.solve(full)
        return None if x is None else x[self.F]

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        x = self.on_host(rhs)
        return x if self.comm is None or self.comm.Get_size() == 1 else self.comm.bcast(x, root=0)
