"""Distributed paths under ``mpirun -n 2`` (``make test-mpi``)."""

import numpy as np
import pytest

pytestmark = pytest.mark.mpi(min_size=2)


def test_matrix_from_per_rank_csr_equals_scipy(comm):
    from meicp.petsc.mat import mat_from_local_csr, mat_to_scipy, ownership
    from meicp.petsc.selfcheck import laplacian_rows

    nx, ny = 7, 6
    n = nx * ny
    start, end = ownership(n, comm.rank, comm.size)
    A = mat_from_local_csr(comm, laplacian_rows(nx, ny, start, end), n)
    assert A.getOwnershipRange() == (start, end)
    assert A.getSize() == (n, n)
    full = mat_to_scipy(A)
    assert abs(full - laplacian_rows(nx, ny, 0, n)).max() == 0
    A.destroy()


def test_slepc_ghep_matches_scipy_on_two_ranks(comm):
    from meicp.petsc.selfcheck import ghep_selfcheck

    r = ghep_selfcheck(comm, nx=15, ny=11, nev=4)
    assert r["ranks"] == comm.size >= 2
    assert r["max_rel_error"] < 1e-10
    assert r["max_residual"] < 1e-8
    # every rank holds the same answer
    gathered = comm.allgather(r["slepc"])
    assert all(np.array_equal(gathered[0], g) for g in gathered)


def test_serial_and_parallel_solves_agree(comm):
    from mpi4py import MPI

    from meicp.petsc.selfcheck import ghep_selfcheck

    par = ghep_selfcheck(comm, nx=10, ny=10, nev=3)["slepc"]
    ser = ghep_selfcheck(MPI.COMM_SELF, nx=10, ny=10, nev=3)["slepc"]
    assert np.allclose(par, ser, rtol=1e-10, atol=0)


def test_vec_gather(comm):
    from meicp.petsc import import_petsc
    from meicp.petsc.mat import vec_to_numpy

    PETSc = import_petsc()
    v = PETSc.Vec().createMPI(10, comm=comm)
    lo, hi = v.getOwnershipRange()
    v.setArray(np.arange(lo, hi, dtype=float))
    assert np.array_equal(vec_to_numpy(v), np.arange(10.0))
    v.destroy()
