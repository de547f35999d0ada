"""The BLAS threads of the dense phases (:mod:`meicp.core.threads`)."""

import numpy as np
import pytest
import threadpoolctl

from meicp.core.threads import dense_phase


def _blas_threads():
    return [lib["num_threads"] for lib in threadpoolctl.threadpool_info() if lib["user_api"] == "blas"]


@pytest.mark.parametrize("setting, expected", [(None, 1), ("2", 2), ("0", 1), ("many", 1)])
def test_a_dense_phase_bounds_the_blas_threads(monkeypatch, setting, expected):
    np.linalg.eigvalsh(np.eye(3))  # BLAS loaded
    if setting is None:
        monkeypatch.delenv("MEICP_BLAS_THREADS", raising=False)
    else:
        monkeypatch.setenv("MEICP_BLAS_THREADS", setting)
    before = _blas_threads()
    assert before, "threadpoolctl sees no BLAS library"
    with dense_phase():
        assert _blas_threads() == [expected] * len(before)
    assert _blas_threads() == before
