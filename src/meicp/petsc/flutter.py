"""Flutter eigenpairs of a distributed sliding pencil with SLEPc (docs/flutter.md §4).

The fastest flutter modes sit inside the spectrum among real and weakly complex
eigenvalues, so only a *complex* shift isolates them.  Debian's PETSc here is real-scalar,
so the complex shift-and-invert works on the real equivalent form of order 2n,

    K_τ = kron(A − αB, I₂) + β·kron(B, [[0, 1], [−1, 0]]),   B₂ = kron(B, I₂),   τ = α + iβ,

interleaved (DOF i → rows 2i, 2i+1: every rank keeps its own rows).  The real pencil
(K_τ, B₂) has the eigenvalues {σ − τ} ∪ {σ − τ̄}; shift-and-invert at target 0 (MUMPS LU of
K_τ, with ICNTL(15) = −4: the matrix comes in blocks of 4 rows, a lattice node, so MUMPS
analyses the node graph — blocks of 2 when n is odd) returns the σ nearest τ.  For an
eigenvector z = [z₁; z₂], x₊ = z₁ + i z₂ belongs to σ = τ + μ and x₋ = z₁ − i z₂ to
σ = τ̄ + μ; the one of larger norm is taken and its backward error is recomputed on (A, B)
itself, independently of SLEPc's estimate (so a block-low-rank factor is never trusted).

Options: prefix :data:`~meicp.petsc.options.FLUTTER` (``-meicp_flutter_eps_*``,
``-meicp_flutter_st_*``), code defaults < the scene's ``[petsc]`` table < command line,
``setFromOptions`` last.  Every function is collective on the matrices' communicator; the
EPS and the 2n matrices are destroyed before each solve returns.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from ..core.comm import mpi_comm
from ..core.errors import ConvergenceError
from . import import_petsc, import_slepc, mumps_c
from .mat import mat_from_local_csr, vec_to_numpy
from .options import FLUTTER, OptionsScope, mumps_controls, st_low_rank, st_node_pairs

#: pairs that all lie this close to their target, relative to |τ|, are pseudo-pairs following
#: it: at 10⁶ DOFs (a two-layer lattice, μ = 2, slip−) 15 pairs within 6e-5 of |τ| = 2.56, none
#: passing the residual gate before or after a stricter solve (docs/benchmarks-notes.md,
#: "FOLLOWING")
FOLLOWING = 1e-4

_J2 = sp.csr_matrix(np.array([[0.0, 1.0], [-1.0, 0.0]]))
_I2 = sp.identity(2, format="csr")


def local_csr(A) -> sp.csr_matrix:
    """This rank's rows of a PETSc AIJ matrix as SciPy CSR (global columns)."""
    indptr, indices, data = A.getValuesCSR()
    return sp.csr_matrix((data, indices, indptr), shape=(A.getLocalSize()[0], A.getSize()[1]))


def _allreduce(comm, value, op="sum"):
    comm = mpi_comm(comm)
    if comm is None:
        return value
    from mpi4py import MPI

    return comm.allreduce(value, op={"sum": MPI.SUM, "max": MPI.MAX}[op])


def _with_basis_and_low_rank(defaults: dict, ncv: int | None, low_rank: float | None) -> dict:
    """The Krylov basis, when given, and the factor's block-low-rank controls (ICNTL(35) = 2,
    CNTL(7) = ``low_rank``), added to either form's defaults."""
    if ncv:
        defaults["eps_ncv"] = ncv
    defaults.update(st_low_rank(low_rank))
    return defaults


def shift_defaults(nev: int, ncv: int | None, tol: float, *, n: int = 1, low_rank: float | None = None,
                   max_it: int = 500) -> dict:
    """Code defaults of one complex shift-and-invert solve on the 2n form of a pencil of
    order ``n`` (nev, ncv there).  MUMPS analyses the graph of blocks of 4 rows of the 2n form
    (a DOF pair of the n form, i.e. a lattice node, when n is even: fewer flops than blocks
    of 2, docs/benchmarks-notes.md) — blocks of 2 when n is odd, since MUMPS returns a wrong
    factor, without an error, when the order is not a multiple of the block.  ``low_rank``:
    MUMPS block-low-rank factor and solves (ICNTL(35) = 2) at that dropping tolerance
    (CNTL(7)); every pair is re-checked on (A, B) anyway (docs/flutter.md §4)."""
    defaults = {"eps_gen_non_hermitian": True, "eps_nev": nev, "eps_target": 0.0, "eps_target_magnitude": True,
                "eps_tol": tol, "eps_max_it": max_it, "st_type": "sinvert", "st_ksp_type": "preonly",
                "st_pc_type": "lu", "st_pc_factor_mat_solver_type": "mumps", "st_mat_mumps_icntl_7": 2,
                "st_mat_mumps_icntl_15": -4 if n % 2 == 0 else -2}
    return _with_basis_and_low_rank(defaults, ncv, low_rank)


class PencilWork:
    """Work vectors (``_work``) of a pencil's operations, freed by :meth:`destroy` or on
    leaving a ``with`` block — not the pencil's matrices.  Collective."""

    _work: list

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.destroy()

    def destroy(self) -> None:
        for v in self._work:
            v.destroy()
        self._work = []

    def gather(self, x_local: np.ndarray) -> np.ndarray:
        """The full complex vector on every rank, x given by this rank's entries (through the
        first work vector, a right vector of the pencil).  Collective."""
        v = self._work[0]
        parts = []
        for part in (x_local.real, x_local.imag):
            v.setArray(np.ascontiguousarray(part))
            parts.append(vec_to_numpy(v))
        return parts[0] + 1j * parts[1]


class SlidingPencilOps(PencilWork):
    """The distributed pencil (A, B) with what every solve needs: ‖A‖₁, ‖B‖₁, this rank's
    rows as SciPy CSR, and work vectors for residuals on (A, B).  Collective; ``destroy``
    (or a ``with`` block) frees the work vectors, not A and B."""

    def __init__(self, A, B, A_local: sp.csr_matrix | None = None, B_local: sp.csr_matrix | None = None):
        """``A_local``, ``B_local``: this rank's rows when the caller has them already."""
        PETSc = import_petsc()
        self.A, self.B = A, B
        self.norm_A = A.norm(PETSc.NormType.NORM_1)
        self.norm_B = B.norm(PETSc.NormType.NORM_1)
        self.A_local = local_csr(A) if A_local is None else A_local
        self.B_local = local_csr(B) if B_local is None else B_local
        self._work = [A.createVecRight(), A.createVecRight(), A.createVecLeft(), A.createVecLeft(),
                      A.createVecLeft()]
        self._parts = False  # not made yet (:meth:`_scaled_parts`)

    def destroy(self) -> None:
        super().destroy()
        self._parts = False

    def residual(self, sigma: complex, x_local: np.ndarray) -> float:
        """Backward error ‖Ax − σBx‖ / ((‖A‖₁ + |σ|‖B‖₁)‖x‖) of (σ, x), x given by this
        rank's entries.  Collective."""
        a, b = sigma.real, sigma.imag
        xr, xi, t1, t2, t3 = self._work
        xr.setArray(np.ascontiguousarray(x_local.real))
        xi.setArray(np.ascontiguousarray(x_local.imag))
        # real part A xr − a B xr + b B xi; imaginary part A xi − a B xi − b B xr
        self.A.mult(xr, t1)
        self.B.mult(xr, t2)
        self.B.mult(xi, t3)
        t1.axpy(-a, t2)
        t1.axpy(b, t3)
        re2 = t1.norm() ** 2
        self.A.mult(xi, t1)
        t1.axpy(-a, t3)
        t1.axpy(-b, t2)
        im2 = t1.norm() ** 2
        x_norm = np.sqrt(xr.norm() ** 2 + xi.norm() ** 2)
        return float(np.sqrt(re2 + im2) / ((self.norm_A + abs(sigma) * self.norm_B) * x_norm))

    def symmetric_with_diagonal_mass(self) -> bool:
        """A exactly symmetric and B diagonal positive: every σ is real.  Collective."""
        if diagonal_of(self.B, self.B_local) is None:
            return False
        return bool(self.A.isSymmetric(0.0))

    def _scaled_parts(self):
        """``(lo, scale, AT_local)`` when B = D is diagonal positive (else None): this rank's
        first row, D^{-1/2} whole, and this rank's rows of Aᵀ — made once for both bounds.
        SciPy on the local rows: PETSc's A ± Aᵀ (MatAYPX, different patterns) is slower
        (docs/benchmarks-notes.md).  Collective."""
        if self._parts is False:
            PETSc = import_petsc()
            d = diagonal_of(self.B, self.B_local)
            self._parts = None
            if d is not None:
                comm = mpi_comm(self.A.getComm())
                scale = 1.0 / np.sqrt(d if comm is None else np.concatenate(comm.allgather(d)))
                AT = self.A.transpose(PETSc.Mat())  # a new matrix: petsc4py's transpose() works in place
                try:
                    self._parts = (self.A.getOwnershipRange()[0], scale, local_csr(AT))
                finally:
                    AT.destroy()
        return self._parts

    def _scaled(self, sign: float) -> tuple[int, sp.csr_matrix] | None:
        """``(lo, this rank's rows of D^{-1/2}·(A + sign·Aᵀ)/2·D^{-1/2})``, or None."""
        parts = self._scaled_parts()
        if parts is None:
            return None
        lo, scale, AT_local = parts
        M = (self.A_local + sign * AT_local).tocsr()
        rows = np.repeat(np.arange(M.shape[0]), np.diff(M.indptr))
        M.data *= 0.5 * scale[lo + rows] * scale[M.indices]  # the entries scaled in place, not two products
        return lo, M

    def skew_bound(self) -> float | None:
        """β ≥ |Im σ| for every eigenvalue when B = D is diagonal positive: Im σ =
        Im(yᴴW y)/(yᴴy) with y = D^{1/2}x and W = D^{-1/2}·skew(A)·D^{-1/2}, so |Im σ| ≤
        ‖W‖₂ ≤ ‖W‖₁ (one pass over the rows).  None when B is not diagonal.  Collective."""
        scaled = self._scaled(-1.0)
        if scaled is None:
            return None
        rows = np.asarray(abs(scaled[1]).sum(axis=1)).ravel()
        return float(_allreduce(self.A.getComm(), float(rows.max()) if rows.size else 0.0, "max"))

    def real_part_bound(self) -> float | None:
        """γ ≥ Re σ for every eigenvalue when B = D is diagonal positive: Re σ =
        yᴴS y/(yᴴy) with y = D^{1/2}x and S = D^{-1/2}·sym(A)·D^{-1/2}, so Re σ ≤ λ_max(S),
        bounded by Gershgorin's discs (one pass over the rows, with a slack of a few units of
        rounding per entry).  None when B is not diagonal.  Collective."""
        return self._gershgorin(1.0)

    def lowest_real_part(self) -> float | None:
        """The other end: ≤ λ_min(S), every Re xᴴAx / xᴴBx above it (Gershgorin, as
        :meth:`real_part_bound`).  None when B is not diagonal.  Collective."""
        top = self._gershgorin(-1.0)
        return None if top is None else -top

    def _gershgorin(self, side: float) -> float | None:
        """Gershgorin's bound on λ_max(side·S) (side ±1), S as in :meth:`real_part_bound`."""
        scaled = self._scaled(1.0)
        if scaled is None:
            return None
        lo, S = scaled
        diag = side * S.diagonal(k=lo)
        radius = np.asarray(abs(S).sum(axis=1)).ravel() - np.abs(diag)
        slack = 4 * np.finfo(float).eps * (np.diff(S.indptr) + 2) * (np.abs(diag) + radius)
        local = float((diag + radius + slack).max()) if diag.size else -np.inf
        return float(_allreduce(self.A.getComm(), local, "max"))


def diagonal_of(B, B_local=None):
    """This rank's part of B's diagonal when B is diagonal with positive entries, else None.
    Collective."""
    B_local = local_csr(B) if B_local is None else B_local
    lo, _ = B.getOwnershipRange()
    rows = np.arange(B_local.shape[0])
    d = np.asarray(B_local[rows, lo + rows]).ravel()
    off_diagonal = int(np.count_nonzero(B_local.data)) - int(np.count_nonzero(d))
    bad = int(off_diagonal != 0 or np.any(d <= 0))
    return None if _allreduce(B.getComm(), bad) else d


def complex_defaults(nev: int, ncv: int | None, tol: float, *, n: int = 1, low_rank: float | None = None,
                     max_it: int = 500) -> dict:
    """Code defaults of one complex shift-and-invert solve with a complex MUMPS factor
    (:class:`~meicp.petsc.mumps_c.ComplexFactor`): SLEPc's Krylov–Schur on the operator
    K_τ⁻¹B₂ of the 2n form (nev, ncv there), and the factor's controls under the names the 2n
    form's factor had (``st_mat_mumps_icntl_<k>``, ``st_mat_mumps_cntl_<k>``: MUMPS' own
    numbers).  ICNTL(15) = −2 analyses the graph of DOF pairs (a lattice node) when n is
    even — none when odd, since blocks that do not divide the order give a wrong factor
    without an error; ``low_rank``: block-low-rank factor and solves at that CNTL(7)."""
    defaults = {"eps_type": "krylovschur", "eps_non_hermitian": True, "eps_largest_magnitude": True,
                "eps_nev": nev, "eps_tol": tol, "eps_max_it": max_it, **st_node_pairs(n)}
    return _with_basis_and_low_rank(defaults, ncv, low_rank)


class _ComplexInverse:
    """The MATSHELL z ↦ K_τ⁻¹B₂z of the 2n form by one complex solve: K_τ acts on
    interleaved z as A − τB on z₁ + iz₂ (:func:`complex_shift_solve`)."""

    def __init__(self, factor, B2):
        self.factor, self.B2 = factor, B2
        self.work = B2.createVecLeft()

    def mult(self, mat, x, y):
        self.B2.mult(x, self.work)
        w = self.work.getArray(readonly=True)
        sol = self.factor.solve(w[0::2] + 1j * w[1::2])
        out = y.getArray()
        out[0::2], out[1::2] = sol.real, sol.imag

    def destroy(self, mat=None):  # petsc4py calls it with the shell Mat when that is destroyed
        if self.work is not None:
            self.work.destroy()
            self.work = None


class StallWatch:
    """A stopping test for the flutter searches, a speed heuristic: after ``restarts``
    Krylov–Schur restarts the solve ends as if out of iterations when the best error estimate
    of the unconverged Ritz values, falling geometrically as it did since the first restart,
    would not reach ``tol`` within ``budget`` restarts in all.  The caller counts a stopped
    solve as not converged, which proves nothing.  Reads the monitor's estimates (one restart
    late); ``gave_up``: why it stopped the solve ("" when it did not).  :meth:`attach` puts it
    on an EPS."""

    def __init__(self, restarts: int, budget: int, tol: float):
        self.restarts, self.budget, self.tol = int(restarts), int(budget), float(tol)
        self.seen, self.errors, self.gave_up = -1, {}, ""

    def attach(self, eps) -> "StallWatch":
        eps.setMonitor(self.monitor)
        eps.setStoppingTest(self.stopping)
        return self

    def monitor(self, _eps, its, nconv, eig, err) -> None:
        self.seen = its
        # the estimates of the pairs still wanted, as the progress monitor reads them (SLEPc
        # sorts the converged first; 0 is "not estimated yet")
        wanted = _eps.getDimensions()[0] if _eps is not None else len(err)
        left = np.asarray(err, dtype=float)[nconv:max(wanted, nconv + 1)]
        left = left[left > 0]
        if left.size:
            self.errors[its] = float(left.min())

    def _too_slow(self, its: int) -> bool:
        first, now = self.errors.get(1), self.errors.get(its)
        if not first or not now or now <= self.tol or its <= 1:
            return False
        rate = (now / first) ** (1.0 / (its - 1))
        return rate >= 1.0 or its + np.log(self.tol / now) / np.log(rate) > self.budget

    def why_stop(self, its: int) -> str:
        return (f"converging too slowly to reach the tolerance within {self.budget} restarts"
                if self._too_slow(its) else "")

    def stopping(self, _eps, its, max_it, nconv, nev):
        reason = import_slepc().EPS.ConvergedReason
        if nconv >= nev:
            return reason.CONVERGED_TOL
        if its >= max_it:
            return reason.DIVERGED_ITS
        if self.seen == its - 1 >= self.restarts:
            self.gave_up = self.why_stop(self.seen)
            if self.gave_up:
                return reason.DIVERGED_ITS
        return reason.ITERATING


def complex_shift_solve(ops: SlidingPencilOps, tau: complex, *, nev: int = 2, ncv: int | None = 12,
                        tol: float = 1e-12, low_rank: float | None = None, max_it: int = 500,
                        options: dict | None = None, gate: float | None = None,
                        strict_tol: float | None = None, give_up: tuple | None = None) -> tuple[list, dict]:
    """The ~nev eigenvalues σ of (A, B) nearest the complex target τ, by SLEPc
    shift-and-invert on the real 2n form (every σ of the real form comes with its
    conjugate: nev, ncv are doubled there): Krylov–Schur on K_τ⁻¹B₂ applied through a complex
    MUMPS factor of A − τB (:mod:`meicp.petsc.mumps_c`), or — when no ZMUMPS of a known
    version loads, or ``-meicp_flutter_real_form`` is given — SLEPc's own shift-and-invert
    with a real MUMPS LU of K_τ (twice the flops and memory).  Returns ``(pairs, info)``:
    pairs = [(σ with Im σ ≥ 0, x gathered on every rank, backward error on (A, B))], info =
    {``radius``: the largest |σ − τ| among the converged (the disk searched), ``nconv``,
    ``iterations``, ``seconds``, ``factor``: "complex" or "real 2n"}.  ``low_rank``: see
    :func:`shift_defaults`; ``max_it``: SLEPc's restarts at most (what converged by then is
    returned).  ``options``: the scene's ``[petsc]`` table (keys without the
    prefix).  ``gate``, ``strict_tol``: when no pair converged at ``tol`` has a backward error
    ≤ ``gate``, the same operator is solved again at ``strict_tol``, started from the pairs
    converged (a loose SLEPc tolerance usually suffices: its residual is that of K_τ⁻¹B₂,
    which the backward error on (A, B) shrinks by about |σ − τ|/‖A‖; info ``solves`` says how
    many were made).  ``give_up``: ``(restarts, budget)`` of a :class:`StallWatch` on the solve
    (info ``gave_up``: why it stopped it, or "").  Collective."""
    PETSc = import_petsc()
    SLEPc = import_slepc()
    t0 = time.perf_counter()
    tau = complex(tau)
    A = ops.A
    n = A.getSize()[0]
    pcomm = A.getComm()
    real_form = bool((options or {}).get("real_form")) or PETSc.Options().getBool(FLUTTER + "real_form", False)
    if not real_form and mumps_c.load("z")[0] is None:
        real_form = True
    B2 = mat_from_local_csr(pcomm, sp.kron(ops.B_local, _I2, format="csr"), 2 * n)
    eps = SLEPc.EPS().create(comm=pcomm)
    K = shell = factor = None
    vectors = []  # the eigenvectors converged: the start of a stricter solve, when one is made
    try:
        if real_form:
            K_local = (sp.kron(ops.A_local - tau.real * ops.B_local, _I2, format="csr")
                       + tau.imag * sp.kron(ops.B_local, _J2, format="csr"))
            K = mat_from_local_csr(pcomm, K_local, 2 * n)
            eps.setOperators(K, B2)
            defaults = shift_defaults(2 * nev, ncv and 2 * ncv, tol, n=n, low_rank=low_rank, max_it=max_it)
        else:
            defaults = complex_defaults(2 * nev, ncv and 2 * ncv, tol, n=n, low_rank=low_rank, max_it=max_it)
        with OptionsScope(FLUTTER, defaults, {k: v for k, v in (options or {}).items() if k != "real_form"}) as scope:
            if not real_form:
                icntl, cntl = mumps_controls(FLUTTER + "st_mat_mumps_")
                lo = A.getOwnershipRange()[0]
                factor = mumps_c.ComplexFactor(mpi_comm(pcomm), (ops.A_local - tau * ops.B_local).tocsr(), lo, n,
                                              icntl=icntl, cntl=cntl)
                shell = _ComplexInverse(factor, B2)
                m = 2 * A.getLocalSize()[0]
                K = PETSc.Mat().createPython(((m, 2 * n), (m, 2 * n)), shell, comm=pcomm)
                K.setUp()
                eps.setOperators(K)
            scope.configure(eps)  # setFromOptions, last
            watch = None if give_up is None else StallWatch(*give_up, tol=eps.getTolerances()[0]).attach(eps)
            try:
                pairs, info = solve_tightened(eps, lambda: _converged_pairs(eps, ops, tau, real_form, B2), B2, gate,
                                              strict_tol, vectors, pseudo=lambda pairs: following(pairs, tau))
            except PETSc.Error as err:  # e.g. LAPACK on a projected problem of entries near 1e-300
                raise ConvergenceError(f"SLEPc's shift-and-invert at τ = {tau:.6g} failed (PETSc error "
                                       f"{err.ierr})") from err
        info["seconds"] = time.perf_counter() - t0
        info["gave_up"] = "" if watch is None else watch.gave_up
        return pairs, info
    finally:
        for obj in (eps, K, B2, shell, factor, *vectors):
            if obj is not None:
                obj.destroy()


def following(pairs, tau: complex) -> bool:
    """Whether every pair's value lies within FOLLOWING·|τ| of the target τ: the pseudo-pairs
    shift-and-invert converges inside a cluster of ill-conditioned eigenvalues, which follow
    whatever target it is given (docs/flutter.md §4, "Off the cluster")."""
    return bool(pairs) and all(abs(value - tau) <= FOLLOWING * abs(tau) for value, _, _ in pairs)


def solve_tightened(eps, collect, template, gate: float | None, strict_tol: float | None,
                    vectors: list, pseudo=None) -> tuple[list, dict]:
    """``eps.solve()`` and ``collect()`` → ``(pairs, info)`` (pairs: (value, x, backward error));
    when no pair converged at the EPS tolerance has a backward error ≤ ``gate``, the same
    operator is solved again at ``strict_tol``, started from the eigenvectors converged
    (copied into ``vectors``, the caller's to destroy; ``template``: a Mat whose right
    vectors are the EPS's) — unless ``pseudo(pairs)`` says they are pseudo-pairs, which a
    stricter solve does not make true ones.  info ``solves``: how many were made.  Collective."""
    eps.solve()
    pairs, info = collect()
    info["solves"] = 1
    if (gate is not None and strict_tol is not None and strict_tol < eps.getTolerances()[0] and pairs
            and not any(res <= gate for _, _, res in pairs) and not (pseudo is not None and pseudo(pairs))):
        # the eigenvectors converged (real and imaginary parts) start the stricter solve;
        # copied only here, where they are needed (each is a vector of the real form)
        for i in range(eps.getConverged()):
            zr, zi = template.createVecRight(), template.createVecRight()
            eps.getEigenvector(i, zr, zi)
            vectors += [zr, zi]
        eps.setTolerances(tol=strict_tol)
        eps.setInitialSpace(vectors)
        eps.solve()
        iterations = info["iterations"]
        pairs, info = collect()
        info["iterations"] += iterations
        info["solves"] = 2
    return pairs, info


def _converged_pairs(eps, ops: SlidingPencilOps, tau: complex, real_form: bool, B2) -> tuple[list, dict]:
    """The converged pairs of a shift-and-invert EPS on the 2n form, back on (A, B) (see
    :func:`complex_shift_solve`), and its info."""
    info = {"factor": "real 2n" if real_form else "complex"}
    return converged_pairs(eps, B2, tau, inverted=not real_form, residual=ops.residual, gather=ops.gather,
                           comm=mpi_comm(ops.A.getComm()), info=info)


def converged_pairs(eps, template, tau: complex, *, inverted: bool, residual, gather, comm,
                    head: int | None = None, info: dict | None = None) -> tuple[list, dict]:
    """The converged pairs of a shift-and-invert EPS on the real form of a complex operator
    whose eigenvalues are ``1/(value − τ)`` (``inverted``) or ``value − τ`` (the real 2n
    form's pencil), and ``info`` with {``nconv``, ``iterations``, ``radius``: the largest
    |value − τ| among the pairs kept, ``real_ritz``: the real Ritz values skipped}.  Pairs: (value with
    Im ≥ 0, x gathered on every rank, its ``residual``); ``head``: x is the first ``head``
    local entries of each complex vector (the companion form's x of [x; λx]), None: all.
    ``template``: a Mat whose right vectors are the EPS's.

    A *real* Ritz value of the real form is skipped: it would put the value exactly on the
    horizontal line through τ (value − τ real), which no eigenvalue of a complex operator
    meets but by accident, and inside a cluster of ill-conditioned eigenvalues Krylov–Schur
    converges such values next to τ — pseudo-pairs that can even pass a residual gate
    (docs/flutter.md §4, "Real Ritz values").  Collective."""
    nconv = eps.getConverged()
    info = {**(info or {}), "nconv": nconv, "iterations": eps.getIterationNumber(), "real_ritz": 0}
    zr, zi = template.createVecRight(), template.createVecRight()
    pairs, seen, radius = [], [], 0.0
    previous = None
    for i in range(nconv):
        theta = complex(eps.getEigenvalue(i))
        if theta.imag == 0:
            info["real_ritz"] += 1
            continue
        mu = (1.0 / theta if theta != 0 else complex(np.inf)) if inverted else theta
        radius = max(radius, abs(mu))
        # SLEPc returns a real form's complex eigenvalues as conjugate pairs, one after the
        # other; the second (eigenvector z̄) maps to the same value as the first
        if previous is not None and mu.imag != 0 and mu == previous.conjugate():
            previous = None
            continue
        previous = mu
        eps.getEigenvector(i, zr, zi)
        z = zr.getArray(readonly=True) + 1j * zi.getArray(readonly=True)
        x_plus, x_minus = z[0::2] + 1j * z[1::2], z[0::2] - 1j * z[1::2]
        if head is not None:
            x_plus, x_minus = x_plus[:head], x_minus[:head]
        norms = [float(np.vdot(x, x).real) for x in (x_plus, x_minus)]
        if comm is not None:
            norms = [comm.allreduce(v) for v in norms]
        value, x = (tau + mu, x_plus) if norms[0] >= norms[1] else (tau.conjugate() + mu, x_minus)
        if value.imag < 0:
            value, x = value.conjugate(), x.conj()
        if any(abs(value - s) <= 1e-10 * max(1.0, abs(s)) for s in seen):
            continue  # the other member of a conjugate pair
        seen.append(value)
        pairs.append((value, gather(x), residual(value, x)))
    info["radius"] = radius
    zr.destroy()
    zi.destroy()
    return pairs, info
