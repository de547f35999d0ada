"""A distributed complex MUMPS factorisation (ZMUMPS, through its C interface) for the
complex shift-and-invert of the flutter search (:mod:`meicp.petsc.flutter`).

Debian's PETSc here is real-scalar, and its complex build cannot share a process with it,
but Debian's MUMPS ships every arithmetic in one package (``libmumps-5.5``, which PETSc
already depends on): ``libzmumps`` factors A − τB in complex arithmetic, half the flops and
memory of the real equivalent form of order 2n (measured at 10⁶ DOFs on 2 ranks: 4.1 s
warm, 9.2 s cold, against 8–18 s for the 2n form's block-low-rank LU).

The matrix goes in distributed by rows (ICNTL(18) = 3: each rank its own rows, as PETSc
owns them); right-hand sides and solutions are centralised on the host (rank 0), so a solve
gathers and scatters one vector.  :data:`ZMUMPS_STRUC_C` is the C structure of MUMPS 5.5
(``zmumps_c.h``); :func:`load` checks that the library's version is one it was written for
(the structure's layout changes between releases) and says why not otherwise, so that the
caller keeps the real 2n form.  Collective on ``comm`` (an mpi4py communicator or None).
"""
from __future__ import annotations

import ctypes as C
import glob

import numpy as np
import scipy.sparse as sp

from ..core.errors import ProblemError

_INT, _INT8, _REAL, _PTR = C.c_int, C.c_int64, C.c_double, C.c_void_p
_PINT = C.POINTER(C.c_int)
#: MUMPS releases whose ZMUMPS_STRUC_C is the one below (checked against zmumps_c.h 5.5.1:
#: 8,360 bytes, version_number at 7,072, metis_options at 8,196)
VERSIONS = ("5.5.",)
LIBRARIES = ("libzmumps-5.5.so", "libzmumps.so")
#: ICNTL(18) (distributed input), (19) (Schur), (20), (21) (right-hand side and solution on the
#: host): the layout this interface passes, not the user's to change
OWN_ICNTL = frozenset({18, 19, 20, 21})


class ZMUMPS_STRUC_C(C.Structure):  # noqa: N801 — the C name
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


_LIB: list = []


def load():
    """``(library, "")``, or ``(None, why)`` when no ZMUMPS of a known version is found."""
    if _LIB:
        return _LIB[0]
    found, why = None, "no libzmumps found (Debian's libmumps-5.5)"
    candidates = list(LIBRARIES) + sorted(glob.glob("/usr/lib/*/libzmumps-*.so"))
    for name in candidates:
        try:
            lib = C.CDLL(name, mode=C.RTLD_GLOBAL)
        except OSError:
            continue
        lib.zmumps_c.argtypes = [C.POINTER(ZMUMPS_STRUC_C)]
        lib.zmumps_c.restype = None
        found, why = lib, ""
        break
    _LIB.append((found, why))
    return found, why


class MumpsError(ProblemError):
    """MUMPS returned INFOG(1) < 0 (the same on every rank: MUMPS reports it globally, so
    every rank raises and none is left waiting), or no usable ZMUMPS was found."""


class ComplexFactor:
    """ZMUMPS LU of the complex matrix whose rows ``lo:lo + rows.shape[0]`` this rank holds
    (``rows``: SciPy CSR with global columns), order ``n``.  ``icntl``, ``cntl``: MUMPS
    controls by their 1-based Fortran numbers, after the defaults (quiet, AMF ordering).
    :meth:`solve` takes and returns this rank's entries.  A context manager; ``destroy`` is
    collective."""

    def __init__(self, comm, rows: sp.csr_matrix, lo: int, n: int, *, icntl: dict | None = None,
                 cntl: dict | None = None):
        lib, why = load()
        if lib is None:
            raise MumpsError(why)
        self.lib, self.comm, self.lo, self.n = lib, comm, lo, n
        self.rows = rows.shape[0]
        for name, given, size in (("ICNTL", icntl, 60), ("CNTL", cntl, 15)):
            bad = sorted(k for k in (given or {}) if not 1 <= k <= size)
            if bad:
                raise MumpsError(f"MUMPS has no {name}({bad[0]}) (1 … {size}): check the "
                                 f"-meicp_flutter_st_mat_mumps_{name.lower()}_<k> options")
        own = sorted(set(icntl or {}) & OWN_ICNTL)
        if own:  # the data layout this interface passes: another value would read absent arrays
            raise MumpsError(f"ICNTL({own[0]}) of the complex flutter factor is set by meicp (distributed rows, "
                             "centralised right-hand side and solution, no Schur complement); remove "
                             f"-meicp_flutter_st_mat_mumps_icntl_{own[0]}")
        self.id = ZMUMPS_STRUC_C()
        self.id.sym, self.id.par = 0, 1
        self.id.comm_fortran = comm.py2f() if comm is not None else _self_comm()
        self._run(-1)
        version = self.id.version_number.decode(errors="replace").strip()
        if not version.startswith(VERSIONS):
            self._run(-2)
            raise MumpsError(f"libzmumps {version!r}: meicp's ZMUMPS_STRUC_C is that of MUMPS {VERSIONS[0]}x")
        self.version = version
        controls = {1: -1, 2: -1, 3: -1, 4: 0, 7: 2, 18: 3}  # quiet; AMF (Debian's MUMPS has no METIS); rows distributed
        controls.update(icntl or {})
        for k, v in controls.items():
            self.id.icntl[k - 1] = int(v)
        for k, v in (cntl or {}).items():
            self.id.cntl[k - 1] = float(v)
        coo = rows.tocoo()
        # MUMPS keeps these pointers until the factor is destroyed: hold the arrays
        self._irn = np.ascontiguousarray(coo.row + lo + 1, dtype=np.int32)
        self._jcn = np.ascontiguousarray(coo.col + 1, dtype=np.int32)
        self._a = np.ascontiguousarray(coo.data, dtype=np.complex128)
        self.id.n = n
        self.id.nz_loc, self.id.nnz_loc = self._a.size, self._a.size
        self.id.irn_loc = self._irn.ctypes.data_as(_PINT)
        self.id.jcn_loc = self._jcn.ctypes.data_as(_PINT)
        self.id.a_loc = self._a.ctypes.data
        try:
            self._run(4)  # analysis and factorisation
        except MumpsError:
            self.destroy()
            raise
        self._counts = None if comm is None else np.array(comm.allgather(self.rows))
        self._rhs = np.zeros(n if self._host else 1, dtype=np.complex128)

    @property
    def _host(self) -> bool:
        return self.comm is None or self.comm.Get_rank() == 0

    @property
    def flops(self) -> float:
        """RINFOG(3): the factorisation's operation count (complex operations)."""
        return float(self.id.rinfog[2])

    def _run(self, job: int) -> None:
        self.id.job = job
        self.lib.zmumps_c(C.byref(self.id))
        if self.id.infog[0] < 0:
            raise MumpsError(f"the complex MUMPS factor of the flutter search failed (ZMUMPS job {job}: INFOG(1) = "
                             f"{self.id.infog[0]}, INFOG(2) = {self.id.infog[1]}, MUMPS users' guide §8); check the "
                             "-meicp_flutter_st_mat_mumps_* options, or use -meicp_flutter_real_form")

    def solve(self, local: np.ndarray) -> np.ndarray:
        """This rank's entries of the solution of F x = b, b given by this rank's entries.
        Collective."""
        local = np.ascontiguousarray(local, dtype=np.complex128)
        if self.comm is None:
            self._rhs[:] = local
        else:
            self.comm.Gatherv(local, [self._rhs, self._counts] if self._host else None, root=0)
        self.id.nrhs, self.id.lrhs = 1, self.n
        self.id.rhs = self._rhs.ctypes.data
        self._run(3)
        if self.comm is None:
            return self._rhs.copy()
        out = np.empty(self.rows, dtype=np.complex128)
        self.comm.Scatterv([self._rhs, self._counts] if self._host else None, out, root=0)
        return out

    def destroy(self) -> None:
        if self.id is not None and self.id.job != -2:
            self._run(-2)
        self.id = None

    def __enter__(self) -> "ComplexFactor":
        return self

    def __exit__(self, *exc) -> None:
        self.destroy()


def _self_comm() -> int:
    from mpi4py import MPI

    return MPI.COMM_SELF.py2f()


def ctypes_size() -> int:
    """sizeof(ZMUMPS_STRUC_C) as laid out here (8,360 bytes for MUMPS 5.5.1's header)."""
    return C.sizeof(ZMUMPS_STRUC_C)
