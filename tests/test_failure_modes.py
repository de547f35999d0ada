"""Documented failure modes (docs/benchmarks.md, "Failure map"; scripts/bench_failure.py):
where a method cannot give the answer, it must say so — a failure status, a refusal, or
the explicit "no divergence mode" — never a wrong, certified-looking answer.

Each test builds one point of the failure map, checks it against an independent
reference (analytic, or brute force with scipy.linalg.eig / numpy.linalg.solve), and
pins what the method reports there.  The problems and the brute-force references are the
failure map's own (:mod:`meicp.examples.failure_map`).  Serial and fast.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import scipy.linalg as sla

import meicp
from meicp.core.errors import ProblemError
from meicp.examples import failure_map as fm
from meicp.examples.failure_map import MU_C  # two_layers.toml, every base node slip+


def _sigmas(A, B, J):
    """Every real MEiCP σ ≥ 0 of the failure map's brute-force reference, largest first."""
    return sorted((lam for lam, _ in fm.all_eicp_solutions(A, B, J, lam_min=0.0)[0]), reverse=True)


# ----------------------------------------------------------------------------- flutter

@pytest.fixture(scope="module")
def flutter_pencil():
    A, B, J = fm.mode_coupling(0.7)
    ev = sla.eigvals(A, B)
    assert np.abs(ev.imag).max() > 0.1          # a complex pair: flutter
    assert _sigmas(A, B, J) == []  # and no real σ ≥ 0 at all
    return A, B, J


def test_flutter_enumerate_reports_no_divergence_mode(flutter_pencil):
    res = meicp.solve_eicp(*flutter_pencil[:2], J=flutter_pencil[2], method="enumerate", lam_min=0.0)
    assert res.status == "no_solution" and res.solutions == []


def test_flutter_active_set_fails_instead_of_a_mode(flutter_pencil):
    res = meicp.solve_eicp(*flutter_pencil[:2], J=flutter_pencil[2], method="active-set", lam_min=0.0)
    assert not res.success and res.status == "not_converged" and res.solutions == []
    assert "does not prove" in res.message


def test_flutter_semismooth_returns_no_real_mode(flutter_pencil):
    res = meicp.solve_eicp(*flutter_pencil[:2], J=flutter_pencil[2], method="semismooth", lam_min=0.0)
    assert not res.success and res.solutions == []
    assert res.status in ("not_found", "not_converged")


def test_flutter_rayleigh_refuses_nonsymmetric(flutter_pencil):
    with pytest.raises(ProblemError, match="symmetric"):
        meicp.solve_eicp(*flutter_pencil[:2], J=flutter_pencil[2], method="rayleigh", lam_min=0.0)


def test_flutter_lattice_analyze_says_no_divergence_mode():
    """Sheared lattice with stick/slip+/stick states at μ = 4: complex σ, no real σ ≥ 0."""
    sc = fm.two_layers(mu=4.0, shear=0.5, states='["stick", "slip+", "slip+", "slip+", "stick"]')
    A, B, J = fm.dense_pencil(sc)
    assert np.abs(sla.eigvals(A, B).imag).max() > 0.1
    assert _sigmas(A, B, J) == []
    r = meicp.analyze(sc)  # enumeration: a proof that no divergence mode exists
    assert r.divergence is False and r.modes == [] and "no solution with σ ≥ 0" in r.evidence
    assert r.flutter is True and r.stable is False  # the complex σ: flutter of steady sliding (issue 15)
    r = meicp.analyze(sc, method="active-set")  # the large-problem path agrees, with its own proof
    assert r.divergence is False and r.modes == [] and r.proofs[0].test == "condensed-windows"


# ----------------------------------------------------------------------------- μ across μ_c

@pytest.mark.parametrize("method", ["enumerate", "active-set"])
def test_just_below_mu_c_no_negative_sigma_reported_as_mode(method):
    """Regression (failure map): at μ = μ_c(1 − 1e-10) the largest σ is −5e-11; enumerate,
    active-set and analyze used to report it as a divergence mode (window slack tol = 1e-10
    on λ), with analyze saying "unstable".  Now λ < lam_min is never a solution."""
    sc = fm.two_layers(mu=MU_C * (1 - 1e-9))
    A, B, J = fm.dense_pencil(sc)
    assert _sigmas(A, B, J) == []
    res = meicp.solve_eicp(A, B, J=J, method=method, lam_min=0.0)
    assert res.solutions == [] and not res.success
    r = meicp.analyze(sc)
    assert r.divergence is False and r.modes == []
    sc = fm.two_layers(mu=MU_C * (1 + 1e-6))  # just above: a genuine σ ≈ 5e-7 > 0 mode
    res = meicp.solve_eicp(*fm.dense_pencil(sc)[:2], J=J, method=method, lam_min=0.0)
    assert res.success and 0 < res.lam < 1e-5


def test_critical_friction_matches_brute_force_bisection():
    mu_c = meicp.critical_friction(fm.two_layers(), flutter=False)
    assert mu_c == pytest.approx(MU_C, rel=1e-8)
    for mu, exists in ((mu_c * (1 - 1e-6), False), (mu_c * (1 + 1e-6), True)):
        A, B, J = fm.dense_pencil(fm.two_layers(mu=mu))
        assert bool(_sigmas(A, B, J)) is exists


# ----------------------------------------------------------------------------- contrast

def test_contrast_1e6_certified_or_reported():
    """k_B/k_A = 10^6: cond(A) ≈ 1.5e7.  Certified answers match the brute force to 1e-10;
    semismooth from its default start does not converge and says so."""
    A, B, J = fm.dense_pencil(fm.two_layers(kB=1e6))
    ref = _sigmas(A, B, J)
    assert len(ref) == 1
    for method in ("enumerate", "active-set", "semismooth"):
        res = meicp.solve_eicp(A, B, J=J, method=method, lam_min=0.0)
        if res.success:
            assert [s.lam for s in res.solutions] == pytest.approx(ref, rel=1e-10)
        else:
            assert method == "semismooth" and res.status in ("not_converged", "certificate_failed", "not_found")
            assert res.solutions == []


# ----------------------------------------------------------------------------- degenerate

def test_repeated_eigenvalues_enumerate_finds_every_support():
    """Z-family at δ = 0: every support of one size has the same λ_min and every block of
    size ≥ 2 a repeated eigenvalue; the 255 solutions are {λ_min(A_SS)} (Perron–Frobenius)."""
    n, a = 8, 0.5
    A, B = fm.z_family(0.0, n=n, a=a)
    res = meicp.solve_eicp(A, B, method="enumerate")
    assert res.success and len(res.solutions) == 2 ** n - 1
    assert {tuple(int(j) for j in s.support) for s in res.solutions} == \
        {S for k in range(1, n + 1) for S in itertools.combinations(range(n), k)}
    for s in res.solutions:
        k = len(s.support)
        assert s.lam == pytest.approx(-(1 + a * (k - 1)), rel=1e-12)


def test_mirror_twins_double_sigma():
    """Two identical uncoupled lattices: every σ is double and the solutions form a cone;
    every method returns σ = 0.3290549424 and nothing else."""
    A1, B1, J1 = fm.dense_pencil(fm.two_layers())
    A, B = sla.block_diag(A1, A1), sla.block_diag(B1, B1)
    J = np.concatenate([J1, J1 + A1.shape[0]])
    for method in ("enumerate", "active-set", "semismooth"):
        res = meicp.solve_eicp(A, B, J=J, method=method, lam_min=0.0)
        assert res.success, method
        assert {round(s.lam, 9) for s in res.solutions} == {0.329054942}, method


# ----------------------------------------------------------------------------- LCP

@pytest.fixture(scope="module")
def infeasible_slip_lcp():
    M, q = fm.slip_lcp(3.0)
    c = meicp.classify(M)
    assert c.p_matrix is False and c.q_matrix is False  # classes predict the loss
    assert fm.all_lcp_solutions(M, q)[0] == []  # and there is indeed no solution
    return M, q


def test_slip_lcp_below_mu_c_is_p_and_unique():
    M, q = fm.slip_lcp(1.0)
    assert meicp.classify(M).p_matrix is True
    (x,) = fm.all_lcp_solutions(M, q)[0]
    for method in ("lemke", "enumerate", "newton", "auto"):
        res = meicp.solve_lcp(M, q, method=method)
        assert res.success and np.allclose(res.x, x, atol=1e-9), method


def test_no_solution_proved_by_enumeration(infeasible_slip_lcp):
    res = meicp.solve_lcp(*infeasible_slip_lcp, method="enumerate")
    assert res.status == "infeasible" and not res.success and res.x is None
    res = meicp.solve_lcp(*infeasible_slip_lcp, method="auto")
    assert res.status == "infeasible"


def test_no_solution_lemke_ray_and_newton_fail(infeasible_slip_lcp):
    res = meicp.solve_lcp(*infeasible_slip_lcp, method="lemke")
    assert res.status == "ray_termination" and not res.success
    res = meicp.solve_lcp(*infeasible_slip_lcp, method="newton")
    assert not res.success and res.status in ("not_converged", "certificate_failed")


@pytest.mark.parametrize("method", ["pgs", "tao"])
def test_nonsymmetric_lcp_refused_by_symmetric_methods(infeasible_slip_lcp, method):
    with pytest.raises(ProblemError, match="symmetric"):
        meicp.solve_lcp(*infeasible_slip_lcp, method=method)


def test_pgs_symmetric_non_p_without_solution_fails():
    """Symmetric, positive diagonal, indefinite (not P): LCP(q, M) has no solution; PGS
    diverges, stops when x overflows and reports "diverged" (x keeps the non-finite
    iterate, for inspection), never a solution."""
    M = np.array([[1.0, -2.0], [-2.0, 1.0]])
    q = np.array([-1.0, -1.0])
    assert fm.all_lcp_solutions(M, q)[0] == []
    res = meicp.solve_lcp(M, q, method="pgs")
    assert res.status == "diverged" and not res.success and res.iterations < 1000
    assert meicp.solve_lcp(M, q, method="enumerate").status == "infeasible"


def test_large_mu_lift_load_two_solutions():
    """Beyond μ_c with q > 0 uniqueness is lost: x = 0 and one more; enumerate lists both,
    single-solution methods return one of them."""
    M, _ = fm.slip_lcp(3.0)
    q = np.ones(M.shape[0])
    ref = fm.all_lcp_solutions(M, q)[0]
    assert len(ref) == 2
    res = meicp.solve_lcp(M, q, method="enumerate")
    assert res.success and len(res.solutions) == 2
    for method in ("lemke", "newton", "auto"):
        res = meicp.solve_lcp(M, q, method=method)
        assert res.success and any(np.allclose(res.x, x, atol=1e-9) for x in ref), method


def test_siconos_reports_failure_without_solution(infeasible_slip_lcp):
    pytest.importorskip("siconos.numerics")
    from meicp.lcp.siconos import siconos_solve

    for solver in ("lemke", "enum", "newton-fb", "pgs"):
        res = siconos_solve(*infeasible_slip_lcp, solver, max_iter=2000)
        assert not res.success and res.status in ("failed", "certificate_failed"), solver


def test_nearly_coinciding_sigmas_active_set_certified_or_certificate_failed():
    """Twins at μ = 3 and 3(1 + 1e-6): two σ 1e-6 apart.  The shift-and-invert solve mixes
    the two eigenvectors; active-set then reports certificate_failed (residual 3.5e-10 >
    1e-10) rather than the mixed vector — never a wrong σ.  enumerate finds both."""
    A1, B1, J1 = fm.dense_pencil(fm.two_layers())
    A2, B2, _ = fm.dense_pencil(fm.two_layers(mu=3.0 * (1 + 1e-6)))
    A, B = sla.block_diag(A1, A2), sla.block_diag(B1, B2)
    J = np.concatenate([J1, J1 + A1.shape[0]])
    ref = _sigmas(A1, B1, J1) + _sigmas(A2, B2, J1)
    res = meicp.solve_eicp(A, B, J=J, method="enumerate", lam_min=0.0)
    assert sorted(s.lam for s in res.solutions) == pytest.approx(sorted(ref), rel=1e-10)
    res = meicp.solve_eicp(A, B, J=J, method="active-set", lam_min=0.0)
    assert res.status in ("solved", "certificate_failed")
    if res.success:
        assert any(res.lam == pytest.approx(l, rel=1e-10) for l in ref)
    else:
        assert res.solutions == [] and res.candidates and res.candidates[0].residual > 1e-10
