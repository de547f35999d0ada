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
    LP at a time — too slow already for a rank-one 12×12 matrix — but settled together
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

Layout: this module holds :func:`classify` and the implications between classes; the result
class, its labels and the guarantees are in :mod:`meicp.lcp.classes_report`, the exact tests
in :mod:`meicp.lcp.classes_exact`, the sufficient ones in :mod:`meicp.lcp.classes_sufficient`.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from ..core.validation import as_int, as_matrix, check_tol, checked_keywords, scale, symmetry_error
from .classes_exact import _EXACT, _exact_tests, _r0_witness_ok
from .classes_report import CLASS_NAMES, LABELS, MatrixClasses, _guarantees, _State
from .classes_sufficient import _offdiag, _sufficient_tests
from .game import game_value

#: largest exact_limit accepted: the exact tests visit 2^n − 1 principal submatrices, their
#: time doubling per n; beyond this a call would run for far longer than anyone waits
#: (docs/benchmarks-notes.md, lcp)
MAX_EXACT_LIMIT = 20

#: largest dense_limit accepted: a dense copy of order 20000 is 3.2 GB
MAX_DENSE_LIMIT = 20000


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
# The entry point
# ----------------------------------------------------------------------------------------

@checked_keywords()
def classify(M, *, exact_limit: int = 12, tol: float = 1e-10, dense_limit: int = 2000,
             det_limit: int = 500, game_limit: int = 1000) -> MatrixClasses:
    """Classify the square matrix ``M`` (dense or SciPy sparse) for LCP theory.

    exact_limit: run the exponential all-subset tests when ``n ≤ exact_limit`` (fast at the
        default, docs/benchmarks-notes.md); above it only sufficient tests, undecided
        → None.
    tol: relative tolerance (to ``max|M|``) below which a quantity is treated as zero.
    dense_limit: sparse input is densified only up to this size; above it only
        sparse-friendly tests run (sign patterns, diagonal dominance, sparse LDLᵀ).
    det_limit: the full determinant/singular values of M are used up to this size.
    game_limit: the game value LP is solved up to this size (else ``game_value`` is None);
        its sparse LP is slow well before n = 3000 (docs/benchmarks-notes.md).

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
