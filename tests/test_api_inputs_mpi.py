"""``comm=None`` under ``mpirun`` (docs/design.md §10.2): ``meicp.analyze`` and
``meicp.critical_friction`` run on ``MPI.COMM_WORLD``, as petsc4py and DOLFINx do;
``meicp.assemble`` stays serial SciPy."""

import numpy as np
import pytest
import scipy.sparse as sp

from .conftest import ROOT

pytestmark = pytest.mark.mpi(min_size=2)
TWO_LAYERS = ROOT / "data" / "scenes" / "two_layers.toml"


def test_comm_none_shares_the_work_of_every_rank(monkeypatch):
    from mpi4py import MPI

    import meicp
    import meicp.api

    ranks = []
    real = meicp.api._analyze

    def spy(scene, comm, **kw):
        ranks.append(comm.Get_size())
        return real(scene, comm, **kw)

    monkeypatch.setattr(meicp.api, "_analyze", spy)
    together = meicp.analyze(TWO_LAYERS)
    alone = meicp.analyze(TWO_LAYERS, comm=MPI.COMM_SELF)
    assert ranks == [MPI.COMM_WORLD.Get_size(), 1]
    assert together.stable is alone.stable is False
    assert [m.sigma for m in together.modes] == pytest.approx([m.sigma for m in alone.modes], rel=1e-10)
    assert np.allclose(together.modes[0].x, alone.modes[0].x, atol=1e-10)
    mu = meicp.critical_friction(TWO_LAYERS)
    assert float(mu) == pytest.approx(float(meicp.critical_friction(TWO_LAYERS, comm=MPI.COMM_SELF)), rel=1e-12)
    K, M = meicp.assemble(TWO_LAYERS)
    assert sp.issparse(K) and sp.issparse(M)
