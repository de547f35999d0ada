"""Sufficient tests for the matrix classes, at any size and sparse-friendly unless noted:
each proves its conclusion and only fills classes still undecided (:func:`_sufficient_tests`;
the list is in :mod:`meicp.lcp.classes`).
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .classes_report import LABELS, _State


# ----------------------------------------------------------------------------------------
# Sufficient tests (any size; sparse-friendly unless noted)
# ----------------------------------------------------------------------------------------

def _offdiag(M):
    """M without its diagonal, in M's own format."""
    if sp.issparse(M):
        D = M - sp.diags(M.diagonal())
        D.eliminate_zeros()
        return D.tocsr()
    D = M.copy()
    np.fill_diagonal(D, 0.0)
    return D


def _pair_minors(M):
    """2×2 principal minors over the coupled pairs i < j (M_ij·M_ji ≠ 0; the others have
    minor d_i·d_j, settled by the diagonal): (i, j, determinant, smallest singular value)."""
    d = np.asarray(M.diagonal(), dtype=float)
    C = sp.coo_matrix(M.multiply(M.T) if sp.issparse(M) else M * M.T)
    keep = C.row < C.col
    i, j = C.row[keep], C.col[keep]
    if not i.size:
        return i, j, np.zeros(0), np.zeros(0)
    mij = np.asarray(M[i, j]).ravel()
    mji = np.asarray(M[j, i]).ravel()
    det = d[i] * d[j] - mij * mji
    fro2 = d[i] ** 2 + d[j] ** 2 + mij ** 2 + mji ** 2
    smax = np.sqrt(0.5 * (fro2 + np.sqrt(np.maximum(fro2 ** 2 - 4 * det ** 2, 0.0))))
    smin = np.abs(det) / np.where(smax > 0, smax, 1.0)
    return i, j, det, smin


def _negative_pairs(H):
    """The pairs i < j where the symmetric part has H_ij < 0: (i, j, H_ij)."""
    Hc = sp.coo_matrix(H)
    keep = (Hc.row < Hc.col) & (Hc.data < 0)
    return Hc.row[keep], Hc.col[keep], Hc.data[keep]


def _mmatrix_test(M, tol: float):
    """For a Z-matrix: solve Mx = 1.  x ≥ 0 with Mx > 0 (checked with a rounding bound)
    proves M is a nonsingular M-matrix; a clearly negative x_i disproves it (an M-matrix
    has M⁻¹ ≥ 0).  Returns (True/False/None, test sentence, x)."""
    n = M.shape[0]
    e = np.ones(n)
    try:
        if sp.issparse(M):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", spla.MatrixRankWarning)
                x = spla.spsolve(M.tocsc(), e)
        else:
            x = np.linalg.solve(M, e)
    except (np.linalg.LinAlgError, RuntimeError):
        return False, "Z-matrix and singular (not P)", None
    if not np.all(np.isfinite(x)):
        return False, "Z-matrix and singular (not P)", None
    Mx = np.asarray(M @ x).ravel()
    absM = abs(M) if sp.issparse(M) else np.abs(M)
    rounding = 4 * n * np.finfo(float).eps * np.asarray(absM @ np.abs(x)).ravel()
    if x.min() >= 0 and np.all(Mx - rounding > 0):
        return True, "Z-matrix with x = M⁻¹·1 ≥ 0 and Mx > 0 (semipositive Z ⇒ M-matrix)", x
    if x.min() < -1e-8 * np.abs(x).max() and np.all(np.abs(Mx - 1) < 1e-6):
        return False, f"Z-matrix with M⁻¹·1 having a negative entry ({x.min():.3g}): M⁻¹ is not ≥ 0", x
    return None, "Z-matrix but M x = 1 is too ill-conditioned to decide", None


def _sufficient_tests(M, A, H, Hs, s, tol, st: _State, dense_limit: int, det_limit: int) -> None:
    """Cheap tests that prove their conclusion; they only fill classes still undecided.

    M: the validated input (dense or CSR); A: dense normalised copy or None (sparse,
    n > dense_limit); H, Hs: normalised symmetric part, dense or sparse.
    """
    n = M.shape[0]
    An = A if A is not None else (M / s)
    d = np.asarray(An.diagonal(), dtype=float)
    off = _offdiag(An)
    off_abs = abs(off) if sp.issparse(off) else np.abs(off)
    row_off = np.asarray(off_abs.sum(axis=1)).ravel()
    col_off = np.asarray(off_abs.sum(axis=0)).ravel()

    # diagonal entries are the 1×1 principal minors and x = e_i in every definition
    if d.min() < -tol:
        i = int(np.argmin(d))
        for name in ("p0", "copositive", "semimonotone", "psd"):
            ei = np.zeros(n)
            ei[i] = 1.0
            st.decide(name, False, f"diagonal entry M[{i},{i}] = {d[i] * s:.3g} < 0",
                      witness=ei if name != "p0" and name != "psd" else None)
    if d.min() <= tol:
        i = int(np.argmin(d))
        st.decide("p_matrix", False, f"diagonal entry M[{i},{i}] = {d[i] * s:.3g} ≤ 0")
        ei = np.zeros(n)
        ei[i] = 1.0
        st.decide("strictly_copositive", False, f"diagonal entry M[{i},{i}] = {d[i] * s:.3g} ≤ 0: "
                  "e_iᵀMe_i ≤ 0", witness=ei)
    # x = e_i solves LCP(0, M) when M_ii = 0 and column i is ≥ 0
    zero_diag = np.flatnonzero(np.abs(d) <= tol)
    if zero_diag.size:
        col_min = np.asarray(An.min(axis=0).toarray() if sp.issparse(An) else An.min(axis=0)).ravel()
        hits = zero_diag[col_min[zero_diag] >= -tol]
        if hits.size:
            i = int(hits[0])
            ei = np.zeros(n)
            ei[i] = 1.0
            st.decide("r0", False, f"M[{i},{i}] = 0 and column {i} ≥ 0: x = e_{i} solves LCP(0, M)",
                      witness=ei)

    # 2×2 principal minors (zero when the 2×2 block is numerically singular, as in the
    # exact test) and 2×2 copositivity of H: only coupled pairs can fail
    pi, pj, det2, smin2 = _pair_minors(An)
    if det2.size:
        bad = np.flatnonzero((det2 <= 0) | (smin2 <= tol))
        if bad.size:
            b = bad[0]
            st.decide("p_matrix", False, f"2×2 principal minor of {{{pi[b]},{pj[b]}}} = "
                      f"{det2[b] * s * s:.3g} (zero or negative)")
        bad = np.flatnonzero((det2 < 0) & (smin2 > tol))
        if bad.size:
            b = bad[0]
            st.decide("p0", False, f"2×2 principal minor of {{{pi[b]},{pj[b]}}} = {det2[b] * s * s:.3g} < 0")
    ci, cj, hij = _negative_pairs(H)
    if ci.size:
        hd = np.asarray(H.diagonal(), dtype=float)
        a, c = hd[ci], hd[cj]
        ok = (a >= 0) & (c >= 0)
        t = np.clip((c - hij) / np.where(ok, a - 2 * hij + c, 1.0), 0.0, 1.0)
        f = a * t * t + 2 * hij * t * (1 - t) + c * (1 - t) ** 2  # min of xᵀHx on the edge
        f = np.where(ok, f, np.inf)
        b = int(np.argmin(f))
        if f[b] <= tol:
            x = np.zeros(n)
            x[ci[b]], x[cj[b]] = t[b], 1 - t[b]
            test = f"on the pair {{{ci[b]},{cj[b]}}}: xᵀMx = {f[b] * s:.3g} for x ≥ 0, 1ᵀx = 1"
            if f[b] < -tol:
                st.decide("copositive", False, test, witness=x)
            st.decide("strictly_copositive", False, test, witness=x)

    # nonnegative matrices: x ≥ 0 gives Mx ≥ 0 and xᵀMx ≥ Σ M_ii x_i²
    off_min = (off.data.min() if off.nnz else 0.0) if sp.issparse(off) else off.min()
    if min(off_min, d.min()) >= 0:
        st.decide("copositive", True, "M ≥ 0 entrywise")
        st.decide("semimonotone", True, "M ≥ 0 entrywise")
        if d.min() > tol:
            st.decide("strictly_copositive", True, "M ≥ 0 entrywise with positive diagonal")

    # strict diagonal dominance with positive diagonal ⇒ every principal submatrix has
    # its Gershgorin discs in the right half plane ⇒ every principal minor > 0
    if d.min() > tol and (np.all(d - row_off > tol) or np.all(d - col_off > tol)):
        which = "row" if np.all(d - row_off > tol) else "column"
        st.decide("p_matrix", True, f"strictly {which} diagonally dominant with positive diagonal")

    # definiteness of the symmetric part
    if A is not None and n <= dense_limit:
        lam = np.linalg.eigvalsh(H)
        st.decide("positive_definite", lam[0] > tol,
                  f"smallest eigenvalue of (M+Mᵀ)/2 = {lam[0] * s:.3g}")
        st.decide("psd", lam[0] >= -tol, f"smallest eigenvalue of (M+Mᵀ)/2 = {lam[0] * s:.3g}")
    elif A is not None:
        try:
            np.linalg.cholesky(H)
            st.decide("positive_definite", True, "Cholesky of (M+Mᵀ)/2 succeeded")
        except np.linalg.LinAlgError:
            st.decide("positive_definite", False, "Cholesky of (M+Mᵀ)/2 failed")
    elif st.get("positive_definite") is None:
        _sparse_ldl_test(Hs, tol, st)

    hd = np.asarray(H.diagonal(), dtype=float)
    hoff = np.asarray(abs(_offdiag(H)).sum(axis=1) if sp.issparse(H) else np.abs(_offdiag(H)).sum(axis=1)).ravel()
    if np.all(hd - hoff > tol):
        st.decide("positive_definite", True, "(M+Mᵀ)/2 strictly diagonally dominant with positive "
                  "diagonal (Gershgorin)")
    elif np.all(hd - hoff >= -tol) and hd.min() >= -tol:
        st.decide("psd", True, "(M+Mᵀ)/2 diagonally dominant with nonnegative diagonal (Gershgorin)")

    # a symmetric part with nonpositive off-diagonal: |x|ᵀH|x| ≤ xᵀHx, so copositivity of
    # H is equivalent to positive semidefiniteness (strict: definiteness)
    hoff_mat = _offdiag(H)
    hoff_max = (hoff_mat.data.max() if hoff_mat.nnz else 0.0) if sp.issparse(hoff_mat) else hoff_mat.max()
    if hoff_max <= tol:
        for name, src in (("copositive", "psd"), ("strictly_copositive", "positive_definite")):
            if st.get(src) is not None:
                st.decide(name, st.get(src), f"(M+Mᵀ)/2 has off-diagonal ≤ 0, so {LABELS[name]} "
                          f"⇔ {LABELS[src]}")

    # the full determinant (dense, moderate n): a nonpositive one refutes P, a negative one P0
    if A is not None and n <= det_limit and (st.get("p_matrix") is None or st.get("p0") is None):
        smin = np.linalg.svd(A, compute_uv=False)[-1]
        sign, logdet = np.linalg.slogdet(A)
        if smin <= tol:
            st.decide("p_matrix", False, f"M is singular (smallest singular value {smin * s:.3g})")
        elif sign < 0:
            st.decide("p_matrix", False, "det M < 0")
            st.decide("p0", False, "det M < 0")

    # Z-matrices: the M-matrix test decides P (and with it Q) at any size
    if st.get("z_matrix") and st.get("p_matrix") is None:
        ok, test, _ = _mmatrix_test(A if A is not None else (M / s).tocsr(), tol)
        if ok is not None:
            st.decide("m_matrix", ok, test)


def _sparse_ldl_test(Hs, tol: float, st: _State) -> None:
    """Definiteness of a large sparse symmetric H by Gaussian elimination without pivoting
    in a symmetric fill-reducing order: with P H Pᵀ = L U and no row interchanges, the
    leading principal minors of P H Pᵀ are products of U's pivots, so all pivots > 0
    ⇔ H positive definite (Sylvester).  If SuperLU did interchange rows, nothing is decided."""
    try:
        lu = spla.splu(Hs.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                       options={"SymmetricMode": True})
    except RuntimeError:
        return
    if not np.array_equal(lu.perm_r, lu.perm_c):
        return
    piv = lu.U.diagonal()  # in elimination order
    if np.all(piv > 0):
        st.decide("positive_definite", True, "sparse LDLᵀ of (M+Mᵀ)/2 (symmetric order, no pivoting): "
                  "all pivots > 0")
        return
    if not np.all(np.isfinite(piv)):
        return
    k = int(np.argmax(piv <= 0))  # the first nonpositive pivot; all before it are positive
    st.decide("positive_definite", False, f"sparse LDLᵀ of (M+Mᵀ)/2: pivot {k} is {piv[k]:.3g} ≤ 0, "
              "so a leading principal minor of the reordered matrix is ≤ 0")
    if piv[k] < -tol and piv[:k].min(initial=np.inf) > tol:
        st.decide("psd", False, f"sparse LDLᵀ of (M+Mᵀ)/2: first nonpositive pivot {piv[k]:.3g} < 0, "
                  "so a leading principal minor of the reordered matrix is < 0")
