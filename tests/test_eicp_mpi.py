"""EiCP on 2 ranks: enumeration split across ranks, active-set on distributed PETSc Mats."""

import numpy as np
import pytest
import scipy.sparse as sp

pytestmark = pytest.mark.mpi(min_size=2)


def _z(n, seed):
    rng = np.random.default_rng(seed)
    A = -rng.uniform(0.1, 1.0, (n, n))
    np.fill_diagonal(A, rng.standard_normal(n))
    return A, np.diag(rng.uniform(0.5, 2.0, n))


def test_enumeration_split_across_ranks_equals_serial(comm):
    import meicp

    A, B = _z(9, 3)
    par = meicp.solve_eicp(A, B, all_solutions=True, comm=comm)
    ser = meicp.solve_eicp(A, B, all_solutions=True)
    assert par.coverage["ranks"] == comm.size
    assert len(par.solutions) == len(ser.solutions) == 2 ** 9 - 1
    assert np.allclose([s.lam for s in par.solutions], [s.lam for s in ser.solutions], rtol=1e-12)
    assert par.coverage["eigen_solves"] == ser.coverage["eigen_solves"]


def test_active_set_distributed_equals_serial(comm):
    import meicp
    from meicp.petsc.mat import mat_from_scipy
    from meicp.petsc.selfcheck import laplacian_rows

    m = 12
    n = m * m
    K = (laplacian_rows(m, m, 0, n)).tocsr()
    Mass = sp.diags(np.linspace(1.0, 2.0, n)).tocsr()
    J = np.arange(0, n, 7)  # a scattered complementarity set
    Ak, Bk = mat_from_scipy(comm, -K), mat_from_scipy(comm, Mass)
    par = meicp.solve_eicp(Ak, Bk, J=J, method="active-set", target=0.0, nev=4)
    ser = meicp.solve_eicp(-K, Mass, J=J, method="active-set", target=0.0, nev=4)
    assert par.success and ser.success, (par.summary(), ser.summary())
    assert abs(par.lam - ser.lam) <= 1e-10 * abs(ser.lam)
    assert np.allclose(par.solutions[0].x, ser.solutions[0].x, atol=1e-8)
    assert par.solutions[0].residual <= 1e-10
    Ak.destroy()
    Bk.destroy()
