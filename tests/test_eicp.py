"""EiCP/MEiCP: enumeration against docs/design.md §4.4's oracles and an independent brute force,
active-set answers among the enumerated ones, certificates, failure statuses, bad input."""

import itertools

import numpy as np
import pytest
import scipy.linalg
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st

import meicp
from meicp.core import limits
from meicp.core.errors import ProblemError, SolverNotFound
from meicp.eicp.problem import EiCPProblem, certify_pair

from .conftest import meicp_cmd, run
from .helpers import write_hdf5_problem


def brute_force(A, B, J):
    """Independent oracle: every support S ⊆ J, scipy.linalg.eig on R = F ∪ S, one by one."""
    n = A.shape[0]
    F = [i for i in range(n) if i not in set(J)]
    out = []
    for k in range(len(J) + 1):
        for S in itertools.combinations(J, k):
            R = F + list(S)
            if not R:
                continue
            lam, V = scipy.linalg.eig(A[np.ix_(R, R)], B[np.ix_(R, R)])
            for l, v in zip(lam, V.T):
                if not np.isfinite(l) or abs(l.imag) > 1e-9 or np.abs(v.imag).max() > 1e-9 * np.abs(v).max():
                    continue
                v = v.real
                if S:
                    vs = v[len(F):]
                    if vs.min() <= 0 < vs.max() or np.abs(vs).min() < 1e-12 * np.abs(v).max():
                        continue
                    v = v if vs.min() > 0 else -v
                x = np.zeros(n)
                x[R] = v
                out_idx = [j for j in J if j not in S]
                scale = np.abs(A).max() + abs(l.real) * np.abs(B).max()
                signs = (1, -1) if not S else (1,)  # an empty support leaves the sign free
                if any(not out_idx or (((l.real * B - A) @ (s * x))[out_idx]).min()
                       >= -1e-9 * scale * np.abs(x).max() for s in signs):
                    out.append(l.real)
    return np.sort(out)[::-1]


def test_design_2x2_has_exactly_three_solutions():
    r = meicp.solve_eicp(-np.array([[1.0, 1.0], [1.0, 2.0]]), np.eye(2), all_solutions=True)
    assert r.success and r.method == "enumerate"
    lams = sorted(s.lam for s in r.solutions)
    assert np.allclose(lams, [-(3 + 5 ** 0.5) / 2, -2.0, -1.0], rtol=1e-12)
    for s in r.solutions:
        assert s.residual <= 1e-12 and abs(np.linalg.norm(s.x) - 1) < 1e-14 and s.x.min() >= 0


def z_family(n, seed=0):
    rng = np.random.default_rng(seed)
    A = -rng.uniform(0.1, 1.0, (n, n))
    np.fill_diagonal(A, rng.standard_normal(n))
    B = np.diag(rng.uniform(0.5, 2.0, n))
    return A, B


@pytest.mark.parametrize("n", [3, 6, 10])
def test_z_family_has_exactly_2n_minus_1_solutions(n):
    A, B = z_family(n, n)
    r = meicp.solve_eicp(A, B, all_solutions=True)
    assert len(r.solutions) == 2 ** n - 1
    expected = sorted(np.linalg.eigvals(np.linalg.solve(B[np.ix_(S, S)], A[np.ix_(S, S)])).real.min()
                      for k in range(1, n + 1) for S in itertools.combinations(range(n), k))
    assert np.allclose(sorted(s.lam for s in r.solutions), expected, rtol=1e-10, atol=1e-12)
    supports = {tuple(s.support) for s in r.solutions}
    assert len(supports) == 2 ** n - 1  # one solution per nonempty support


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 5), st.integers(0, 2 ** 31), st.booleans(), st.integers(0, 2))
def test_enumeration_matches_brute_force(n, seed, symmetric, n_free):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    if symmetric:
        A = A + A.T
    C = rng.standard_normal((n, n))
    B = C @ C.T + n * np.eye(n) if symmetric else np.diag(rng.uniform(0.5, 2, n))
    J = sorted(rng.choice(n, size=max(0, n - n_free), replace=False).tolist())
    r = meicp.solve_eicp(A, B, J=J, all_solutions=True)
    ref = brute_force(A, B, J)
    got = np.sort([s.lam for s in r.solutions])[::-1]
    # brute force may list one λ twice (±ξ on an empty support); compare the distinct values
    assert np.allclose(np.unique(np.round(got, 8)), np.unique(np.round(ref, 8)), atol=1e-7)
    for s in r.solutions:
        assert s.residual <= 1e-10
        assert np.all(s.x[J] >= 0) and np.all(np.isin(s.support, J))


@settings(max_examples=30, deadline=None)
@given(st.integers(2, 8), st.integers(0, 2 ** 31))
def test_active_set_answer_is_an_enumerated_solution(n, seed):
    A, B = z_family(n, seed)
    every = meicp.solve_eicp(A, B, method="enumerate")
    r = meicp.solve_eicp(A, B, method="active-set", target=float(np.abs(A).sum()))
    if r.success:
        sol = r.solutions[0]
        assert sol.residual <= 1e-10
        assert any(abs(sol.lam - e.lam) <= 1e-9 * max(1, abs(e.lam)) and
                   tuple(sol.support) == tuple(e.support) for e in every.solutions)
    else:
        assert r.status in ("max_iterations", "cycling", "not_converged", "empty_support")
        assert "does not prove" in r.message


def test_active_set_on_z_family_finds_the_full_support_perron_solution():
    # the positive (Perron) eigenvector belongs to λ_min(B⁻¹A): with the target below the
    # spectrum the first solve on S = J returns it, and it is violation-free
    A, B = z_family(30, 4)
    r = meicp.solve_eicp(sp.csr_matrix(A), sp.csr_matrix(B), method="active-set", target=-float(np.abs(A).sum()))
    assert r.success and r.solutions[0].support.size == 30 and r.coverage["eigen_solves"] == 1
    lam = np.linalg.eigvals(np.linalg.solve(B, A)).real.min()
    assert abs(r.solutions[0].lam - lam) <= 1e-10 * abs(lam)


def test_mixed_problem_with_free_variables():
    rng = np.random.default_rng(2)
    n = 7
    A = rng.standard_normal((n, n))
    A = A + A.T
    B = np.diag(rng.uniform(1, 2, n))
    J = [1, 4, 5]
    r = meicp.solve_eicp(A, B, J=J, all_solutions=True)
    assert r.success
    assert np.allclose(np.sort([s.lam for s in r.solutions])[::-1], brute_force(A, B, J), atol=1e-9)
    F = np.setdiff1d(np.arange(n), J)
    for s in r.solutions:
        assert np.abs(s.w[F]).max() <= 1e-10 * (np.abs(A).max() + abs(s.lam) * 2)


def test_lambda_window_and_no_solution_is_a_proof():
    A, B = z_family(5, 1)
    every = meicp.solve_eicp(A, B, all_solutions=True)
    top = max(s.lam for s in every.solutions)
    r = meicp.solve_eicp(A, B, all_solutions=True, lam_min=top + 1.0)
    assert r.status == "no_solution" and not r.success and "all 32 supports" in r.message
    r = meicp.solve_eicp(A, B, all_solutions=True, lam_min=top - 1e-9)
    assert [s.lam for s in r.solutions] == pytest.approx([top])


def test_certificate_rejects_a_wrong_pair():
    p = EiCPProblem.from_data(-np.array([[1.0, 1.0], [1.0, 2.0]]), np.eye(2))
    assert certify_pair(p, -1.0, np.array([1.0, 0.0])).residual < 1e-15
    assert certify_pair(p, -1.5, np.array([1.0, 0.0])).residual > 0.1
    assert certify_pair(p, -1.0, np.array([-1.0, 0.0])).x[0] > 0  # sign convention


def test_complex_spectrum_gives_no_fake_solution():
    # rotation: no real eigenvalue at all, so no EiCP solution
    A = np.array([[0.0, -1.0], [1.0, 0.0]])
    r = meicp.solve_eicp(A, np.eye(2), J=[], all_solutions=True)
    assert r.status == "no_solution"


@pytest.mark.parametrize("A, B, J, words", [
    (np.eye(2), np.eye(3), None, "same shape"),
    (np.array([[np.nan, 0], [0, 1]]), np.eye(2), None, "NaN"),
    (np.eye(2), np.eye(2), [0, 2], "out of range"),
    (np.eye(2), np.eye(2), [1, 1], "repeats"),
    (np.ones((2, 3)), np.ones((2, 3)), None, "square"),
])
def test_bad_input(A, B, J, words):
    with pytest.raises(ProblemError, match=words):
        meicp.solve_eicp(A, B, J=J)


def test_unknown_method_and_large_enumeration():
    with pytest.raises(SolverNotFound, match="active-set"):
        meicp.solve_eicp(np.eye(2), np.eye(2), method="nope")
    with pytest.raises(ProblemError, match="max_j"):
        meicp.solve_eicp(np.eye(30), np.eye(30), method="enumerate")


def test_cli_eicp(tmp_path):
    import json

    write_hdf5_problem(tmp_path / "p.h5", A=-np.array([[1.0, 1.0], [1.0, 2.0]]), B=np.eye(2))
    out = run(meicp_cmd() + ["eicp", str(tmp_path / "p.h5"), "--all", "--json"])
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert sorted(s["lam"] for s in data["solutions"]) == pytest.approx([-(3 + 5 ** 0.5) / 2, -2, -1])
    assert data["attempts"] == []  # --all runs the enumeration itself, not auto's portfolio
    # auto records the method(s) it ran, as `meicp lcp --json` does
    out = run(meicp_cmd() + ["eicp", str(tmp_path / "p.h5"), "--json"])
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert data["attempts"] and data["attempts"][-1][:2] == [data["method"], data["status"]]
    write_hdf5_problem(tmp_path / "bad.h5", A=np.eye(2))
    out = run(meicp_cmd() + ["eicp", str(tmp_path / "bad.h5")])
    assert out.returncode == 2 and "no dataset 'B'" in out.stderr


def test_tol_out_of_range_is_refused_and_a_loose_one_warned(caplog):
    A, B = np.diag([1.0, 2.0]), np.eye(2)
    for bad in (0.0, -1e-8, 1.0, float("nan")):
        with pytest.raises(meicp.ProblemError, match="tol must lie in"):
            meicp.solve_eicp(A, B, tol=bad)
    with caplog.at_level("WARNING", logger="meicp"):
        r = meicp.solve_eicp(A, B, tol=1e-3)
    assert r.success and "does not pin" in caplog.text


def test_enumeration_with_a_nearly_singular_nondiagonal_B_misses_no_solution():
    """B_RR⁻¹A_RR loses finite eigenvalues when B has a 1e-13 singular value; a missed
    solution would make the enumeration a false proof.  Brute force by QZ as reference."""
    misses = 0
    for seed in range(40):
        rng = np.random.default_rng(seed)
        n = 5
        A = rng.standard_normal((n, n))
        U = np.linalg.qr(rng.standard_normal((n, n)))[0]
        V = np.linalg.qr(rng.standard_normal((n, n)))[0]
        B = U @ np.diag([1, 1, 1, 1, 1e-13]) @ V.T
        want = []
        for k in range(1, n + 1):
            for S in itertools.combinations(range(n), k):
                R = np.array(S)
                lam, X = scipy.linalg.eig(A[np.ix_(R, R)], B[np.ix_(R, R)])
                for l, x in zip(lam, X.T):
                    if not np.isfinite(l) or abs(l.imag) > 1e-8 * max(1, abs(l)):
                        continue
                    x = x.real * np.sign(x.real[np.argmax(np.abs(x.real))])
                    full = np.zeros(n)
                    full[R] = x
                    w = (l.real * B - A) @ full
                    s = np.abs(A).max() + abs(l.real) * np.abs(B).max()
                    if x.min() > 1e-9 * np.abs(x).max() and np.delete(w, R).min(initial=0) > -1e-9 * s:
                        want.append(l.real)
        got = [s.lam for s in meicp.solve_eicp(A, B, method="enumerate").solutions]
        # the same set up to relative rounding: the eigenvalue pushed to ~1e12 by B's 1e-13
        # singular value differs in its 16th digit between LAPACK builds
        misses += not (_within(got, want) and _within(want, got))
    assert misses == 0


def _within(xs, ys, rel=1e-9):
    """Every x of xs is within ``rel`` (relative, or absolute below 1) of some y of ys."""
    return all(any(abs(x - y) <= rel * max(1.0, abs(x)) for y in ys) for x in xs)


def test_enumeration_by_name_is_refused_by_its_work_before_any_solve():
    # 16 pairs passed the pair limit whatever the order: on order 400 that is 4.2e12 flops
    # (hours); the budget refuses it at once, and an explicit max_j accepts the cost
    from meicp.eicp import budget
    from meicp.eicp.solve import auto_order
    from meicp.eicp.problem import EiCPProblem

    A, B, J = -np.eye(400), np.eye(400), np.arange(16)
    with pytest.raises(ProblemError, match=r"\|J\| = 16, r = 400 is about 4\.2e\+12 flops .*max_j=16"):
        meicp.solve_eicp(A, B, J=J, method="enumerate")
    with pytest.raises(ProblemError, match="ENUMERATE_MAX_FLOPS"):
        meicp.solve_eicp(A, B, J=J, all_solutions=True)
    assert auto_order(EiCPProblem.from_data(A, B, J))[0] == "enumerate"  # auto's own choice unchanged
    budget.check_enumeration_work(16, 312, "max_j")  # about an hour: accepted
    with pytest.raises(ProblemError):
        budget.check_enumeration_work(16, 313, "max_j")
    assert limits.ENUMERATE_MAX_FLOPS * limits.SECONDS_PER_FLOP <= 1.2 * 3600
