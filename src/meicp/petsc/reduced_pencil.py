"""Eigenpairs of a pencil restricted to a changing index set, with SLEPc, cheaply.

The active-set EiCP solver asks many times for eigenpairs of ``(A_RR, B_RR)`` with
``R = F ∪ S`` and S changing a few indices at a time.  Instead of extracting submatrices,
the removed rows and columns are zeroed in work copies of A and B (same size, same
nonzero pattern) with ``A_ii = α``, ``B_ii = 1`` on them: the pencil then has the reduced
pencil's eigenpairs (eigenvectors zero on the removed set) plus a spurious eigenvalue α
placed far from the target, where shift-and-invert never looks.  Because the pattern
never changes, MUMPS' symbolic factorisation is reused and only the numeric one is redone;
the previous wanted eigenvector is the next solve's initial space.

Options live under a prefix (default ``meicp_as_``): ``eps_*``, ``st_*`` — e.g.
``-meicp_as_eps_nev 8 -meicp_as_st_pc_factor_mat_solver_type superlu_dist``.  They are in
the options database during every solve (so that those read at solve time, such as
``eps_view``, take effect from a scene's ``[petsc]`` table as from the command line), and
the ones that no solve read are reported once, when the solver is closed.  Collective.
"""

from __future__ import annotations

import numpy as np

from . import import_petsc, import_slepc
from .mat import vec_to_numpy
from .options import ACTIVE_SET, OptionsScope, petsc_errors, report_unused, st_low_rank, st_node_pairs

#: MUMPS factors A − τB block-low-rank at this dropping tolerance (ICNTL(35) = 2, CNTL(7)) and
#: on the graph of node pairs (ICNTL(15) = −2 for an even order: `options.st_node_pairs`), as
#: the flutter search does
#: (`meicp.petsc.flutter.LOW_RANK_TOL`): the shipped 10⁶-DOF `extensive_contact.toml`, whose
#: first search converges in one restart, spent 29.6 s in the divergence verdict full rank,
#: 24.0 s block-low-rank, 20.8 s with both, the same certified mode (residual 1.8e-15)
#: (docs/benchmarks-notes.md, "SEARCH_LOW_RANK")
SEARCH_LOW_RANK = 1e-10
#: the fall of a Ritz value's error estimate per restart that lets a solve with
#: ``converging_after`` go on (:meth:`ReducedPencilSolver._give_up_when_hopeless`)
FAST_CONVERGENCE = 10.0


class ReducedPencilSolver:
    """Shift-and-invert SLEPc solves of ``A ξ = λ B ξ`` on ``R = complement of removed``.

    A, B: PETSc Mats (same layout).  symmetric: both symmetric (GHEP) or not (GNHEP).
    target: the shift τ; pairs are returned nearest τ in real part.  spurious: the value α
    given to removed DOFs.  A context manager: leaving the ``with`` block (or
    :meth:`destroy`, collective) reports the unused options and frees the PETSc objects::

        with ReducedPencilSolver(A, B, symmetric=True, target=0.0, spurious=-1e6) as solver:
            pairs = solver.solve(removed)
    """

    def __init__(self, A, B, *, symmetric: bool, target: float, spurious: float, nev: int = 4,
                 prefix: str = ACTIVE_SET, options: dict | None = None, give_up: tuple | None = None):
        PETSc = import_petsc()
        SLEPc = import_slepc()
        # A and B copied into their union pattern, so that (A − τB) and the zeroed work
        # copies all share one pattern and MUMPS' symbolic factorisation can be reused
        self.A, self.B = _in_union_pattern(A, B), _in_union_pattern(B, A)
        self.Aw = self.A.duplicate(copy=True)
        self.Bw = self.B.duplicate(copy=True)
        self.symmetric = symmetric
        self.target, self.spurious = float(target), float(spurious)
        self.prefix = prefix
        self.eps = SLEPc.EPS().create(comm=A.getComm())
        defaults = {
            "eps_nev": nev,
            "eps_target": self.target,
            "eps_target_real": True,
            "eps_tol": 1e-12,
            "eps_max_it": 1000,
            "st_type": "sinvert",
            "st_ksp_type": "preonly",
            "st_pc_type": "lu",
            "st_pc_factor_mat_solver_type": "mumps",
            # AMF ordering: Debian's MUMPS has no METIS/SCOTCH and picks PORD, which was
            # 1.05-1.36x slower per eigen-solve from 3e5 to 1e6 DOFs (docs/benchmarks.md, scaling)
            "st_mat_mumps_icntl_7": 2,
            **st_low_rank(SEARCH_LOW_RANK),
            **st_node_pairs(A.getSize()[0]),
        }
        defaults["eps_gen_hermitian" if symmetric else "eps_gen_non_hermitian"] = True
        self._defaults = defaults
        self._options = options
        self.eps.setOptionsPrefix(prefix)
        st = self.eps.getST()
        st.setMatStructure(PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
        #: options under the prefix that no solve so far has read
        self.unused_options: list = []
        self.solves = 0
        self.eps_iterations = 0
        self._configured = False
        self._closed = False
        #: (restarts, floor[, converging_after]): a solve stops after that many Krylov–Schur
        #: restarts when no Ritz value, back-transformed, has a real part ≥ floor, and after
        #: ``converging_after`` restarts unless one of those converges fast
        #: (:meth:`_give_up_when_hopeless`)
        self.give_up = give_up
        self.gave_up = 0

    @petsc_errors("a SLEPc eigen-solve of the reduced pencil")
    def solve(self, removed: np.ndarray, initial: np.ndarray | None = None, *,
              target: float | None = None, nev: int | None = None):
        """Converged real eigenpairs ``[(λ, ξ, relative_residual)]`` of the pencil without
        the ``removed`` DOFs (global indices, same on every rank), nearest the target first.
        ``target``/``nev`` override the configured ones for this solve (e.g. to follow one
        eigenpair with a shift at its previous eigenvalue).  ξ is a NumPy array on every
        rank.  A PETSc or SLEPc error is raised as :class:`~meicp.core.errors.PetscSolveError`.
        Collective."""
        PETSc = import_petsc()
        SLEPc = import_slepc()
        same = PETSc.Mat.Structure.SAME_NONZERO_PATTERN
        self.A.copy(self.Aw, structure=same)
        self.B.copy(self.Bw, structure=same)
        lo, hi = self.Aw.getOwnershipRange()
        mine = removed[(removed >= lo) & (removed < hi)].astype(PETSc.IntType)
        self.Aw.zeroRowsColumns(mine, diag=self.spurious)
        self.Bw.zeroRowsColumns(mine, diag=1.0)
        self.eps.setOperators(self.Aw, self.Bw)
        if initial is not None:
            v = self.Aw.createVecRight()
            v.setArray(initial[lo:hi])
            self.eps.setInitialSpace([v])
        with OptionsScope(self.prefix, self._defaults, self._options, warn=False) as scope:
            first = not self._configured
            if first:
                scope.configure(self.eps)
                self.eps.setUp()
                self._configured = True
                self._target = self.eps.getTarget()
                self._dimensions = self.eps.getDimensions()
            self.eps.setTarget(self._target if target is None else target)
            nev_c, ncv_c, mpd_c = self._dimensions
            # a followed pair (nev given) sits next to the shift: a small basis converges at once
            self.eps.setDimensions(nev=nev_c if nev is None else nev, ncv=ncv_c if nev is None else nev + 4,
                                   mpd=mpd_c if nev is None else PETSc.DECIDE)
            if first and self.give_up is not None:
                self._give_up_when_hopeless(*self.give_up)
            self.eps.solve()
        self.unused_options = scope.unused if first else [n for n in self.unused_options if n in scope.unused]
        self.solves += 1
        self.eps_iterations += self.eps.getIterationNumber()
        pairs = []
        xr, xi = self.Aw.createVecRight(), self.Aw.createVecRight()
        removed_set = np.zeros(self.Aw.getSize()[0], dtype=bool)
        removed_set[removed] = True
        for i in range(self.eps.getConverged()):
            lam = self.eps.getEigenpair(i, xr, xi)
            if abs(lam.imag) > 1e-10 * max(1.0, abs(lam.real)):
                continue  # complex pair: no real eigenvector
            x = vec_to_numpy(xr)
            nrm = np.abs(x).max()
            if removed.size and np.abs(x[removed_set]).max() > 1e-6 * nrm:
                continue  # a spurious pair living on the removed DOFs
            err = self.eps.computeError(i, SLEPc.EPS.ErrorType.RELATIVE)
            pairs.append((float(lam.real), x, float(err)))
        xr.destroy()
        xi.destroy()
        return pairs

    def _give_up_when_hopeless(self, restarts: int, floor: float, converging_after: int | None = None) -> None:
        """A stopping test: after ``restarts`` Krylov–Schur restarts with no Ritz value whose
        eigenvalue estimate (shift-and-invert back-transformed, σ = τ + 1/θ) has a real part
        ≥ ``floor``, the solve ends as if out of iterations.  A search for the rightmost
        eigenvalue above the floor stops early where none stands apart: on a stable lattice
        every Ritz value sits in the cluster of slow vibrations below 0 from the first restart
        on, while a mode's estimate shows above the floor at once (10⁶ DOFs: σ = 0.3255 from
        the first restart, converged in the fourth).  A speed heuristic only: the caller treats
        the solve as not converged, which proves nothing either way.

        SLEPc calls the stopping test after solving the projected problem and before the
        monitor, so the test reads this restart's Ritz values from the projected matrix itself
        (its eigenvalues are the monitor's, in the same restart); where the projected problem
        is stored compactly (a symmetric pencil) it uses the monitor's view of the previous
        restart, one restart later (a restart's cost: docs/benchmarks-notes.md).

        ``converging_after``: from that restart on, the solve also stops unless the smallest
        error estimate of a Ritz value above the floor fell at least ``FAST_CONVERGENCE``-fold
        in the monitor's last restart: a mode one or two restarts from converging is not cut
        off at the cap (the shipped 10⁶-DOF scene coarsened: error 8e-10 at restart 6, 18×
        per restart, converged at 9), while a slow one still stops there."""
        SLEPc = import_slepc()
        eps, seen = self.eps, {"hopeless": False, "restarts": 0}
        if eps.getST().getType() != SLEPc.ST.Type.SINVERT:  # another transform: no back-transform here
            return

        def hopeless(_eps, theta) -> bool:
            theta = np.asarray(theta, dtype=complex)
            theta = theta[theta != 0]
            return theta.size > 0 and bool(np.all((_eps.getTarget() + 1.0 / theta).real < floor))

        def ritz_values_now(_eps):
            ds = _eps.getDS()
            if ds.getType() != SLEPc.DS.Type.NHEP or ds.getCompact():
                return None
            n = ds.getDimensions()[0]
            A = ds.getMat(SLEPc.DS.MatType.A)
            try:
                T = A.getValues(range(n), range(n))
            finally:
                ds.restoreMat(SLEPc.DS.MatType.A, A)
            return np.linalg.eigvals(T)

        def monitor(_eps, its, nconv, eig, err):
            seen["restarts"] = its
            seen["hopeless"] = hopeless(_eps, eig)
            seen["errors"] = [*seen.get("errors", [])[-1:], (its, _best_error_above(_eps, eig, err))]

        def _best_error_above(_eps, theta, err) -> float:
            theta, err = np.asarray(theta, dtype=complex), np.asarray(err, dtype=float)
            keep = theta != 0
            above = (_eps.getTarget() + 1.0 / theta[keep]).real >= floor
            return float(err[keep][above].min()) if above.any() else np.inf

        def converging(its) -> bool:
            errors = seen.get("errors", [])
            if len(errors) < 2 or errors[-1][0] != its - 1 or errors[-2][0] != its - 2:
                return False  # no history of this solve's last two restarts
            return errors[-1][1] * FAST_CONVERGENCE <= errors[-2][1]

        def stopping(_eps, its, max_it, nconv, nev):
            reason = SLEPc.EPS.ConvergedReason
            if nconv >= nev:
                return reason.CONVERGED_TOL
            if its >= max_it:
                return reason.DIVERGED_ITS
            now = ritz_values_now(_eps) if its >= restarts else None
            if (hopeless(_eps, now) if now is not None else
                    # the monitor's view of this solve's previous restart (not of an earlier solve's)
                    seen["hopeless"] and seen["restarts"] == its - 1 >= restarts):
                self.gave_up += 1
                return reason.DIVERGED_ITS
            if converging_after is not None and its >= converging_after and not converging(its):
                return reason.DIVERGED_ITS
            return reason.ITERATING

        # added once, beside any monitor the options asked for
        eps.setMonitor(monitor)
        eps.setStoppingTest(stopping)

    def __enter__(self) -> "ReducedPencilSolver":
        return self

    def __exit__(self, *exc) -> None:
        self.destroy()

    def destroy(self) -> None:
        """Report the options no solve read, free the EPS and work matrices (collective).
        After a failed solve SLEPc may refuse to destroy its half-built state; that is
        ignored (a leak, not a wrong answer)."""
        if self._closed:
            return
        self._closed = True
        PETSc = import_petsc()
        report_unused(self.unused_options)
        for obj in (self.eps, self.Aw, self.Bw, self.A, self.B):
            try:
                obj.destroy()
            except PETSc.Error:
                pass


def _in_union_pattern(X, Y):
    """A copy of X whose nonzero pattern is the union of X's and Y's (exact values of X)."""
    PETSc = import_petsc()
    U = X.duplicate(copy=True)
    U.axpy(1.0, Y, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
    U.zeroEntries()
    U.axpy(1.0, X, structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
    return U
