"""Matrix classes (meicp.lcp.classes) and the game value (meicp.lcp.game).

Every class claim below was checked by hand or by the brute-force oracles at the top of
this file, which are deliberately computed differently from the library:
principal minors by ``itertools`` + ``np.linalg.det``, R0 and E0 by one LP per support,
copositivity by enumerating the KKT points of ``min xᵀHx`` on the simplex, the game value
by enumerating the vertices of the row player's LP, and LCP solutions by enumerating all
complementary bases.
"""

import json
from itertools import combinations

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import HealthCheck, given, settings, strategies as st
from hypothesis.extra.numpy import arrays
from scipy.optimize import linprog

from meicp.core.errors import ProblemError
from meicp.lcp.classes import CLASS_NAMES, MatrixClasses, classify
from meicp.lcp.game import GameValue, game_value

# ------------------------------------------------------------------------------------------
# brute-force oracles (small n only)
# ------------------------------------------------------------------------------------------


def subsets(n):
    for k in range(1, n + 1):
        yield from (list(S) for S in combinations(range(n), k))


def minors(M):
    """Principal minors, rounded: the test matrices are integer."""
    return [round(float(np.linalg.det(M[np.ix_(S, S)])), 6) for S in subsets(len(M))]


def r0_oracle(M):
    """True iff LCP(0, M) has only x = 0: one LP per support S (x_S ≥ 0, 1ᵀx_S = 1,
    M_SS x_S = 0, M_{S̄S} x_S ≥ 0)."""
    n = len(M)
    for S in subsets(n):
        R = [i for i in range(n) if i not in S]
        A_eq = np.vstack([M[np.ix_(S, S)], np.ones((1, len(S)))])
        b_eq = np.concatenate([np.zeros(len(S)), [1.0]])
        A_ub = -M[np.ix_(R, S)] if R else None
        b_ub = np.zeros(len(R)) if R else None
        res = linprog(np.zeros(len(S)), A_ub=A_ub, b_ub=b_ub, A_eq=A_eq, b_eq=b_eq,
                      bounds=[(0, None)] * len(S), method="highs")
        if res.status == 0:
            return False
    return True


def e0_oracle(M):
    """True iff M is semimonotone: for no S is min_{x∈Δ_S} max_i (M_SS x)_i < 0 (one LP each)."""
    for S in subsets(len(M)):
        k = len(S)
        A_ub = np.hstack([M[np.ix_(S, S)], -np.ones((k, 1))])
        res = linprog(np.r_[np.zeros(k), 1.0], A_ub=A_ub, b_ub=np.zeros(k),
                      A_eq=np.r_[np.ones(k), 0.0][None, :], b_eq=[1.0],
                      bounds=[(0, None)] * k + [(None, None)], method="highs")
        if res.fun < -1e-9:
            return False
    return True


def simplex_min_quadratic(H):
    """min xᵀHx over the simplex, by enumerating the stationary points of every face
    (the minimum is attained at one whose bordered KKT system is nonsingular)."""
    best = np.inf
    for S in subsets(len(H)):
        k = len(S)
        K = np.block([[2 * H[np.ix_(S, S)], np.ones((k, 1))], [np.ones((1, k)), np.zeros((1, 1))]])
        if abs(np.linalg.det(K)) < 1e-12:
            continue
        x = np.linalg.solve(K, np.r_[np.zeros(k), 1.0])[:k]
        if x.min() >= -1e-12:
            best = min(best, float(x @ H[np.ix_(S, S)] @ x))
    return best


def game_oracle(A):
    """v(A) = min_x max_y xᵀAy by enumerating the vertices of the row player's LP
    {(x, t): Aᵀx ≤ t·1, x ∈ Δ}: support I of x, |I| tight columns J."""
    m, n = A.shape
    best = np.inf
    for k in range(1, min(m, n) + 1):
        for I in combinations(range(m), k):
            for J in combinations(range(n), k):
                K = np.zeros((k + 1, k + 1))
                K[:k, :k] = A[np.ix_(I, J)].T
                K[:k, k] = -1.0
                K[k, :k] = 1.0
                if abs(np.linalg.det(K)) < 1e-12:
                    continue
                z = np.linalg.solve(K, np.r_[np.zeros(k), 1.0])
                x = np.zeros(m)
                x[list(I)] = z[:k]
                if x.min() >= -1e-12 and np.max(A.T @ x) <= z[k] + 1e-9:
                    best = min(best, z[k])
    return best


def lcp_solutions(M, q):
    """All solutions of LCP(q, M) for a generic q, one per complementary basis."""
    n = len(q)
    sols = []
    for k in range(0, n + 1):
        for S in combinations(range(n), k):
            S = list(S)
            x = np.zeros(n)
            if S:
                B = M[np.ix_(S, S)]
                if abs(np.linalg.det(B)) < 1e-12:
                    continue
                x[S] = np.linalg.solve(B, -q[S])
            w = M @ x + q
            if x.min() >= -1e-10 and w.min() >= -1e-10:
                sols.append(x)
    return sols


def classes_of(c):
    return {name: getattr(c, name) for name in CLASS_NAMES}


def assert_classes(c, **expected):
    got = {k: getattr(c, k) for k in expected}
    assert got == expected, "\n" + c.report()


TRIDIAG = np.array([[2.0, -1, 0], [-1, 2, -1], [0, -1, 2]])
HORN = np.array([[1, -1, 1, 1, -1],
                 [-1, 1, -1, 1, 1],
                 [1, -1, 1, -1, 1],
                 [1, 1, -1, 1, -1],
                 [-1, 1, 1, -1, 1]], dtype=float)

# ------------------------------------------------------------------------------------------
# the game value
# ------------------------------------------------------------------------------------------


def test_game_value_seed_002_two_point_example():
    g = game_value([[2, -1], [-1, 2]])
    assert isinstance(g, GameValue) and g.success
    assert g.value == pytest.approx(0.5, abs=1e-12)
    np.testing.assert_allclose(g.x, [0.5, 0.5], atol=1e-12)
    np.testing.assert_allclose(g.y, [0.5, 0.5], atol=1e-12)
    assert g.residual <= 1e-9


def test_game_value_tridiagonal_erratum():
    """docs/design.md §12: v = 1/5 at x* = y* = (0.3, 0.4, 0.3), not the seed's 1/3."""
    g = game_value(TRIDIAG)
    assert g.success and g.residual <= 1e-9
    assert g.value == pytest.approx(0.2, abs=1e-12)
    np.testing.assert_allclose(g.x, [0.3, 0.4, 0.3], atol=1e-10)
    np.testing.assert_allclose(g.y, [0.3, 0.4, 0.3], atol=1e-10)
    # the seed's uniform strategy: A·(1/3,1/3,1/3) = (1/3, 0, 1/3), so it only guarantees 0
    np.testing.assert_allclose(TRIDIAG @ np.full(3, 1 / 3), [1 / 3, 0, 1 / 3])
    # both certificates: x* concedes at most 1/5 to every column, y* gets 1/5 from every row
    np.testing.assert_allclose(TRIDIAG.T @ g.x, 0.2, atol=1e-10)
    np.testing.assert_allclose(TRIDIAG @ g.y, 0.2, atol=1e-10)


def test_game_value_identity_rectangular_sparse_and_scale():
    assert game_value(np.eye(4)).value == pytest.approx(0.25)
    g = game_value(np.array([[3.0, -1, 0], [0, 2, 1]]))  # rectangular: x ∈ Δ₂, y ∈ Δ₃
    assert g.success and g.x.shape == (2,) and g.y.shape == (3,)
    assert g.value == pytest.approx(game_oracle(np.array([[3.0, -1, 0], [0, 2, 1]])))
    gs = game_value(sp.csr_matrix(TRIDIAG) * 1e6)
    assert gs.success and gs.value == pytest.approx(2e5, rel=1e-10)
    d = gs.to_dict()
    json.dumps(d)
    assert d["value"] == pytest.approx(2e5)


def test_game_value_bad_input():
    for bad in (np.array([[1.0, np.nan], [0, 1]]), np.zeros((0, 0)), np.ones(3), [["a"]]):
        with pytest.raises(ProblemError):
            game_value(bad)


small_int = st.integers(1, 4).flatmap(
    lambda n: arrays(np.float64, (n, n), elements=st.integers(-3, 3).map(float)))


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(A=st.tuples(st.integers(1, 3), st.integers(1, 3)).flatmap(
    lambda s: arrays(np.float64, s, elements=st.floats(-5, 5, allow_nan=False, width=32))))
def test_game_value_against_vertex_enumeration_and_transpose(A):
    g = game_value(A)
    assert g.success and g.residual <= 1e-9
    tol = 1e-9 * max(1.0, np.abs(A).max())
    assert g.value == pytest.approx(game_oracle(A), abs=tol)
    # certificates: x ∈ Δ concedes ≤ v, y ∈ Δ earns ≥ v
    assert g.x.min() >= 0 and g.y.min() >= 0
    assert g.x.sum() == pytest.approx(1) and g.y.sum() == pytest.approx(1)
    assert np.max(A.T @ g.x) <= g.value + tol and np.min(A @ g.y) >= g.value - tol
    # v(A) = min_x max_y xᵀAy = max_y min_x xᵀAy = −min_y max_x yᵀ(−Aᵀ)x = −v(−Aᵀ),
    # and the roles of the strategies swap
    h = game_value(-A.T)
    assert h.value == pytest.approx(-g.value, abs=tol)
    assert np.min(A @ h.x) >= g.value - tol and np.max(A.T @ h.y) <= g.value + tol


# ------------------------------------------------------------------------------------------
# known matrices
# ------------------------------------------------------------------------------------------


def test_seed_002_examples():
    for M, v in (([[2, -1], [-1, 2]], 0.5), (TRIDIAG, 0.2)):
        c = classify(M)
        assert isinstance(c, MatrixClasses)
        assert all(val is True for val in classes_of(c).values()), c.report()
        assert c.game_value.value == pytest.approx(v)
        text = " ".join(c.guarantees)
        assert "every load q" in text and "unique" in text and "q = 0 the only solution" in text
        assert "v(M) = " in text and "> 0" in text
    c = classify(TRIDIAG)
    assert "all 7 principal minors > 0" in c.tests["p_matrix"]


def test_identity():
    c = classify(np.eye(5))
    assert all(v is True for v in classes_of(c).values())
    assert c.game_value.value == pytest.approx(0.2)


def test_psd_singular():
    c = classify([[1, -1], [-1, 1]])
    assert_classes(c, symmetric=True, spd=False, psd=True, positive_definite=False, p_matrix=False,
                   p0=True, z_matrix=True, m_matrix=False, q_matrix=False, r0=False, copositive=True,
                   strictly_copositive=False, semimonotone=True)
    np.testing.assert_allclose(c.witnesses["r0"], [0.5, 0.5])  # M(1,1) = 0
    assert c.game_value.value == pytest.approx(0.0, abs=1e-12)
    assert any("no feasible point" in g for g in c.guarantees)
    assert any("NOT guaranteed" in g and "Q-matrix" in g for g in c.guarantees)


def test_p_matrix_that_is_not_symmetric_nor_positive_definite():
    # minors 1, 1, det 1; (M+Mᵀ)/2 = [[1,-1.5],[-1.5,1]] is indefinite; x = (1,1): xᵀMx = −1
    c = classify([[1, -3], [0, 1]])
    assert_classes(c, symmetric=False, spd=False, psd=False, positive_definite=False, p_matrix=True,
                   p0=True, z_matrix=True, m_matrix=True, q_matrix=True, r0=True, copositive=False,
                   strictly_copositive=False, semimonotone=True)
    x = np.array(c.witnesses["copositive"])
    assert x.min() >= 0 and x @ np.array([[1, -3], [0, 1]]) @ x < 0
    # not Z either: minors 1, 1, 1+4 = 5; xᵀMx = x1² + 3x1x2 + x2² > 0 on x ≥ 0
    c = classify([[1, 4], [-1, 1]])
    assert_classes(c, p_matrix=True, z_matrix=False, m_matrix=False, psd=False,
                   strictly_copositive=True, q_matrix=True)


def test_p0_not_p():
    # minors 1, 0, det = 0 + 1 = 1; only singular support {1} has M e_1 = (−1, 0) ≱ 0 ⇒ R0;
    # P0 ⊆ E0 and E0 ∩ R0 ⊆ Q
    M = np.array([[1.0, -1], [1, 0]])
    c = classify(M)
    assert_classes(c, p_matrix=False, p0=True, r0=True, semimonotone=True, q_matrix=True)
    rng = np.random.default_rng(0)
    for _ in range(50):
        assert lcp_solutions(M, rng.standard_normal(2)), "Q-matrix: every q must have a solution"


def test_z_and_m_matrices():
    c = classify([[1, -2], [-2, 1]])  # Z, det −3
    assert_classes(c, z_matrix=True, p_matrix=False, m_matrix=False, q_matrix=False)
    assert "Z" in c.tests["q_matrix"] or "v(M)" in c.tests["q_matrix"]
    c = classify([[1, -0.5], [-3, 2]])  # Z, det 0.5 > 0, nonsymmetric
    assert_classes(c, z_matrix=True, p_matrix=True, m_matrix=True, symmetric=False, q_matrix=True)


def test_strictly_copositive_not_psd():
    c = classify([[1, 2], [2, 1]])  # eigenvalues 3, −1; nonnegative with positive diagonal
    assert_classes(c, psd=False, spd=False, strictly_copositive=True, copositive=True, q_matrix=True,
                   r0=True, p_matrix=False, p0=False, semimonotone=True)


def test_horn_matrix_copositive_not_psd():
    assert simplex_min_quadratic(HORN) == pytest.approx(0.0, abs=1e-12)  # oracle: copositive, not strictly
    assert np.linalg.eigvalsh(HORN)[0] < 0
    c = classify(HORN)
    assert_classes(c, symmetric=True, psd=False, copositive=True, strictly_copositive=False,
                   semimonotone=True)
    x = np.array(c.witnesses["strictly_copositive"])
    assert x.min() >= 0 and x @ HORN @ x == pytest.approx(0.0, abs=1e-12)


def test_r0_but_not_q():
    # LCP(0, [−1]) has only x = 0, but q < 0 has no solution
    c = classify([[-1.0]])
    assert_classes(c, r0=True, q_matrix=False, p_matrix=False, semimonotone=False)
    assert lcp_solutions(np.array([[-1.0]]), np.array([-1.0])) == []
    M = np.diag([-1.0, 1.0])
    c = classify(M)
    assert_classes(c, r0=True, q_matrix=False)
    assert lcp_solutions(M, np.array([-1.0, -0.5])) == []


def test_not_r0():
    M = np.array([[0.0, 1], [-1, 0]])  # x = (0, 1): w = Mx = (1, 0) ≥ 0, xᵀw = 0
    c = classify(M)
    assert_classes(c, r0=False, q_matrix=False, p_matrix=False, p0=True, psd=True, copositive=True,
                   strictly_copositive=False)
    x = np.array(c.witnesses["r0"])
    np.testing.assert_allclose(x, [0, 1])
    w = M @ x
    assert w.min() >= 0 and x @ w == 0
    assert lcp_solutions(M, np.array([-1.0, -1.0])) == []


def test_copositive_not_r0_q_stays_undecided():
    # [[0,1],[1,0]]: copositive (M ≥ 0), e_0 solves LCP(0, M); q = (−1, 1) has no solution.
    # No rule the classifier trusts refutes Q here (v(M) > 0), so it must say None, not guess.
    M = np.array([[0.0, 1], [1, 0]])
    c = classify(M)
    assert_classes(c, copositive=True, semimonotone=True, r0=False, q_matrix=None)
    assert c.game_value.value == pytest.approx(0.5)  # an S-matrix all the same
    assert lcp_solutions(M, np.array([-1.0, 1.0])) == []


def test_rank_one_matrix_uses_the_milp_path():
    rng = np.random.default_rng(1)
    u, v = rng.standard_normal(12), rng.uniform(0.5, 1.5, 12)
    c = classify(np.outer(u, v))  # Mx = u·(vᵀx) ≱ 0 for x ≥ 0, x ≠ 0 since u has both signs
    assert c.r0 is True and "MILP" in c.tests["r0"]
    c = classify(np.outer(np.r_[u[:6], -np.abs(u[6:])], np.r_[v[:6], -v[6:]]))
    assert c.r0 is False
    x = np.array(c.witnesses["r0"])
    M = np.outer(np.r_[u[:6], -np.abs(u[6:])], np.r_[v[:6], -v[6:]])
    assert x.min() >= 0 and (M @ x).min() >= -1e-9 and abs(x @ M @ x) <= 1e-9


def test_n12_exact_runs_every_exact_test():
    # speed (under a second) is measured by scripts/bench_classes.py, not asserted here
    M = np.diag(np.arange(1, 13.0)) - 0.1 * np.ones((12, 12))  # everything True: no early exit
    c = classify(M)
    assert all(v is True for v in classes_of(c).values())
    assert "all 4095 principal minors > 0" in c.tests["p_matrix"]


# ------------------------------------------------------------------------------------------
# above the exact limit: sufficient tests or None, never a guess
# ------------------------------------------------------------------------------------------


def test_above_limit_returns_none_not_a_guess():
    rng = np.random.default_rng(3)
    M = np.eye(20) + 0.3 * rng.standard_normal((20, 20))  # positive diagonal, no dominance
    M[np.diag_indices(20)] = np.abs(np.diag(M)) + 0.5
    c = classify(M)
    assert c.symmetric is False and c.z_matrix is False
    for name in ("r0", "q_matrix", "semimonotone"):
        assert getattr(c, name) is None, name
        assert c.tests[name].startswith("undecided")
    assert "n=20 > exact_limit=12" in c.tests["r0"]
    assert any("R0 undecided" in g for g in c.guarantees)
    # the same classes are decided when the exact tests are allowed
    d = classify(M[:12, :12])
    assert None not in (d.p_matrix, d.p0, d.r0, d.copositive, d.semimonotone)


def test_exact_limit_parameter_and_sufficient_tests():
    # P but not diagonally dominant, not Z, not PD: with exact_limit=2 P stays undecided
    M = np.array([[1.0, 3, 0], [-1, 1, 3], [0, -1, 1]])
    assert min(minors(M)) > 0
    assert classify(M).p_matrix is True
    c = classify(M, exact_limit=2)
    assert c.p_matrix is None and "exact_limit=2" in c.tests["p_matrix"]
    # SPD above the limit: eigenvalues decide, and the implications fill in the rest
    n = 30
    T = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    c = classify(T)
    assert_classes(c, spd=True, p_matrix=True, r0=True, q_matrix=True, strictly_copositive=True,
                   m_matrix=True, semimonotone=True)
    # a Z-matrix that is not an M-matrix, above the limit: x = M⁻¹1 has negative entries
    c = classify(T - 0.5 * np.eye(n))
    assert_classes(c, z_matrix=True, m_matrix=False, p_matrix=False, q_matrix=False)
    # nonnegative with positive diagonal ⇒ strictly copositive ⇒ Q, R0
    c = classify(np.abs(np.random.default_rng(0).standard_normal((25, 25))) + np.eye(25))
    assert_classes(c, strictly_copositive=True, q_matrix=True, r0=True, semimonotone=True)


def test_singular_laplacian_above_the_limit():
    rng = np.random.default_rng(0)
    W = np.abs(rng.standard_normal((30, 30)))
    W = W + W.T
    np.fill_diagonal(W, 0)
    L = np.diag(W.sum(axis=1)) - W  # L·1 = 0: PSD, singular, Z
    c = classify(L)
    assert_classes(c, psd=True, spd=False, z_matrix=True, p_matrix=False, m_matrix=False, q_matrix=False,
                   r0=False, copositive=True, strictly_copositive=False, p0=True, semimonotone=True)
    y = np.array(c.witnesses["r0"])  # the game's y* is uniform and solves LCP(0, L)
    np.testing.assert_allclose(y, np.full(30, 1 / 30), atol=1e-9)
    assert np.abs(L @ y).max() <= 1e-9 * np.abs(L).max()


def test_sparse_input_small_and_large():
    c_dense, c_sparse = classify(TRIDIAG), classify(sp.csr_matrix(TRIDIAG))
    assert classes_of(c_dense) == classes_of(c_sparse)
    n = 2500  # above dense_limit: never densified; game LP above game_limit is skipped
    T = sp.diags([-np.ones(n - 1), 2.0 * np.ones(n), -np.ones(n - 1)], [-1, 0, 1], format="csr")
    c = classify(T)
    assert_classes(c, symmetric=True, spd=True, z_matrix=True, m_matrix=True, p_matrix=True,
                   q_matrix=True, r0=True, copositive=True, strictly_copositive=True)
    assert "LDLᵀ" in c.tests["positive_definite"]
    assert c.game_value is None
    c = classify(sp.csr_matrix(-T))
    assert_classes(c, psd=False, p0=False, copositive=False, semimonotone=False, positive_definite=False)
    assert c.r0 is None


def test_bad_input_raises_problem_error():
    for bad in (np.ones((2, 3)), np.array([[1.0, np.nan], [0, 1]]), np.zeros((0, 0)), np.ones(3),
                sp.csr_matrix(np.ones((2, 3)))):
        with pytest.raises(ProblemError):
            classify(bad)


def test_report_and_to_dict():
    c = classify(TRIDIAG)
    text = c.report()
    assert "3×3" in text and "M-matrix" in text and "0.2" in text and "Guarantees" in text
    assert str(c) == text
    d = json.loads(json.dumps(c.to_dict()))
    assert d["classes"]["p_matrix"] is True and d["game_value"]["value"] == pytest.approx(0.2)
    assert set(d["classes"]) == set(CLASS_NAMES)
    c = classify([[0.0, 1], [-1, 0]])
    d = json.loads(json.dumps(c.to_dict()))
    assert d["classes"]["r0"] is False and d["witnesses"]["r0"] == [0.0, 1.0]


# ------------------------------------------------------------------------------------------
# exact tests against the brute-force oracles
# ------------------------------------------------------------------------------------------


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(M=small_int)
def test_exact_tests_match_oracles(M):
    c = classify(M)
    mins = minors(M)
    assert c.p_matrix == (min(mins) > 0)
    assert c.p0 == (min(mins) >= 0)
    assert c.r0 == r0_oracle(M)
    assert c.semimonotone == e0_oracle(M)
    H = 0.5 * (M + M.T)
    qmin = simplex_min_quadratic(H)
    assert c.copositive == (qmin >= -1e-9)
    assert c.strictly_copositive == (qmin > 1e-9)
    lam = np.linalg.eigvalsh(H)[0]
    assert c.psd == (lam >= -1e-9) and c.positive_definite == (lam > 1e-9)
    offdiag = M[~np.eye(len(M), dtype=bool)]
    assert c.z_matrix == bool(np.all(offdiag <= 0))
    assert c.m_matrix == (c.z_matrix and c.p_matrix)
    assert c.symmetric == bool(np.array_equal(M, M.T))
    if c.symmetric:  # symmetric semimonotone matrices are exactly the copositive ones
        assert c.semimonotone == c.copositive
    # witnesses satisfy their definitions
    if c.r0 is False:
        x = np.array(c.witnesses["r0"])
        assert x.min() >= 0 and x.sum() == pytest.approx(1)
        assert (M @ x).min() >= -1e-9 and abs(x @ M @ x) <= 1e-9
    if c.semimonotone is False:
        x = np.array(c.witnesses["semimonotone"])
        assert x.min() >= 0 and np.all((M @ x)[x > 0] < 0)
    if c.copositive is False:
        x = np.array(c.witnesses["copositive"])
        assert x.min() >= 0 and x @ M @ x < 0


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(M=small_int, seed=st.integers(0, 2 ** 16))
def test_guarantees_hold_on_lcps(M, seed):
    """What the classes promise, checked on LCPs solved by enumerating complementary bases."""
    c = classify(M)
    n = len(M)
    rng = np.random.default_rng(seed)
    # implications between classes are never violated
    implied = [("p_matrix", "p0"), ("p0", "semimonotone"), ("copositive", "semimonotone"),
               ("strictly_copositive", "copositive"), ("strictly_copositive", "r0"),
               ("p_matrix", "r0"), ("psd", "copositive"), ("psd", "p0"), ("positive_definite", "p_matrix"),
               ("p_matrix", "q_matrix"), ("strictly_copositive", "q_matrix"), ("m_matrix", "p_matrix")]
    for a, b in implied:
        if getattr(c, a) is True:
            assert getattr(c, b) is True, (a, b)
    if c.game_value.value > 1e-9:  # S-matrix: y* > 0 direction makes every q feasible
        assert np.min(M @ c.game_value.y) > 0
    for _ in range(5):
        q = rng.standard_normal(n) * 3
        sols = lcp_solutions(M, q)
        if c.q_matrix:
            assert sols, f"Q-matrix but LCP(q, M) unsolvable for q = {q}"
        if c.p_matrix:
            assert len(sols) == 1
        if c.semimonotone and q.min() > 0:
            assert len(sols) == 1 and np.all(sols[0] == 0)
    if c.q_matrix is False and c.game_value.upper <= 1e-10 * max(1.0, np.abs(M).max()):
        assert lcp_solutions(M, -np.ones(n)) == []
