"""Which LCP matrix classes a square matrix belongs to, and what that guarantees.

Seed 002 §3–§7 (docs/design.md §3): before solving ``LCP(q, M)`` — find ``x ≥ 0`` with
``w = Mx + q ≥ 0`` and ``xᵀw = 0`` — classify ``M``; the classes say whether a solution
exists for every load (Q), is unique for every load (P), whether the unloaded problem has
spurious nonzero solutions (not R0), and so on.  :func:`classify` answers each class with
True, False or None (undecided) and records the test that decided it.

Two regimes:

- ``n ≤ exact_limit``: exact finite tests over all ``2ⁿ − 1`` principal submatrices,
  done in batches by subset size with stacked NumPy linear algebra (≈ 4095 small matrices
  for n = 12, well under a second):

  * P / P0 — the sign of every principal minor.  A minor counts as zero when its
    submatrix is numerically singular (smallest singular value ≤ ``tol·max|M|``), not
    when the determinant is small: determinants of well-conditioned matrices can be tiny.
  * R0 — ``LCP(0, M)`` has a nonzero solution iff some support ``S`` carries
    ``x_S ≥ 0, 1ᵀx_S = 1, M_SS x_S = 0, M_{S̄S} x_S ≥ 0``.  Taking ``S`` as the exact
    support of a solution, ``M_SS`` is singular, so only singular principal submatrices
    are examined: a one-dimensional null space is checked for a sign-definite vector
    directly.  Larger null spaces (rank-deficient or structured M) are not enumerated one
    LP at a time — that took seconds for a rank-one 12×12 matrix — but settled together
    by one small mixed-integer feasibility problem (HiGHS) with the support as binaries.
  * semimonotone (E0) — violated iff some ``x ≥ 0, x ≠ 0`` has ``(Mx)_i < 0`` on its
    support.  A *minimal* violating support ``S`` has ``M_SS`` nonsingular and
    ``x_S = −M_SS⁻¹·1 > 0`` (a vertex argument on ``{x_S ≥ 0 : M_SS x_S ≤ −1}``), so one
    batched linear solve per subset replaces one LP per subset.
  * copositive / strictly copositive — Kaplan's criterion (LAA 313, 2000) on the
    symmetric part ``H = (M + Mᵀ)/2``, which has the same quadratic form: H is
    copositive iff no principal submatrix has an eigenvector ``v > 0`` with eigenvalue
    ``< 0`` (strictly: ``≤ 0``).

- ``n > exact_limit``: only sufficient tests, each of which proves its conclusion
  (diagonal signs, 2×2 principal minors and 2×2 copositivity, strict diagonal dominance,
  Gershgorin, eigenvalues or Cholesky of ``H``, the M-matrix test ``x = M⁻¹1 > 0`` for
  Z-matrices, nonnegativity, a zero diagonal entry over a nonnegative column, the game's
  optimal y* when v(M) = 0 as a nonzero solution of LCP(0, M)), plus the implications
  between classes.  Anything they do not settle stays None, never a guess.

Every False that comes from a search carries a witness (a subset or a vector) in
``tests`` / ``witnesses``, checked against the definition before it is reported.

Q-matrices have no exact test here.  Q is decided only by theorems: P ⇒ Q, strictly
copositive ⇒ Q, E0 ∩ R0 ⊆ Q (Karamardian's theorem: LCP(0, M) and LCP(e, M) both have only x = 0),
for Z-matrices Q ⇔ P; and refuted only by ``v(M) ≤ 0`` (Q ⊆ S).  Other refutations
found in the literature were left out until checked against their sources; where no
rule applies, Q stays None.

Tolerance: ``tol`` is relative to ``max|M|``; a quantity within ``tol·max|M|`` of zero is
treated as zero (a singular value, an eigenvalue, a residual).  Matrices on a class
boundary (singular PSD, zero minors) are classified with that convention.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from itertools import combinations, islice
import time
import warnings

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.optimize import Bounds, LinearConstraint, milp

from ..core.validation import as_int, as_matrix, check_tol, scale, symmetry_error
from .game import GameValue, game_value

#: largest exact_limit accepted: the exact tests visit 2^n − 1 principal submatrices
#: (n = 12 well under a second, doubling per n: n = 20 takes minutes)
MAX_EXACT_LIMIT = 20

#: largest dense_limit accepted: a dense copy of order 20000 is 3.2 GB
MAX_DENSE_LIMIT = 20000

#: the class attributes, in report order
CLASS_NAMES = (
    "symmetric", "spd", "psd", "positive_definite", "p_matrix", "p0", "z_matrix", "m_matrix",
    "q_matrix", "r0", "copositive", "strictly_copositive", "semimonotone",
)

#: short human names for the report
LABELS = {
    "symmetric": "symmetric",
    "spd": "SPD",
    "psd": "PSD (xᵀMx ≥ 0)",
    "positive_definite": "PD (xᵀMx > 0)",
    "p_matrix": "P",
    "p0": "P0",
    "z_matrix": "Z",
    "m_matrix": "M-matrix",
    "q_matrix": "Q",
    "r0": "R0",
    "copositive": "copositive",
    "strictly_copositive": "strictly copositive",
    "semimonotone": "semimonotone (E0)",
}

#: classes decided by an exponential exact test when n ≤ exact_limit
_EXACT = ("p_matrix", "p0", "r0", "copositive", "strictly_copositive", "semimonotone")


@dataclass
class MatrixClasses:
    """Class membership of a square matrix M: each attribute is True, False or None.

    symmetric: M = Mᵀ (to ``tol``).
    spd: symmetric and positive definite.
    psd: xᵀMx ≥ 0 for all x — M need *not* be symmetric (the monotone LCP); the
        symmetric part ``(M + Mᵀ)/2`` is positive semidefinite.
    positive_definite: xᵀMx > 0 for all x ≠ 0, M not necessarily symmetric.
    p_matrix / p0: every principal minor > 0 / ≥ 0.
    z_matrix: off-diagonal entries ≤ 0.   m_matrix: Z and P (nonsingular M-matrix).
    q_matrix: LCP(q, M) has a solution for every q.
    r0: LCP(0, M) has only the solution x = 0.
    copositive / strictly_copositive: xᵀMx ≥ 0 / > 0 for all x ≥ 0, x ≠ 0.
    semimonotone: E0 — every x ≥ 0, x ≠ 0 has some i with x_i > 0 and (Mx)_i ≥ 0.

    tests: for each class, the test (or implication) that decided it, or why not.
    witnesses: vectors that refute a class (JSON-friendly lists), e.g. ``r0`` → a
        nonzero solution of LCP(0, M); ``copositive`` → x ≥ 0 with xᵀMx < 0.
    game_value: :class:`~meicp.lcp.game.GameValue` (None if n > ``game_limit``).
    guarantees: sentences on what the classes guarantee for LCP(q, M), and what they
        do not (seed 002 §7).
    """

    n: int
    symmetric: bool | None = None
    spd: bool | None = None
    psd: bool | None = None
    positive_definite: bool | None = None
    p_matrix: bool | None = None
    p0: bool | None = None
    z_matrix: bool | None = None
    m_matrix: bool | None = None
    q_matrix: bool | None = None
    r0: bool | None = None
    copositive: bool | None = None
    strictly_copositive: bool | None = None
    semimonotone: bool | None = None
    tests: dict = field(default_factory=dict)
    witnesses: dict = field(default_factory=dict)
    game_value: GameValue | None = None
    guarantees: list = field(default_factory=list)
    exact_limit: int = 12
    tol: float = 1e-10
    scale: float = 1.0
    notes: list = field(default_factory=list)
    timings: dict = field(default_factory=dict)

    def classes(self) -> dict:
        """``{name: True/False/None}`` for every class."""
        return {name: getattr(self, name) for name in CLASS_NAMES}

    def report(self) -> str:
        """A readable multi-line report: one line per class, the game value, the guarantees."""
        exact = "exact tests" if self.n <= self.exact_limit else "sufficient tests only"
        lines = [f"Matrix classes of a {self.n}×{self.n} matrix "
                 f"({exact}; exact_limit = {self.exact_limit}, tol = {self.tol:g})"]
        word = {True: "yes", False: "no", None: "undecided"}
        for name in CLASS_NAMES:
            lines.append(f"  {LABELS[name]:<22} {word[getattr(self, name)]:<10} "
                         f"{self.tests.get(name, '')}")
        gv = self.game_value
        if gv is None:
            lines.append("  game value v(M)       not computed (n above game_limit)")
        elif gv.success:
            lines.append(f"  game value v(M)        {gv.value:.6g}  (duality gap {gv.residual:.1e}·max|M|)")
            if self.n <= 8:
                lines.append(f"    x* (min player) = {_fmt_vec(gv.x)}, y* (max player) = {_fmt_vec(gv.y)}")
        else:
            lines.append(f"  game value v(M)        not certified: {gv.message}")
        lines.append("Guarantees for LCP(q, M) (seed 002 §7):")
        lines.extend(f"  - {g}" for g in self.guarantees)
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """A JSON-serialisable dictionary (classes, tests, witnesses, game value, guarantees)."""
        return {
            "n": self.n,
            "classes": self.classes(),
            "tests": dict(self.tests),
            "witnesses": {k: list(v) for k, v in self.witnesses.items()},
            "game_value": None if self.game_value is None else self.game_value.to_dict(),
            "guarantees": list(self.guarantees),
            "exact_limit": self.exact_limit,
            "tol": self.tol,
            "scale": self.scale,
            "notes": list(self.notes),
            "timings": dict(self.timings),
        }

    def __str__(self) -> str:
        return self.report()


def _fmt_vec(v) -> str:
    return "(" + ", ".join(f"{t:.4g}" for t in v) + ")"


def _fmt_set(idx) -> str:
    return "{" + ",".join(str(int(i)) for i in idx) + "}"


class _State:
    """The classification being built: a class is set once, by the first test that decides it."""

    def __init__(self, out: MatrixClasses):
        self.out = out
        self.notes: list[str] = []

    def get(self, name):
        return getattr(self.out, name)

    def decide(self, name: str, value: bool, test: str, witness=None) -> bool:
        current = getattr(self.out, name)
        if current is None:
            setattr(self.out, name, bool(value))
            self.out.tests[name] = test
            if witness is not None:
                self.out.witnesses[name] = [float(t) for t in np.asarray(witness).ravel()]
            return True
        if current != bool(value):  # only at numerical class boundaries
            self.notes.append(f"{name}: kept {current} ({self.out.tests[name]}); "
                              f"a second test said {bool(value)} ({test})")
        return False


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


# ----------------------------------------------------------------------------------------
# Implications between classes
# ----------------------------------------------------------------------------------------

#: (premises, conclusion, value, reason): applied until nothing changes
_RULES = [
    ({"spd": True}, "symmetric", True, "SPD"),
    ({"spd": True}, "positive_definite", True, "SPD"),
    ({"symmetric": False}, "spd", False, "not symmetric"),
    ({"positive_definite": False}, "spd", False, "not positive definite"),
    ({"symmetric": True, "positive_definite": True}, "spd", True, "symmetric and xᵀMx > 0"),
    ({"positive_definite": True}, "psd", True, "positive definite ⇒ PSD"),
    ({"positive_definite": True}, "p_matrix", True, "xᵀMx > 0 for x ≠ 0 ⇒ P (seed 002 (13))"),
    ({"positive_definite": True}, "strictly_copositive", True, "positive definite ⇒ strictly copositive"),
    ({"psd": False}, "positive_definite", False, "not PSD"),
    ({"psd": True}, "p0", True, "PSD ⇒ P0"),
    ({"psd": True}, "copositive", True, "PSD ⇒ copositive"),
    ({"p_matrix": True}, "p0", True, "P ⇒ P0"),
    ({"p_matrix": True}, "r0", True, "P ⇒ R0"),
    ({"p_matrix": True}, "q_matrix", True, "P ⇒ Q (seed 002 (16))"),
    ({"p_matrix": False}, "positive_definite", False, "not P"),
    ({"p_matrix": False}, "m_matrix", False, "not P"),
    ({"p0": True}, "semimonotone", True, "P0 ⇒ E0"),
    ({"p0": False}, "p_matrix", False, "not P0"),
    ({"p0": False}, "psd", False, "not P0"),
    ({"strictly_copositive": True}, "copositive", True, "strictly copositive"),
    ({"strictly_copositive": True}, "r0", True, "strictly copositive ⇒ R0 (xᵀMx > 0 on x ≥ 0, x ≠ 0)"),
    ({"strictly_copositive": True}, "q_matrix", True, "strictly copositive ⇒ Q"),
    ({"strictly_copositive": False}, "positive_definite", False, "not strictly copositive"),
    ({"copositive": True}, "semimonotone", True, "copositive ⇒ E0"),
    ({"copositive": False}, "strictly_copositive", False, "not copositive"),
    ({"copositive": False}, "psd", False, "not copositive"),
    ({"semimonotone": False}, "copositive", False, "not E0"),
    ({"semimonotone": False}, "p0", False, "not E0"),
    ({"r0": False}, "p_matrix", False, "not R0"),
    ({"r0": False}, "strictly_copositive", False, "not R0"),
    ({"q_matrix": False}, "p_matrix", False, "not Q"),
    ({"q_matrix": False}, "strictly_copositive", False, "not Q"),
    ({"z_matrix": False}, "m_matrix", False, "not Z"),
    ({"m_matrix": True}, "z_matrix", True, "M-matrix"),
    ({"m_matrix": True}, "p_matrix", True, "M-matrix (Z and P)"),
    ({"z_matrix": True, "p_matrix": True}, "m_matrix", True, "Z and P"),
    ({"z_matrix": True, "m_matrix": False}, "p_matrix", False, "Z but not an M-matrix"),
    ({"z_matrix": True, "p_matrix": True}, "q_matrix", True, "P ⇒ Q"),
    ({"z_matrix": True, "p_matrix": False}, "q_matrix", False,
     "Z and not P: for Z-matrices Q ⇔ P (Q ⊆ S and Z ∩ S = Z ∩ P, Fiedler–Pták)"),
    ({"semimonotone": True, "r0": True}, "q_matrix", True, "E0 and R0 ⇒ Q (Karamardian)"),
    ({"symmetric": True, "semimonotone": True}, "copositive", True,
     "symmetric and E0 ⇒ copositive (KKT point of xᵀMx on the simplex)"),
]


def _propagate(st: _State, n: int) -> None:
    rules = _RULES
    changed = True
    while changed:
        changed = False
        for premises, name, value, reason in rules:
            if st.get(name) is None and all(st.get(k) == v for k, v in premises.items()):
                changed |= st.decide(name, value, reason)


# ----------------------------------------------------------------------------------------
# Guarantees (seed 002 §7)
# ----------------------------------------------------------------------------------------

def _guarantees(c: MatrixClasses) -> list[str]:
    g = []
    gv = c.game_value
    tol = c.tol
    if c.q_matrix:
        g.append(f"Existence: LCP(q, M) has a solution for every load q (Q-matrix: {c.tests['q_matrix']}).")
    elif c.q_matrix is False:
        g.append(f"NOT guaranteed: existence fails for some load q — M is not a Q-matrix "
                 f"({c.tests['q_matrix']}).")
    else:
        g.append("NOT guaranteed: existence for every q (Q undecided); check each solve's certificate.")
    if c.p_matrix:
        g.append("Uniqueness: for every q the solution is unique (P-matrix), and x(q) depends "
                 "Lipschitz-continuously on q.")
    elif c.p_matrix is False:
        g.append("NOT guaranteed: uniqueness — M is not P, and P is necessary for a unique solution "
                 "for every q, so some q has no solution or several.")
    else:
        g.append("NOT guaranteed: uniqueness for every q (P undecided).")
    if c.r0:
        g.append("No spurious unloaded equilibria: with q = 0 the only solution is x = 0 (R0).")
    elif c.r0 is False:
        g.append("Spurious unloaded equilibria exist: LCP(0, M) has a nonzero solution (not R0), "
                 "and every positive multiple of it is one too.")
    else:
        g.append("NOT guaranteed: absence of nonzero unloaded equilibria (R0 undecided).")
    if gv is not None and gv.success:
        if gv.lower > tol * c.scale:
            g.append(f"Game value v(M) = {gv.value:.6g} > 0: y* gives My* > 0, so LCP(q, M) is "
                     "feasible for every q and the energetic margin of seed 002 §4 holds.")
        elif gv.upper <= tol * c.scale:
            g.append(f"Game value v(M) = {gv.value:.6g} ≤ 0 (to tolerance): no y ≥ 0 has My > 0, so "
                     "for every q < 0 (e.g. q = −1) LCP(q, M) has no feasible point; no energetic margin.")
        else:
            g.append(f"Game value v(M) = {gv.value:.6g} is zero to tolerance: no certified "
                     "energetic margin (seed 002 (19)).")
    elif gv is not None:
        g.append("Game value not certified: the energetic margin v(M) > 0 is not established.")
    else:
        g.append("Game value not computed (n above game_limit): the energetic margin is not established.")
    if c.spd:
        g.append("SPD: LCP(q, M) is the optimality condition of the strictly convex energy "
                 "min ½xᵀMx + qᵀx over x ≥ 0, whose minimiser is the unique solution.")
    elif c.psd and not c.p_matrix:
        g.append("PSD (monotone LCP): the solution set is convex and LCP(q, M) is solvable "
                 "whenever it is feasible (Lemke's method finds a solution or proves infeasibility).")
    if c.m_matrix:
        g.append("M-matrix: the solution is the least element of the feasible set "
                 "{x ≥ 0 : Mx + q ≥ 0}, and contact couplings are purely compressive (Z).")
    if c.semimonotone:
        g.append("E0: for every q > 0 (all contacts pushed open) the only solution is x = 0.")
    elif c.semimonotone is False:
        g.append("Not E0: some q > 0 (all contacts pushed open) still has a nonzero solution.")
    if c.strictly_copositive:
        g.append("Strictly copositive: xᵀMx > 0 for every nonzero x ≥ 0 — this alone implies "
                 "Q, R0 and v(M) > 0 (seed 002 (20)).")
    return g


# ----------------------------------------------------------------------------------------
# The entry point
# ----------------------------------------------------------------------------------------

def classify(M, *, exact_limit: int = 12, tol: float = 1e-10, dense_limit: int = 2000,
             det_limit: int = 500, game_limit: int = 1000) -> MatrixClasses:
    """Classify the square matrix ``M`` (dense or SciPy sparse) for LCP theory.

    exact_limit: run the exponential all-subset tests when ``n ≤ exact_limit`` (n = 12
        takes well under a second); above it only sufficient tests, undecided → None.
    tol: relative tolerance (to ``max|M|``) below which a quantity is treated as zero.
    dense_limit: sparse input is densified only up to this size; above it only
        sparse-friendly tests run (sign patterns, diagonal dominance, sparse LDLᵀ).
    det_limit: the full determinant/singular values of M are used up to this size.
    game_limit: the game value LP is solved up to this size (else ``game_value`` is None);
        a sparse LP with n = 3000 already takes seconds.

    Raises :class:`~meicp.core.errors.ProblemError` for non-square, empty, complex or
    non-finite M, for tol outside (0, 1e-2], for an ``exact_limit`` above
    ``MAX_EXACT_LIMIT`` (2^n subsets: n = 24 takes hours), a ``dense_limit`` above
    ``MAX_DENSE_LIMIT`` (memory) or negative limits.
    """
    t0 = time.perf_counter()
    tol = check_tol(tol)
    exact_limit = as_int(exact_limit, "exact_limit", minimum=0, maximum=MAX_EXACT_LIMIT)
    dense_limit = as_int(dense_limit, "dense_limit", minimum=0, maximum=MAX_DENSE_LIMIT)
    det_limit = as_int(det_limit, "det_limit", minimum=0)
    game_limit = as_int(game_limit, "game_limit", minimum=0)
    M = as_matrix(M, "M")
    n = M.shape[0]
    s = scale(M)
    out = MatrixClasses(n=n, exact_limit=int(exact_limit), tol=float(tol), scale=s)
    st = _State(out)
    sparse = sp.issparse(M)
    A = None
    if not sparse:
        A = M / s
    elif n <= dense_limit:
        A = M.toarray() / s
    if A is not None:
        H = 0.5 * (A + A.T)
        Hs = None
    else:
        Hs = ((M + M.T) * (0.5 / s)).tocsr()
        H = Hs

    err = symmetry_error(M)
    st.decide("symmetric", err <= tol, f"max|M − Mᵀ| = {err * s:.3g}")
    off = _offdiag(M)
    off_max = (off.data.max() if off.nnz else 0.0) if sp.issparse(off) else (off.max() if n > 1 else 0.0)
    if off_max <= tol * s:
        st.decide("z_matrix", True, "all off-diagonal entries ≤ 0")
    else:
        if sp.issparse(off):
            k = int(np.argmax(off.data))
            coo = off.tocoo()
            i, j = int(coo.row[k]), int(coo.col[k])
        else:
            i, j = np.unravel_index(int(np.argmax(off)), off.shape)
        st.decide("z_matrix", False, f"off-diagonal entry M[{i},{j}] = {off_max:.3g} > 0")
    out.timings["signs"] = time.perf_counter() - t0

    if n <= exact_limit and A is not None:
        t1 = time.perf_counter()
        _exact_tests(A, H, tol, st)
        out.timings["exact"] = time.perf_counter() - t1

    t1 = time.perf_counter()
    _sufficient_tests(M, A, H, Hs, s, tol, st, dense_limit, det_limit)
    out.timings["sufficient"] = time.perf_counter() - t1

    _propagate(st, n)
    if n <= game_limit:
        t1 = time.perf_counter()
        gv = game_value(M)
        out.game_value = gv
        out.timings["game"] = time.perf_counter() - t1
        # Q ⊆ S: a row strategy with Mᵀx ≤ 0 (to tol) refutes Q — asked only after the
        # theorems have had their say, so a tiny positive v(M) never overrides "P ⇒ Q"
        if gv.success and gv.upper <= tol * s:
            st.decide("q_matrix", False, f"v(M) = {gv.value:.3g} ≤ 0 (to tol): x* ∈ Δ has Mᵀx* ≤ 0, so no "
                      "y ≥ 0 has My > 0 and LCP(q, M) is infeasible for q < 0", witness=gv.x)
            # when v(M) = 0, My* ≥ 0 and y* may be complementary to it: a free R0 witness
            if st.get("r0") is None and _r0_witness_ok(A if A is not None else M / s, gv.y, tol):
                st.decide("r0", False, "the column player's optimal strategy y* solves LCP(0, M) "
                          "(My* ≥ 0, y*ᵀMy* = 0)", witness=gv.y)
            _propagate(st, n)
    for name in CLASS_NAMES:
        if getattr(out, name) is None:
            if name == "q_matrix":
                necessary = ("no necessary one fails (v(M) > 0)" if out.game_value is not None else
                             f"the game value (a necessary condition) was not computed (n > game_limit={game_limit})")
                out.tests[name] = ("undecided: no sufficient condition for Q holds (P, strictly "
                                   f"copositive, E0 ∩ R0, Z-matrix rule) and {necessary}")
            elif name in _EXACT or n > exact_limit:
                out.tests[name] = (f"undecided: n={n} > exact_limit={exact_limit} and no "
                                   "sufficient test applies")
            else:
                out.tests[name] = "undecided: no test applies"
    out.notes = st.notes
    out.guarantees = _guarantees(out)
    out.timings["total"] = time.perf_counter() - t0
    return out


__all__ = ["MatrixClasses", "classify", "CLASS_NAMES", "LABELS"]
