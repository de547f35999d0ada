"""MUMPS through its C interface (``dmumps_c``, ``zmumps_c``), for what PETSc's MUMPS
interface cannot do here: a complex factorisation in the real-scalar build, and a series of
Schur complements that share one analysis.

* :class:`ComplexFactor` — ZMUMPS LU of A − τB for the complex shift-and-invert of the flutter
  search (:mod:`meicp.petsc.flutter`).  Debian's PETSc here is real-scalar and its complex
  build cannot share a process with it, but Debian's MUMPS ships every arithmetic in one
  package (``libmumps-5.5``, which PETSc already depends on); complex arithmetic has half the
  flops and memory of the real equivalent form of order 2n (10⁶ DOFs, 2 ranks: 4.1 s warm,
  9.2 s cold, against 8–18 s for the 2n form's block-low-rank LU).
* :class:`SchurSeries` — DMUMPS LDLᵀ Schur complements of H₀ + σH₁ (one pattern) onto fixed
  rows, one analysis for every σ: the condensation's σ-samples (:mod:`meicp.contact.condenser`).
  Through PETSc each σ paid MUMPS' analysis again (0.56 s of 2.2 s at 10⁶ DOFs), and a
  refactorisation kept for the next σ returned a wrong Schur complement on 2 ranks.

The matrix goes in distributed by rows (ICNTL(18) = 3: each rank its own rows, in PETSc's
default split); right-hand sides, solutions and Schur complements are centralised on the host
(rank 0).  :class:`MUMPS_STRUC_C` is the C structure of MUMPS 5.5 (``dmumps_c.h`` and
``zmumps_c.h`` lay it out alike: the scalars behind its pointers differ, its reals are double
in both); :func:`load` hands out a library only when its version is one this structure was
written for (asked of a padded instance on this process) and says why not otherwise, so the
callers fall back.  Collective on ``comm`` (an mpi4py communicator or None).
"""
from __future__ import annotations

import ctypes as C
import glob

import numpy as np
import scipy.sparse as sp

from ..core.errors import ProblemError
from .mat import ownership

_INT, _INT8, _REAL, _PTR = C.c_int, C.c_int64, C.c_double, C.c_void_p
_PINT = C.POINTER(C.c_int)
#: MUMPS releases whose structure is the one below (checked against zmumps_c.h and dmumps_c.h
#: 5.5.1: 8,360 bytes, version_number at 7,072, metis_options at 8,196)
VERSIONS = ("5.5.",)
#: ICNTL(18) (distributed input), (19) (Schur), (20), (21) (right-hand side and solution on the
#: host): the layout this interface passes, not the user's to change
OWN_ICNTL = frozenset({18, 19, 20, 21})


class MUMPS_STRUC_C(C.Structure):  # noqa: N801 — the C name (DMUMPS_STRUC_C, ZMUMPS_STRUC_C)
    _fields_ = [
        ("sym", _INT), ("par", _INT), ("job", _INT), ("comm_fortran", _INT),
        ("icntl", _INT * 60), ("keep", _INT * 500), ("cntl", _REAL * 15), ("dkeep", _REAL * 230),
        ("keep8", _INT8 * 150), ("n", _INT), ("nblk", _INT), ("nz_alloc", _INT),
        ("nz", _INT), ("nnz", _INT8), ("irn", _PINT), ("jcn", _PINT), ("a", _PTR),
        ("nz_loc", _INT), ("nnz_loc", _INT8), ("irn_loc", _PINT), ("jcn_loc", _PINT), ("a_loc", _PTR),
        ("nelt", _INT), ("eltptr", _PINT), ("eltvar", _PINT), ("a_elt", _PTR),
        ("blkptr", _PINT), ("blkvar", _PINT), ("perm_in", _PINT), ("sym_perm", _PINT), ("uns_perm", _PINT),
        ("colsca", _PTR), ("rowsca", _PTR), ("colsca_from_mumps", _INT), ("rowsca_from_mumps", _INT),
        ("rhs", _PTR), ("redrhs", _PTR), ("rhs_sparse", _PTR), ("sol_loc", _PTR), ("rhs_loc", _PTR),
        ("irhs_sparse", _PINT), ("irhs_ptr", _PINT), ("isol_loc", _PINT), ("irhs_loc", _PINT),
        ("nrhs", _INT), ("lrhs", _INT), ("lredrhs", _INT), ("nz_rhs", _INT), ("lsol_loc", _INT),
        ("nloc_rhs", _INT), ("lrhs_loc", _INT), ("schur_mloc", _INT), ("schur_nloc", _INT), ("schur_lld", _INT),
        ("mblock", _INT), ("nblock", _INT), ("nprow", _INT), ("npcol", _INT),
        ("info", _INT * 80), ("infog", _INT * 80), ("rinfo", _REAL * 40), ("rinfog", _REAL * 40),
        ("deficiency", _INT), ("pivnul_list", _PINT), ("mapping", _PINT),
        ("size_schur", _INT), ("listvar_schur", _PINT), ("schur", _PTR),
        ("instance_number", _INT), ("wk_user", _PTR),
        ("version_number", C.c_char * 32), ("ooc_tmpdir", C.c_char * 256), ("ooc_prefix", C.c_char * 64),
        ("write_problem", C.c_char * 256), ("lwk_user", _INT), ("save_dir", C.c_char * 256),
        ("save_prefix", C.c_char * 256), ("metis_options", _INT * 40)]


_LIBS: dict = {}


def load(arith: str = "z"):
    """``(library, "")`` for ``arith`` "d" (real) or "z" (complex), or ``(None, why)`` when no
    MUMPS library of that arithmetic is found."""
    if arith not in _LIBS:
        found, why = None, f"no lib{arith}mumps found (Debian's libmumps-5.5)"
        for name in [f"lib{arith}mumps-5.5.so", f"lib{arith}mumps.so"] + sorted(glob.glob(f"/usr/lib/*/lib{arith}mumps-*.so")):
            try:
                lib = C.CDLL(name, mode=C.RTLD_GLOBAL)
            except OSError:
                continue
            entry = getattr(lib, f"{arith}mumps_c")
            entry.argtypes = [C.POINTER(MUMPS_STRUC_C)]
            entry.restype = None
            version = _version_of(entry)
            found, why = (entry, "") if version.startswith(VERSIONS) else (
                None, f"lib{arith}mumps {version!r}: meicp's MUMPS_STRUC_C is that of MUMPS {VERSIONS[0]}x")
            break
        _LIBS[arith] = (found, why)
    return _LIBS[arith]


def _version_of(entry) -> str:
    """The library's version string, from an instance on this process alone (JOB = −1, then
    −2) whose structure is padded by 64 kB: a MUMPS whose structure is larger than the one
    above writes into the padding, not past it."""
    buffer = C.create_string_buffer(C.sizeof(MUMPS_STRUC_C) + 65536)
    ident = MUMPS_STRUC_C.from_buffer(buffer)
    ident.sym, ident.par, ident.job, ident.comm_fortran = 0, 1, -1, _self_comm()
    entry(C.byref(ident))
    version = ident.version_number.decode(errors="replace").strip("\x00 ")
    if ident.infog[0] >= 0:
        ident.icntl[0], ident.icntl[1], ident.icntl[2], ident.icntl[3] = -1, -1, -1, 0  # quiet
        ident.job = -2
        entry(C.byref(ident))
    return version


class MumpsError(ProblemError):
    """MUMPS returned INFOG(1) < 0 (the same on every rank: MUMPS reports it globally, so
    every rank raises and none is left waiting), or no usable MUMPS was found, or a control
    was refused before MUMPS read anything.  ``code``: INFOG(1), 0 when MUMPS did not run."""

    code = 0


class _Instance:
    """One MUMPS instance: JOB = −1 with ``sym`` (0 unsymmetric, 2 general symmetric) on a
    library whose version :func:`load` checked, the controls set (``defaults`` < ``icntl``/``cntl``, by Fortran number),
    and :meth:`destroy` (JOB = −2, collective).  ``what``/``option``: how errors name it."""

    def __init__(self, comm, arith: str, sym: int, defaults: dict, icntl: dict | None, cntl: dict | None,
                 what: str, option: str):
        self.what, self.option, self.id = what, option, None
        entry, why = load(arith)
        if entry is None:
            raise MumpsError(why)
        for name, given, size in (("ICNTL", icntl, 60), ("CNTL", cntl, 15)):
            bad = sorted(k for k in (given or {}) if not 1 <= k <= size)
            if bad:
                raise MumpsError(f"MUMPS has no {name}({bad[0]}) (1 … {size}): check the {option}{name.lower()}_<k> options")
        own = sorted(set(icntl or {}) & OWN_ICNTL)
        if own:  # the data layout this interface passes: another value would read absent arrays
            raise MumpsError(f"ICNTL({own[0]}) of the {what} is set by meicp (distributed rows, centralised "
                             f"right-hand sides, solutions and Schur complements); remove {option}icntl_{own[0]}")
        self.entry, self.comm = entry, comm
        self.id = MUMPS_STRUC_C()
        self.id.sym, self.id.par = sym, 1
        self.id.comm_fortran = comm.py2f() if comm is not None else _self_comm()
        self._run(-1)
        # load() handed out only a library of a known version (_version_of)
        self.version = self.id.version_number.decode(errors="replace").strip()
        # quiet; AMF (Debian's MUMPS has no METIS); rows distributed
        controls = {1: -1, 2: -1, 3: -1, 4: 0, 7: 2, 18: 3, **defaults, **(icntl or {})}
        for k, v in controls.items():
            self.id.icntl[k - 1] = int(v)
        for k, v in (cntl or {}).items():
            self.id.cntl[k - 1] = float(v)

    @property
    def host(self) -> bool:
        return self.comm is None or self.comm.Get_rank() == 0

    @property
    def flops(self) -> float:
        """RINFOG(3): the factorisation's operation count (in its arithmetic)."""
        return float(self.id.rinfog[2])

    def _rows(self, irn: np.ndarray, jcn: np.ndarray, values: np.ndarray, n: int) -> None:
        # MUMPS keeps these pointers until the instance is destroyed: hold the arrays
        self._irn, self._jcn, self._a = irn, jcn, values
        self.id.n = n
        self.id.nz_loc, self.id.nnz_loc = values.size, values.size
        self.id.irn_loc = irn.ctypes.data_as(_PINT)
        self.id.jcn_loc = jcn.ctypes.data_as(_PINT)
        self.id.a_loc = values.ctypes.data

    def _run(self, job: int) -> None:
        self.id.job = job
        self.entry(C.byref(self.id))
        if self.id.infog[0] < 0:
            error = MumpsError(f"the {self.what} failed (MUMPS job {job}: INFOG(1) = {self.id.infog[0]}, INFOG(2) = "
                               f"{self.id.infog[1]}, MUMPS users' guide §8); check the {self.option}* options")
            error.code = int(self.id.infog[0])
            raise error

    def destroy(self) -> None:
        if self.id is not None:
            ident, self.id = self.id, None
            ident.job = -2
            self.entry(C.byref(ident))

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.destroy()


class LUFactor(_Instance):
    """MUMPS LU (``arith`` "d": real, "z": complex) of the matrix whose rows
    ``lo:lo + rows.shape[0]`` this rank holds (``rows``: SciPy CSR with global columns), order
    ``n``.  ``icntl``, ``cntl``: MUMPS controls by their 1-based Fortran numbers, after the
    defaults (quiet, AMF ordering).  :meth:`solve` takes and returns this rank's entries.  A
    context manager; ``destroy`` is collective."""

    def __init__(self, comm, rows: sp.csr_matrix, lo: int, n: int, *, arith: str = "z", icntl: dict | None = None,
                 cntl: dict | None = None, what: str = "MUMPS factor", option: str = "-meicp_flutter_st_mat_mumps_"):
        super().__init__(comm, arith, 0, {}, icntl, cntl, what, option)
        self.dtype = np.complex128 if arith == "z" else np.float64
        self.lo, self.n, self.rows = lo, n, rows.shape[0]
        coo = rows.tocoo()
        self._rows(np.ascontiguousarray(coo.row + lo + 1, dtype=np.int32),
                   np.ascontiguousarray(coo.col + 1, dtype=np.int32),
                   np.ascontiguousarray(coo.data, dtype=self.dtype), n)
        try:
            self._run(4)  # analysis and factorisation
        except MumpsError:
            self.destroy()
            raise
        self._counts = None if comm is None else np.array(comm.allgather(self.rows))
        self._rhs = np.zeros(n if self.host else 1, dtype=self.dtype)

    def solve(self, local: np.ndarray) -> np.ndarray:
        """This rank's entries of the solution of F x = b, b given by this rank's entries.
        Collective."""
        local = np.ascontiguousarray(local, dtype=self.dtype)
        if self.comm is None:
            self._rhs[:] = local
        else:
            self.comm.Gatherv(local, [self._rhs, self._counts] if self.host else None, root=0)
        self.id.nrhs, self.id.lrhs = 1, self.n
        self.id.rhs = self._rhs.ctypes.data
        self._run(3)
        if self.comm is None:
            return self._rhs.copy()
        out = np.empty(self.rows, dtype=self.dtype)
        self.comm.Scatterv([self._rhs, self._counts] if self.host else None, out, root=0)
        return out


class ComplexFactor(LUFactor):
    """ZMUMPS LU of a complex matrix (:class:`LUFactor` with ``arith`` "z"): the flutter
    searches' factor."""

    def __init__(self, comm, rows: sp.csr_matrix, lo: int, n: int, *, icntl: dict | None = None,
                 cntl: dict | None = None):
        super().__init__(comm, rows, lo, n, arith="z", icntl=icntl, cntl=cntl,
                         what="complex MUMPS factor of the flutter search")


class SchurSeries(_Instance):
    """``series(σ)``: the dense Schur complement onto ``rows`` (global indices, in their
    order) of the symmetric matrix H₀ + σH₁ (+ σ²H₂ with ``H2``: a quadratic pencil's) (SciPy
    CSR, one pattern, every rank holds them),
    on every rank — DMUMPS LDLᵀ (general symmetric: indefinite allowed, H_FF must factor
    without pivoting into the Schur rows, which holds when it is definite), one analysis for
    every σ.  The same instance serves the interior block H_II (every row not a Schur row):
    :meth:`factor` gives its inertia (a proof with ``exact``), :meth:`solve` solves with it.
    ``icntl``, ``cntl``: after ``defaults``.  Collective; a context manager."""

    #: the interior solves and inertias of :meth:`solve` and :meth:`factor` (the PETSc fallback
    #: of :func:`meicp.petsc.schur.schur_series` has neither)
    interior = True

    def __init__(self, comm, H0: sp.csr_matrix, H1: sp.csr_matrix | None, rows: np.ndarray, *,
                 defaults: dict | None = None, icntl: dict | None = None, cntl: dict | None = None,
                 what: str = "Schur complement of the condensation", option: str = "-meicp_schur_mat_mumps_",
                 H2: sp.csr_matrix | None = None):
        # (the Schur block is the root of the elimination tree and is not factored: no ScaLAPACK
        # root whose pivots INFOG(12) would miss)
        super().__init__(comm, "d", 2, {19: 1, **(defaults or {})}, icntl, cntl, what, option)
        # H1 None: the constant matrix H0 (one factorisation, no second copy of its values)
        H0 = sp.csr_matrix(H0)
        H1 = None if H1 is None else sp.csr_matrix(H1)
        H2 = None if H2 is None else sp.csr_matrix(H2)
        if (H2 is not None and H1 is None) or any(
                H is not None and (H0.shape != H.shape or not (np.array_equal(H0.indptr, H.indptr)
                                                              and np.array_equal(H0.indices, H.indices)))
                for H in (H1, H2)):
            self.destroy()
            raise ValueError("SchurSeries needs H₀, H₁ (and H₂) on one pattern")
        n = H0.shape[0]
        lo, hi = (0, n) if comm is None else ownership(n, comm.Get_rank(), comm.Get_size())
        local0 = H0[lo:hi].tocoo()
        upper = local0.col >= local0.row + lo  # a symmetric matrix gives one triangle (MUMPS sums both)
        self._h0 = local0.data[upper].astype(float)
        self._h1 = None if H1 is None else H1[lo:hi].tocoo().data[upper].astype(float)
        self._h2 = None if H2 is None else H2[lo:hi].tocoo().data[upper].astype(float)
        rows_upper, cols_upper = local0.row[upper] + lo, local0.col[upper]
        self._rows(np.ascontiguousarray(rows_upper + 1, dtype=np.int32),
                   np.ascontiguousarray(cols_upper + 1, dtype=np.int32), self._h0.copy(), n)
        on_diagonal = rows_upper == cols_upper
        self._diagonal_at, self._diagonal_row = np.flatnonzero(on_diagonal), rows_upper[on_diagonal]
        self._lo, self._hi, self.n = lo, hi, n
        self._listvar = np.ascontiguousarray(np.asarray(rows) + 1, dtype=np.int32)
        self.m = self._listvar.size
        self.id.size_schur = self.m
        self.id.listvar_schur = self._listvar.ctypes.data_as(_PINT)
        self._schur = np.zeros(self.m * self.m if self.host else 1)
        self.id.schur = self._schur.ctypes.data
        self._analysed = False
        #: (σ, shifted, exact) of the matrix factorised last (None before the first)
        self.factored: tuple | None = None

    def __call__(self, sigma: float) -> np.ndarray:
        self.factor(sigma)
        return self.schur_complement()

    def schur_complement(self) -> np.ndarray:
        """The Schur complement of the matrix factorised last, on every rank.  Collective."""
        S = None
        if self.host:
            # ICNTL(19) = 1, symmetric: the lower triangle, by rows
            low = np.tril(self._schur.reshape(self.m, self.m))
            S = low + np.tril(low, -1).T
        return S if self.comm is None else self.comm.bcast(S, root=0)

    def factor(self, sigma: float, *, diagonal: np.ndarray | None = None, exact: bool = False) -> tuple[int, int]:
        """Factorise H₀ + σH₁ (+ σ²H₂) + diag(``diagonal``) (a vector of order n every rank holds, added
        on the pattern's diagonal; its Schur complement is computed, not read) and return the
        interior's ``(negative, null)`` pivot counts (INFOG(12), INFOG(28)).  ``exact``: this
        factorisation full rank (ICNTL(35) = 0: the series' block low rank is an approximation
        whose inertia proves nothing) and with null pivot detection (ICNTL(24) = 1), for an
        inertia that is a proof up to rounding; its null count then includes the pivots MUMPS
        forced to ±eps next to the Schur block (INFOG(25)), which a proof cannot accept either.
        Collective."""
        if self._h1 is None:
            self._a[:] = self._h0
        else:
            np.multiply(self._h1, sigma, out=self._a)
            self._a += self._h0
            if self._h2 is not None:
                self._a += (sigma * sigma) * self._h2
        if diagonal is not None:
            diagonal = np.asarray(diagonal, dtype=float)
            mine = np.zeros(self._hi - self._lo, dtype=bool)
            mine[self._diagonal_row - self._lo] = True
            outside = bool(np.any(diagonal[self._lo:self._hi][~mine] != 0))
            if self.comm is not None and self.comm.Get_size() > 1:  # every rank raises, none waits in MUMPS
                outside = self.comm.allreduce(outside, op=_lor())
            if outside:
                raise ValueError("SchurSeries.factor: a diagonal shift where the pattern has no diagonal entry")
            self._a[self._diagonal_at] += diagonal[self._diagonal_row]
        if not self._analysed:  # with the series' own controls: block low rank is chosen here
            self._run(1)
            self._analysed = True
        saved = (self.id.icntl[34], self.id.icntl[23])
        if exact:
            self.id.icntl[34], self.id.icntl[23] = 0, 1
        self.factored = None  # until this factorisation succeeds
        try:
            self._run(2)
        finally:
            self.id.icntl[34], self.id.icntl[23] = saved
        self.factored = (float(sigma), diagonal is not None, exact)
        null = int(self.id.infog[27]) + int(self.id.infog[24]) if exact else 0
        return int(self.id.infog[11]), null

    def solve(self, rhs: np.ndarray | None) -> np.ndarray | None:
        """``x`` with H_II x_I = b_I for the matrix factorised last (JOB = 3, ICNTL(26) = 0: the
        interior problem; b's Schur rows are ignored, x's are 0).  ``rhs``: order n, a vector
        or a block of columns, read on the host (the other ranks may pass None); returns the
        solution on the host, None elsewhere.  Collective."""
        if self.factored is None:
            raise RuntimeError("SchurSeries.solve without a successful factorisation")
        block = None
        if self.host:
            rhs = np.asarray(rhs, dtype=float)
            block = np.array(rhs.reshape(self.n, -1), dtype=float, order="F")
            block[self._listvar - 1] = 0.0
            self.id.nrhs, self.id.lrhs = block.shape[1], self.n
            self.id.rhs = block.ctypes.data
        self.id.icntl[25] = 0
        self._run(3)
        if not self.host:
            return None
        block[self._listvar - 1] = 0.0
        return block[:, 0] if rhs.ndim == 1 else block


def _lor():
    from mpi4py import MPI

    return MPI.LOR


def _self_comm() -> int:
    from mpi4py import MPI

    return MPI.COMM_SELF.py2f()


def ctypes_size() -> int:
    """sizeof(MUMPS_STRUC_C) as laid out here (8,360 bytes for MUMPS 5.5.1's header)."""
    return C.sizeof(MUMPS_STRUC_C)
