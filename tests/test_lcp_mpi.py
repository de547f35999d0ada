"""Distributed LCP solves on 2 ranks: PETSc Mat input, same answer as serial."""

import numpy as np
import pytest
import scipy.sparse as sp

pytestmark = pytest.mark.mpi(min_size=2)


@pytest.mark.parametrize("method", ["newton", "tao", "auto"])
def test_distributed_lcp_matches_serial(comm, method):
    from meicp.lcp.solve import solve_lcp
    from meicp.petsc.mat import mat_from_scipy
    from meicp.petsc.selfcheck import laplacian_rows

    m = 30
    M = (laplacian_rows(m, m, 0, m * m) + 0.05 * sp.eye(m * m)).tocsr()
    q = np.random.default_rng(11).standard_normal(m * m)
    A = mat_from_scipy(comm, M)
    r = solve_lcp(A, q, method=method)
    assert r.success and r.residual <= 1e-10, r.summary()
    serial = solve_lcp(M, q, method="lemke" if method == "auto" else method)
    assert np.allclose(r.x, serial.x, atol=1e-9)
    same = comm.allgather(r.x)
    assert all(np.array_equal(same[0], s) for s in same)
    A.destroy()


def test_distributed_rejects_dense_only_methods(comm):
    from meicp.core.errors import ProblemError
    from meicp.lcp.solve import solve_lcp
    from meicp.petsc.mat import mat_from_scipy

    A = mat_from_scipy(comm, sp.eye(4).tocsr())
    with pytest.raises(ProblemError, match="PETSc Mat"):
        solve_lcp(A, np.ones(4), method="lemke")
    A.destroy()
