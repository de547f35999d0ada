"""The BLAS threads of meicp's dense phases.

NumPy/SciPy's OpenBLAS starts one thread per core.  meicp's dense phases — the condensed
divergence certificates, the critical friction's bracket, the enumeration of supports — are
hundreds of eigen-solves of order 10 to 10³ in a loop.  A second thread gains them little on
an idle machine, and on a busy one threads spinning against other processes made them many
times slower (docs/benchmarks-notes.md, core).  So these phases run
with ``MEICP_BLAS_THREADS`` threads (default 1) through threadpoolctl, the way scikit-learn
bounds its BLAS; the sparse factorisations (MUMPS) and the flutter analysis's single large
QZ keep the process's setting.  threadpoolctl comes from Debian (``make setup``).
"""
from __future__ import annotations

import os

from threadpoolctl import threadpool_limits

#: the BLAS threads of a dense phase unless ``MEICP_BLAS_THREADS`` says otherwise
DEFAULT = 1


def dense_phase():
    """A context manager limiting the BLAS threads for a loop of dense eigen-solves."""
    text = os.environ.get("MEICP_BLAS_THREADS", "")
    threads = int(text) if text.isdigit() and int(text) > 0 else DEFAULT
    return threadpool_limits(limits=threads, user_api="blas")
