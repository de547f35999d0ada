"""Exact tests over all ``2ⁿ − 1`` principal submatrices (n ≤ exact_limit) for P, P0, R0,
E0 and (strict) copositivity: :func:`_exact_tests` and the witness searches it batches
(the method is described in :mod:`meicp.lcp.classes`).
"""

from __future__ import annotations

from itertools import combinations, islice

import numpy as np
from scipy.optimize import Bounds, LinearConstraint, milp

from .classes_report import _fmt_set, _State

#: classes decided by an exponential exact test when n ≤ exact_limit
_EXACT = ("p_matrix", "p0", "r0", "copositive", "strictly_copositive", "semimonotone")


# ----------------------------------------------------------------------------------------
# Exact tests over all principal submatrices (n ≤ exact_limit)
# ----------------------------------------------------------------------------------------

def _subset_batches(n: int, k: int, max_entries: int = 400_000):
    """All k-subsets of range(n) as int arrays of shape (batch, k), bounded memory."""
    per = max(1, max_entries // (k * k))
    it = combinations(range(n), k)
    while True:
        chunk = list(islice(it, per))
        if not chunk:
            return
        yield np.array(chunk, dtype=np.intp)


def _r0_witness_ok(A: np.ndarray, x: np.ndarray, tol: float) -> bool:
    """x in the simplex solves LCP(0, A) to ``tol``: Ax ≥ 0 and (Ax)_i = 0 where x_i > 0."""
    w = A @ x
    return bool(w.min() >= -tol and np.all(np.abs(w[x > 0]) <= tol))


def _e0_witness_ok(A: np.ndarray, x: np.ndarray, tol: float) -> bool:
    """x in the simplex violates semimonotonicity: (Ax)_i < −tol wherever x_i > 0."""
    w = A @ x
    return bool(np.all(w[x > 0] < -tol))


def _padded(n: int, idx, values) -> np.ndarray:
    """A vector of length n in the simplex with ``values`` (clipped at 0) on ``idx``."""
    x = np.zeros(n)
    x[idx] = np.clip(values, 0.0, None)
    total = x.sum()
    return x / total if total > 0 else x


def _r0_support_search(A: np.ndarray, S: np.ndarray, sv: np.ndarray, Vt: np.ndarray, tol: float):
    """For a singular A_SS (SVD ``sv, Vt``): a nonzero solution of LCP(0, A) with support
    in S, ``None`` if there is none, or ``"deferred"`` when the null space has dimension
    ≥ 2 (then :func:`_r0_milp` decides all such supports at once)."""
    n = A.shape[0]
    N = Vt[sv <= tol]  # rows: orthonormal basis of the null space of A_SS
    if N.shape[0] != 1:
        return "deferred"
    v = N[0] * (1.0 if N[0].sum() >= 0 else -1.0)
    if v.min() < -1e-9 * np.abs(v).max():
        return None  # the only null direction changes sign: no solution with support S
    x = _padded(n, S, v)
    return x if _r0_witness_ok(A, x, tol) else None


def _r0_milp(A: np.ndarray, tol: float):
    """Decide whether LCP(0, A) has a solution x in the simplex with one mixed-integer
    feasibility problem (HiGHS): binaries z_i mark the support,
    ``x_i ≤ z_i``, ``0 ≤ (Ax)_i ≤ U_i (1 − z_i)`` with ``U_i = max_j |A_ij|`` (a valid bound
    on the simplex), ``1ᵀx = 1``.  Used only when some singular principal submatrix has a
    null space of dimension ≥ 2, where the closed-form check does not apply.
    Returns (x or None, tolerance the witness satisfies)."""
    n = A.shape[0]
    U = np.abs(A).max(axis=1) * (1 + 1e-9) + 1e-12
    I = np.eye(n)
    Z = np.zeros((n, n))
    rows = np.vstack([np.hstack([A, Z]),               # Ax ≥ 0
                      np.hstack([A, np.diag(U)]),      # Ax + U z ≤ U
                      np.hstack([I, -I]),              # x − z ≤ 0
                      np.hstack([np.ones(n), np.zeros(n)])[None, :]])
    lo = np.concatenate([np.zeros(n), np.full(n, -np.inf), np.full(n, -np.inf), [1.0]])
    hi = np.concatenate([np.full(n, np.inf), U, np.zeros(n), [1.0]])
    res = milp(np.zeros(2 * n), constraints=LinearConstraint(rows, lo, hi),
               integrality=np.concatenate([np.zeros(n), np.ones(n)]), bounds=Bounds(0.0, 1.0))
    if res.status == 2:  # infeasible
        return None, tol
    if res.x is None:
        raise RuntimeError(f"R0 MILP did not finish: {res.message}")
    x = _padded(n, np.arange(n), res.x[:n])
    for t in (tol, 1e-6):
        if _r0_witness_ok(A, x, t):
            return x, t
    raise RuntimeError("R0 MILP returned a point that is not a solution of LCP(0, M)")


def _e0_search(A: np.ndarray, idx: np.ndarray, U: np.ndarray, sv: np.ndarray, Vt: np.ndarray,
               tol: float):
    """A semimonotonicity violation among the subsets ``idx``, or None.

    ``x_S = −A_SS⁻¹·1`` from the SVDs ``A_SS = U diag(sv) Vt`` already computed (a batched
    ``solve`` is much slower under a multithreaded BLAS), on the numerically nonsingular
    subsets; a nonnegative ``x_S`` is a violation, checked against the definition.
    """
    n = A.shape[0]
    ok = np.flatnonzero(sv[:, -1] > 1e-13)
    if not ok.size:
        return None
    coef = U[ok].sum(axis=1) / sv[ok]            # (Uᵀ·1) / σ, row-wise
    xs = -np.einsum("cij,ci->cj", Vt[ok], coef)  # −V diag(1/σ) Uᵀ·1
    for j in np.flatnonzero(xs.min(axis=1) >= -1e-12 * np.abs(xs).max(axis=1)):
        x = _padded(n, idx[ok[j]], xs[j])
        if _e0_witness_ok(A, x, tol):
            return x
    return None


def _exact_tests(A: np.ndarray, H: np.ndarray, tol: float, st: _State) -> None:
    """All-subset tests for P, P0, R0, E0 and (strict) copositivity; A, H scaled to max|A| = 1.

    Subsets are visited by increasing size, so every refutation names a smallest witness.
    """
    n = A.shape[0]
    total = 2 ** n - 1
    open_ = {"p": True, "p0": True, "r0": True, "e0": True, "cop": True, "scop": True}
    min_sv = np.inf
    deferred = 0  # singular supports with a null space of dimension ≥ 2
    for k in range(1, n + 1):
        for idx in _subset_batches(n, k):
            if not any(open_.values()):
                break
            rows, cols = idx[:, :, None], idx[:, None, :]
            sub = A[rows, cols]
            if open_["p"] or open_["p0"] or open_["r0"] or open_["e0"]:
                U, sv, Vt = np.linalg.svd(sub)
                smin = sv[:, -1]
                min_sv = min(min_sv, float(smin.min()))
                zero = smin <= tol
            if open_["p"] or open_["p0"]:
                sign, logdet = np.linalg.slogdet(sub)
                if open_["p"]:
                    bad = np.flatnonzero(zero | (sign <= 0))
                    if bad.size:
                        b = bad[0]
                        what = ("singular" if zero[b] else
                                f"of negative determinant {sign[b] * np.exp(logdet[b]):.3g}·max|M|^{k}")
                        st.decide("p_matrix", False, f"principal submatrix {_fmt_set(idx[b])} is {what}")
                        open_["p"] = False
                if open_["p0"]:
                    bad = np.flatnonzero(~zero & (sign < 0))
                    if bad.size:
                        b = bad[0]
                        st.decide("p0", False, f"principal minor of {_fmt_set(idx[b])} = "
                                  f"{sign[b] * np.exp(logdet[b]):.3g}·max|M|^{k} < 0")
                        open_["p0"] = False
            if open_["r0"]:
                for b in np.flatnonzero(zero):
                    x = _r0_support_search(A, idx[b], sv[b], Vt[b], tol)
                    if isinstance(x, str):
                        deferred += 1
                    elif x is not None:
                        st.decide("r0", False, f"LCP(0, M) has the nonzero solution x "
                                  f"supported on {_fmt_set(np.flatnonzero(x > 0))}", witness=x)
                        open_["r0"] = False
                        break
            if open_["e0"]:
                x = _e0_search(A, idx, U, sv, Vt, tol)
                if x is not None:
                    st.decide("semimonotone", False, f"x ≥ 0 supported on "
                              f"{_fmt_set(np.flatnonzero(x > 0))} has (Mx)_i < 0 on its support",
                              witness=x)
                    open_["e0"] = False
            if open_["cop"] or open_["scop"]:
                w, V = np.linalg.eigh(H[rows, cols])  # Kaplan: positive eigenvectors of H_SS
                V = V * np.where(V.sum(axis=1) >= 0, 1.0, -1.0)[:, None, :]
                positive = V.min(axis=1) > -1e-12
                for key, name, limit, rel in (("cop", "copositive", -tol, "<"),
                                              ("scop", "strictly_copositive", tol, "≤")):
                    if not open_[key]:
                        continue
                    hits = np.argwhere(positive & ((w < limit) if key == "cop" else (w <= limit)))
                    for b, j in hits:
                        x = _padded(n, idx[b], V[b, :, j])
                        q = float(x @ H @ x)
                        if (q < 0) if key == "cop" else (q <= tol):
                            st.decide(name, False, f"principal submatrix {_fmt_set(idx[b])} of (M+Mᵀ)/2 "
                                      f"has a positive eigenvector with eigenvalue {w[b, j]:.3g}·max|M| "
                                      f"{rel} 0 (Kaplan): xᵀMx = {q:.3g}·max|M|", witness=x)
                            open_[key] = False
                            if key == "cop":
                                open_["scop"] = False
                                st.decide("strictly_copositive", False, "not copositive", witness=x)
                            break
    if open_["p"]:
        st.decide("p_matrix", True, f"all {total} principal minors > 0 "
                  f"(smallest singular value of a principal submatrix {min_sv:.3g}·max|M|)")
    if open_["p0"]:
        st.decide("p0", True, f"all {total} principal minors ≥ 0")
    if open_["r0"] and deferred:
        try:
            x, used = _r0_milp(A, tol)
        except RuntimeError as exc:
            st.notes.append(str(exc))
        else:
            if x is None:
                st.decide("r0", True, f"no support among the {total} carries a nonzero solution of "
                          f"LCP(0, M) ({deferred} with null spaces of dimension ≥ 2 settled by one MILP)")
            else:
                st.decide("r0", False, f"LCP(0, M) has the nonzero solution x supported on "
                          f"{_fmt_set(np.flatnonzero(x > 0))} (found by MILP, residual ≤ {used:g}·max|M|)",
                          witness=x)
        open_["r0"] = False
    if open_["r0"]:
        st.decide("r0", True, f"no support among the {total} carries a nonzero solution of LCP(0, M)")
    if open_["e0"]:
        st.decide("semimonotone", True, f"no subset S of the {total} has x_S = −M_SS⁻¹·1 ≥ 0")
    if open_["cop"]:
        st.decide("copositive", True, f"Kaplan: no principal submatrix of (M+Mᵀ)/2 (all {total}) "
                  "has a positive eigenvector with a negative eigenvalue")
    if open_["scop"]:
        st.decide("strictly_copositive", True, f"Kaplan: no principal submatrix of (M+Mᵀ)/2 (all {total}) "
                  "has a positive eigenvector with a nonpositive eigenvalue")
