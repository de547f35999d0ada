"""The MEiCP pencil ``A = −P K Q``, ``B = P M Q`` from the lattice's K, M and the contact maps
P (rows) and Q (columns), for any layout: SciPy products when K is a SciPy matrix, PETSc
matrix products on the lattice's row bands when it is a distributed Mat."""

from __future__ import annotations

import numpy as np

from ..core.matrix import is_petsc_mat
from .mat import mat_from_rows


def reduced_pencil(K, M, P, Q, retained: np.ndarray, P_B=None):
    """``(A, B)`` with ``A = −P K Q``, ``B = P_B M Q`` (``P_B = P`` by default: the MEiCP
    pencil; the critical friction's pencil in μ has ``M = K`` and ``P_B`` the friction rows).

    P, P_B (r × n) and Q (n × r): SciPy matrices every rank holds, in natural numbering;
    ``retained``: the natural DOF of each of the r reduced DOFs, sorted.  K, M SciPy: CSR
    results.  K, M PETSc (collective on their communicator): Q gets K's row bands and each
    reduced DOF is owned by the rank of its node, two sparse products per matrix; the
    caller destroys A and B."""
    P_B = P if P_B is None else P_B
    if not is_petsc_mat(K):
        return -(P @ K @ Q).tocsr(), (P_B @ M @ Q).tocsr()
    Qm, Pm = _maps_on_bands(K, P, Q, retained)
    PBm = Pm if P_B is P else _maps_on_bands(K, P_B, None, retained)[1]
    try:
        KQ, MQ = K.matMult(Qm), M.matMult(Qm)
        A, B = Pm.matMult(KQ), PBm.matMult(MQ)
        A.scale(-1.0)
        KQ.destroy()
        MQ.destroy()
    finally:
        Qm.destroy()
        Pm.destroy()
        if PBm is not Pm:
            PBm.destroy()
    return A, B


def reduced_matrix(C, P, Q, retained: np.ndarray):
    """``P C Q`` in the pencil's layout (as :func:`reduced_pencil` lays out A and B): SciPy CSR
    when C is SciPy, else a PETSc Mat the caller destroys (collective)."""
    if not is_petsc_mat(C):
        return (P @ C @ Q).tocsr()
    Qm, Pm = _maps_on_bands(C, P, Q, retained)
    try:
        CQ = C.matMult(Qm)
        try:
            return Pm.matMult(CQ)
        finally:
            CQ.destroy()
    finally:
        Qm.destroy()
        Pm.destroy()


def _maps_on_bands(K, P, Q, retained: np.ndarray):
    """``(Q, P)`` as PETSc Mats on the row bands of the distributed K (Q None: not made): Q gets
    K's row bands, P the rows of the reduced DOFs each rank owns.  Collective."""
    comm = K.getComm()
    lo, hi = K.getOwnershipRange()
    r_lo, r_hi = np.searchsorted(retained, [lo, hi])
    n, r = K.getSize()[0], retained.size
    Qm = None if Q is None else mat_from_rows(comm, Q[lo:hi], (n, r), int(r_hi - r_lo))
    return Qm, mat_from_rows(comm, P[r_lo:r_hi], (r, n), hi - lo)
