"""An install check: a distributed pencil built from per-rank CSR, solved by SLEPc and
compared with a dense SciPy reference.  Used by ``make demo`` and the harness tests.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.linalg
import scipy.sparse as sp

from . import import_petsc
from .comm import to_petsc_comm
from .eigen import solve_ghep
from .mat import mat_from_local_csr, ownership
from .options import SELFCHECK


def laplacian_rows(nx: int, ny: int, start: int, end: int) -> sp.csr_matrix:
    """Rows ``start:end`` of the 5-point Dirichlet Laplacian on an nx × ny grid, vectorized."""
    n = nx * ny
    rows = np.arange(start, end)
    i, j = rows % nx, rows // nx
    r, c, v = [rows], [rows], [np.full(rows.size, 4.0)]
    for ok, off in ((i > 0, -1), (i < nx - 1, 1), (j > 0, -nx), (j < ny - 1, nx)):
        r.append(rows[ok] - start)
        c.append(rows[ok] + off)
        v.append(np.full(ok.sum(), -1.0))
    r[0] = rows - start
    return sp.csr_matrix((np.concatenate(v), (np.concatenate(r), np.concatenate(c))),
                         shape=(end - start, n))


def mass_rows(nx: int, ny: int, start: int, end: int) -> sp.csr_matrix:
    """Rows of a positive diagonal 'lumped mass' that varies along the grid (not a multiple of I)."""
    rows = np.arange(start, end)
    d = 1.0 + (rows // nx) / max(ny - 1, 1)
    return sp.csr_matrix((d, (rows - start, rows)), shape=(end - start, nx * ny))


def ghep_selfcheck(comm=None, nx: int = 12, ny: int = 10, nev: int = 4) -> dict:
    """Solve the 4 smallest eigenvalues of (K, M) with SLEPc on ``comm`` and compare with
    ``scipy.linalg.eigh`` on the same dense pencil.  Collective; every rank returns the report."""
    PETSc = import_petsc()
    pcomm = to_petsc_comm(comm)
    n = nx * ny
    start, end = ownership(n, pcomm.getRank(), pcomm.getSize())
    t0 = time.perf_counter()
    K = mat_from_local_csr(pcomm, laplacian_rows(nx, ny, start, end), n)
    M = mat_from_local_csr(pcomm, mass_rows(nx, ny, start, end), n)
    t1 = time.perf_counter()
    pairs = solve_ghep(K, M, nev=nev, target=0.0, prefix=SELFCHECK)
    t2 = time.perf_counter()
    K.destroy()
    M.destroy()
    Kd = laplacian_rows(nx, ny, 0, n).toarray()
    Md = mass_rows(nx, ny, 0, n).toarray()
    ref = scipy.linalg.eigh(Kd, Md, eigvals_only=True, subset_by_index=[0, nev - 1])
    got = np.sort(pairs.values)
    return {
        "ranks": pcomm.getSize(),
        "n": n,
        "slepc": got,
        "scipy": ref,
        "max_rel_error": float(np.max(np.abs(got - ref) / np.abs(ref))),
        "max_residual": float(np.max(pairs.residuals)),
        "assemble_s": t1 - t0,
        "solve_s": t2 - t1,
        "petsc_version": PETSc.Sys.getVersion(),
    }
