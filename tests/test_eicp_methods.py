"""Two independent EiCP methods: SPG on the Rayleigh quotient (meicp.eicp.rayleigh) and
semismooth Newton on PETSc SNES VI (meicp.petsc.eicp_semismooth).

Oracles (docs/design.md §4.4), computed here without the library:
- ``brute_force``: every nonempty support S ⊆ J, the reduced pencil on R = F ∪ S by
  ``scipy.linalg.eigh``, eigenpairs with ξ_S > 0 and (λB − A)_{J∖S} ξ ≥ 0 (both signs of ξ
  when S = ∅, since then nothing fixes the sign);
- the 2×2 example with eigenvalues −1, −2, −(3+√5)/2;
- the Z-family (off-diagonal A < 0, B positive diagonal): exactly 2^n − 1 solutions
  λ_min(B_SS⁻¹A_SS).  Direction: −B_SS⁻¹A_SS is nonnegative off the diagonal and
  irreducible, so by Perron–Frobenius only its *largest* eigenvalue has a positive
  eigenvector, i.e. the *smallest* eigenvalue of B_SS⁻¹A_SS; and outside S,
  w_j = −Σ_{i∈S} A_ji ξ_i > 0, so every S ≠ ∅ gives a solution.
- the Niu et al. set in tests/data/eicp-niu (no reference values: certificates only).
"""

import itertools
import math
import os

import numpy as np
import pytest
import scipy.io as sio
import scipy.linalg as la
import scipy.sparse as sp
from hypothesis import HealthCheck, given, settings, strategies as st

from meicp.core.errors import ProblemError
from meicp.eicp.problem import EiCPProblem
from meicp.eicp.rayleigh import project_simplex, rayleigh
from meicp.petsc.eicp_semismooth import semismooth

from .conftest import DATA

TOL = 1e-10

# ------------------------------------------------------------------------------------------
# oracles
# ------------------------------------------------------------------------------------------


def brute_force(A, B, J=None, dual_tol=1e-9):
    """All (λ, x) of the MEiCP by support enumeration; x with ‖x‖₂ = 1."""
    n = len(A)
    J = list(range(n)) if J is None else sorted(int(j) for j in J)
    F = [i for i in range(n) if i not in J]
    out = []
    for k in range(len(J) + 1):
        for S in itertools.combinations(J, k):
            R = sorted(F + list(S))
            if not R:
                continue
            lams, V = la.eigh(A[np.ix_(R, R)], B[np.ix_(R, R)])
            in_S = np.isin(R, S)
            rest = [j for j in J if j not in S]
            for lam, v in zip(lams, V.T):
                if in_S.any():
                    v = -v if v[in_S].sum() < 0 else v
                    signs = [v] if np.all(v[in_S] > 0) else []
                else:
                    signs = [v, -v]
                for v in signs:
                    x = np.zeros(n)
                    x[R] = v
                    w = lam * B @ x - A @ x
                    scale = np.abs(A).max() + abs(lam) * np.abs(B).max()
                    if rest and w[rest].min() < -dual_tol * scale:
                        continue
                    out.append((float(lam), x / np.linalg.norm(x)))
    return out


def among(sol, reference, lam_tol=1e-7, x_tol=1e-5) -> bool:
    """Whether a returned solution is one of the oracle's (x up to sign when x_J = 0)."""
    return any(abs(sol.lam - lam) <= lam_tol * max(1.0, abs(lam))
               and min(np.abs(sol.x - x).max(), np.abs(sol.x + x).max()) <= x_tol
               for lam, x in reference)


def z_family(n, seed):
    rng = np.random.default_rng(seed)
    A = -rng.uniform(0.2, 1.0, (n, n))
    A = A + A.T
    np.fill_diagonal(A, rng.uniform(-1.0, 1.0, n))
    B = np.diag(rng.uniform(0.5, 2.0, n))
    return A, B


def subsets(n):
    for k in range(1, n + 1):
        yield from (list(S) for S in itertools.combinations(range(n), k))


def random_symmetric(n, seed):
    rng = np.random.default_rng(seed)
    M = rng.standard_normal((n, n))
    C = rng.standard_normal((n, n))
    return M + M.T, C @ C.T + n * np.eye(n)


EXAMPLE_A = -np.array([[1.0, 1.0], [1.0, 2.0]])
EXAMPLE_LAMS = [-1.0, -2.0, -(3 + math.sqrt(5)) / 2]

# ------------------------------------------------------------------------------------------
# the oracles themselves
# ------------------------------------------------------------------------------------------


def test_brute_force_on_the_small_example():
    assert sorted(lam for lam, _ in brute_force(EXAMPLE_A, np.eye(2))) == pytest.approx(
        sorted(EXAMPLE_LAMS), abs=1e-12)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_z_family_solutions_are_the_smallest_reduced_eigenvalues(seed):
    n = 5
    A, B = z_family(n, seed)
    found = sorted(lam for lam, _ in brute_force(A, B))
    smallest = sorted(min(la.eigvalsh(A[np.ix_(S, S)], B[np.ix_(S, S)])) for S in subsets(n))
    largest = sorted(max(la.eigvalsh(A[np.ix_(S, S)], B[np.ix_(S, S)])) for S in subsets(n))
    assert len(found) == 2 ** n - 1
    assert found == pytest.approx(smallest, abs=1e-10)
    assert found != pytest.approx(largest, abs=1e-6)  # the other direction is wrong


def test_simplex_projection():
    rng = np.random.default_rng(0)
    for _ in range(50):
        v = rng.standard_normal(7) * 3
        p = project_simplex(v)
        assert p.min() >= 0 and p.sum() == pytest.approx(1.0)
        # optimality: v − p = θe − ν with ν ≥ 0 on p = 0, i.e. v − p constant on the support
        d = (v - p)[p > 0]
        assert np.ptp(d) < 1e-12 and np.all((v - p)[p == 0] <= d[0] + 1e-12)
    assert project_simplex(np.array([1e300, -1e300, 0.0])) == pytest.approx([1, 0, 0])


# ------------------------------------------------------------------------------------------
# rayleigh
# ------------------------------------------------------------------------------------------


def test_rayleigh_small_example_all_three():
    p = EiCPProblem.from_data(EXAMPLE_A, np.eye(2))
    both = rayleigh(p, sense="both")
    assert both.success
    assert [s.lam for s in both.solutions] == pytest.approx(EXAMPLE_LAMS, abs=1e-12)
    assert max(s.residual for s in both.solutions) <= 1e-14
    ascent = rayleigh(p)  # the maximiser of r on the simplex is e_1, λ = −1
    assert ascent.solutions[0].lam == pytest.approx(-1.0, abs=1e-14)
    assert rayleigh(p, lam_min=-1.5, sense="both").lam == pytest.approx(-1.0)
    none = rayleigh(p, lam_min=0.0, sense="both")
    assert not none.success and none.status == "not_found" and len(none.candidates) >= 3


@pytest.mark.parametrize("seed", [0, 1])
def test_rayleigh_z_family(seed):
    n = 6
    A, B = z_family(n, seed)
    reference = brute_force(A, B)
    assert len(reference) == 2 ** n - 1
    p = EiCPProblem.from_data(A, B)
    vertices = rayleigh(p, starts=list(np.eye(n)))  # every vertex is a solution here
    assert sorted(s.lam for s in vertices.solutions) == pytest.approx(
        sorted(np.diag(A) / np.diag(B)), abs=1e-12)
    descent = rayleigh(p, sense="min")  # the global minimum: full support
    assert descent.solutions[-1].lam == pytest.approx(la.eigvalsh(A, B)[0], abs=1e-10)
    for result in (vertices, descent):
        assert all(s.residual <= TOL and among(s, reference) for s in result.solutions)


def test_rayleigh_sparse_matches_dense():
    A, B = z_family(8, 3)
    dense = rayleigh(EiCPProblem.from_data(A, B), sense="both")
    sparse = rayleigh(EiCPProblem.from_data(sp.csr_matrix(A), sp.csr_matrix(B)), sense="both")
    assert [s.lam for s in sparse.solutions] == pytest.approx([s.lam for s in dense.solutions])
    assert all(s.residual <= TOL for s in sparse.solutions)


def test_rayleigh_large_sparse_polishes_with_eigsh():
    """|support| > 2000 goes through the shift-invert polish (a Z-family, B diagonal)."""
    n = 2500
    A = sp.diags([-np.ones(n - 1), np.full(n, 2.0), -np.ones(n - 1)], [-1, 0, 1], format="csr")
    B = sp.identity(n, format="csr")
    # SPG alone crawls here (4e-8 after 5000 steps); the support is right early, polish does the rest
    result = rayleigh(EiCPProblem.from_data(A, B), sense="min", n_starts=1, max_iter=300)
    full = [s for s in result.solutions if s.support.size == n]
    assert full and full[0].lam == pytest.approx(2 - 2 * math.cos(math.pi / (n + 1)), abs=1e-12)
    assert full[0].residual <= TOL


@pytest.mark.parametrize("make", [
    lambda: (np.array([[1.0, 2.0], [0.0, 1.0]]), np.eye(2), "A"),
    lambda: (np.eye(2), np.array([[2.0, 1.0], [0.0, 2.0]]), "B"),
    lambda: (np.eye(2), np.diag([1.0, -1.0]), "positive definite"),
    lambda: (sp.csr_matrix([[1.0, 2.0], [0.0, 1.0]]), sp.identity(2, format="csr"), "A"),
    lambda: (sp.identity(2, format="csr"), sp.diags([1.0, 0.0], format="csr"), "positive definite"),
])
def test_rayleigh_rejects_non_symmetric_definite_input(make):
    A, B, word = make()
    with pytest.raises(ProblemError, match=word):
        rayleigh(EiCPProblem.from_data(A, B))


# ------------------------------------------------------------------------------------------
# semismooth
# ------------------------------------------------------------------------------------------


def test_semismooth_small_example_from_each_vertex_and_the_middle():
    p = EiCPProblem.from_data(EXAMPLE_A, np.eye(2))
    for snes_type in ("vinewtonrsls", "vinewtonssls"):
        got = [semismooth(p, x0=x0, snes_type=snes_type).lam
               for x0 in ([1, 0], [0, 1], [1, 1.6])]
        assert got == pytest.approx(EXAMPLE_LAMS, abs=1e-12)


def test_semismooth_options_prefix_reaches_snes():
    from meicp.petsc import import_petsc

    db = import_petsc().Options()
    db.setValue("meicp_eicp_vi_snes_max_it", "0")  # as if given on the command line
    try:
        result = semismooth(EiCPProblem.from_data(EXAMPLE_A, np.eye(2)), x0=[1, 1])
    finally:
        db.delValue("meicp_eicp_vi_snes_max_it")
    assert result.iterations == 0 and result.status == "not_converged"
    assert "DIVERGED_MAX_IT" in result.message and not result.solutions
    assert result.candidates and result.candidates[0].residual > TOL


def test_semismooth_sparse_and_mixed():
    A, B = z_family(6, 5)
    J = [0, 1, 2]
    reference = brute_force(A, B, J)
    p = EiCPProblem.from_data(sp.csr_matrix(A), sp.csr_matrix(B), J)
    lam, x = next((lam, x) for lam, x in reference if x[J].sum() > 0.1)
    result = semismooth(p, x0=x * (1 + 1e-3), lam0=lam + 1e-3)
    assert result.success and result.lam == pytest.approx(lam, abs=1e-10)
    free_only = semismooth(EiCPProblem.from_data(A, B, []))  # J = ∅: a generalised eigenpair
    assert free_only.success
    assert np.min(np.abs(la.eigvalsh(A, B) - free_only.lam)) <= 1e-9


def test_semismooth_rejects_bad_start():
    p = EiCPProblem.from_data(EXAMPLE_A, np.eye(2))
    with pytest.raises(ProblemError, match="x_J"):
        semismooth(p, x0=[-1.0, 0.0])
    with pytest.raises(ProblemError, match="snes_type"):
        semismooth(p, snes_type="newtonls")


# ------------------------------------------------------------------------------------------
# property tests against the brute-force enumeration
# ------------------------------------------------------------------------------------------

problems = st.tuples(st.integers(1, 6), st.integers(0, 2 ** 32 - 1), st.integers(0, 2 ** 6 - 1))


def _problem(n, seed, mask):
    A, B = random_symmetric(n, seed)
    J = [j for j in range(n) if mask >> j & 1] if mask % 3 else None  # a third are EiCPs
    return A, B, J


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problems)
def test_rayleigh_solutions_are_certified_and_enumerated(data):
    A, B, J = _problem(*data)
    reference = brute_force(A, B, J)
    result = rayleigh(EiCPProblem.from_data(A, B, J), sense="both", n_starts=6)
    assert result.success  # every symmetric-definite (M)EiCP has a solution: the max of r
    for sol in result.solutions:
        assert sol.residual <= TOL
        assert among(sol, reference), (sol.lam, sorted(lam for lam, _ in reference))


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problems, st.sampled_from(["vinewtonrsls", "vinewtonssls"]))
def test_semismooth_from_default_start_is_certified_or_honest(data, snes_type):
    A, B, J = _problem(*data)
    result = semismooth(EiCPProblem.from_data(A, B, J), snes_type=snes_type)
    assert result.status in ("solved", "not_converged", "certificate_failed")
    if result.success:
        assert result.solutions[0].residual <= TOL
        assert among(result.solutions[0], brute_force(A, B, J))
    else:
        assert not result.solutions and result.message


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problems, st.sampled_from(["vinewtonrsls", "vinewtonssls"]), st.integers(0, 10 ** 6))
def test_semismooth_converges_from_near_a_known_solution(data, snes_type, pick):
    """A start within 1e-3 of a solution with the same zeros converges to it (to a
    solution, when another lies within that distance).

    Zeros stay zeros: the reduced-space method identifies the active set from x_j = 0 and,
    from a small *positive* x_j where the solution has 0, often converges elsewhere
    (measured: ~40 % of EiCP starts perturbed on every entry; vinewtonssls handled all).
    """
    A, B, J = _problem(*data)
    p = EiCPProblem.from_data(A, B, J)
    reference = [(lam, x) for lam, x in brute_force(A, B, J)
                 if p.J.size == 0 or x[p.J].sum() > 1e-3]  # g = eᵀx_J − 1 needs x_J ≠ 0
    if not reference:
        return
    lam, x = reference[pick % len(reference)]
    rng = np.random.default_rng(pick)
    x0 = x * (1 + 1e-3 * rng.standard_normal(x.size))
    result = semismooth(p, x0=x0, lam0=lam * (1 + 1e-3) + 1e-3, snes_type=snes_type)
    assert result.success, result.message
    assert result.solutions[0].residual <= TOL
    every = brute_force(A, B, J)
    assert among(result.solutions[0], every)
    # a start 1e-3 away is as near a second solution whose λ lies that close (measured: two
    # supports of one 6×6 EiCP 6.4e-7 apart in λ); an isolated one must be the one converged to
    others = [mu for mu, _ in every if mu != lam]
    if all(abs(mu - lam) > 1e-2 * max(1.0, abs(lam)) for mu in others):
        assert result.lam == pytest.approx(lam, abs=1e-9 * max(1.0, abs(lam)))


# ------------------------------------------------------------------------------------------
# the Niu et al. set (symmetric EiCPs, n = 50..200, no reference values)
# ------------------------------------------------------------------------------------------

NIU = sorted(str(f) for f in (DATA / "eicp-niu").glob("*.mat"))


def _niu(path):
    d = sio.loadmat(path)
    return EiCPProblem.from_data(d["A"], d["B"]), d["x0"].ravel()


@pytest.mark.parametrize("path", NIU, ids=[os.path.basename(f) for f in NIU])
def test_niu_rayleigh_solves_every_problem(path):
    problem, x0 = _niu(path)
    result = rayleigh(problem)
    assert result.success
    assert max(s.residual for s in result.solutions) <= TOL
    from_x0 = rayleigh(problem, starts=[x0])
    assert from_x0.success and from_x0.solutions[0].residual <= TOL


def test_niu_semismooth_never_claims_an_uncertified_solution():
    solved = {}
    for path in NIU:
        problem, x0 = _niu(path)
        for snes_type in ("vinewtonrsls", "vinewtonssls"):
            result = semismooth(problem, x0=x0, snes_type=snes_type)
            assert result.status in ("solved", "not_converged", "certificate_failed")
            if result.success:
                assert result.solutions[0].residual <= TOL
                solved.setdefault(snes_type, []).append(os.path.basename(path))
            else:
                assert not result.solutions and "SNES" in result.message
    # the two the README reports for a plain semismooth approach (measured here: rsls with
    # full Newton steps also solves both RANDEICP problems, 4 of 6; ssls 1 of 6)
    assert {"NEP_rdb200.mtx.mat", "NEP_tub100.mtx.mat"} <= set(solved.get("vinewtonrsls", []))


@pytest.mark.parametrize("path", NIU, ids=[os.path.basename(f) for f in NIU])
def test_niu_semismooth_polishes_from_the_rayleigh_solution(path):
    """Third opinion: Newton started 1e-3 away from SPG's solution (same zeros) returns it."""
    problem, _ = _niu(path)
    best = rayleigh(problem, n_starts=2).solutions[0]
    x0 = best.x * (1 + 1e-3 * np.cos(np.arange(problem.n)))
    again = semismooth(problem, x0=x0, lam0=best.lam * (1 + 1e-3))
    assert again.success and again.lam == pytest.approx(best.lam, rel=1e-12)
    assert np.abs(again.solutions[0].x - best.x).max() <= 1e-8


def test_through_solve_eicp_and_lam_min():
    from meicp import solve_eicp

    ray = solve_eicp(EXAMPLE_A, np.eye(2), method="rayleigh", sense="both", lam_min=-2.5)
    assert [s.lam for s in ray.solutions] == pytest.approx([-1.0, -2.0])
    newton = solve_eicp(EXAMPLE_A, np.eye(2), method="semismooth", lam_min=-2.5)  # finds −2.618
    assert newton.status == "not_found" and not newton.solutions
    assert newton.candidates[0].lam == pytest.approx(EXAMPLE_LAMS[2])
    assert solve_eicp(EXAMPLE_A, np.eye(2), method="semismooth", x0=[1, 0], lam_min=-2.5).lam == -1.0
