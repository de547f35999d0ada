"""``solve_eicp(method="auto")``: the portfolio's order, its recorded fallbacks, and the
Niu et al. set it must solve (6/6; the active-set search alone solves none of them)."""

import numpy as np
import pytest
import scipy.io as sio

import meicp
from meicp.eicp import solve as eicp_solve
from meicp.eicp.problem import EiCPProblem, certify_pair

from .conftest import DATA

NIU = sorted((DATA / "eicp-niu").glob("*.mat"), key=lambda p: p.name)
SMALL_A = -np.array([[1.0, 1.0], [1.0, 2.0]])  # EiCP(A, I): λ = −1, −2, −(3+√5)/2


def _niu(name):
    d = sio.loadmat(DATA / "eicp-niu" / name)
    return d["A"], d["B"]


def _names(result):
    return [a[0] for a in result.attempts]


@pytest.mark.parametrize("path", NIU, ids=lambda p: p.stem)
def test_auto_solves_the_niu_set(path):
    A, B = _niu(path.name)
    r = meicp.solve_eicp(A, B)
    assert r.success and r.method == "rayleigh", r.attempts
    assert r.attempts == [("rayleigh", "solved", r.message)]
    assert r.solutions and max(s.residual for s in r.solutions) <= 1e-10
    assert all(certify_pair(EiCPProblem.from_data(A, B), s.lam, s.x).residual <= 1e-10 for s in r.solutions)


def test_the_niu_set_has_six_problems():
    assert len(NIU) == 6


def test_auto_enumerates_a_small_problem_and_its_answer_is_final():
    r = meicp.solve_eicp(SMALL_A, np.eye(2))
    assert r.method == "enumerate" and _names(r) == ["enumerate"] and len(r.solutions) == 3
    proof = meicp.solve_eicp(SMALL_A, np.eye(2), lam_min=0.0)  # every λ is negative
    assert proof.status == "no_solution" and _names(proof) == ["enumerate"]


def test_auto_order_by_size_symmetry_and_layout():
    sym = EiCPProblem.from_data(*_niu("RANDEICP_-1_1_50.mat"))
    assert eicp_solve.auto_order(sym) == ["rayleigh", "active-set", "semismooth"]
    A, B = _niu("RANDEICP_-1_1_50.mat")
    A = A.copy()
    A[0, 1] += 1e-3
    assert eicp_solve.auto_order(EiCPProblem.from_data(A, B)) == ["active-set", "semismooth"]
    small = EiCPProblem.from_data(SMALL_A, np.eye(2))
    assert eicp_solve.auto_order(small) == ["enumerate", "rayleigh", "active-set", "semismooth"]


def test_auto_falls_back_from_the_active_set_to_semismooth():
    """A nonsymmetric EiCP (n = 50): no enumeration, no rayleigh; measured here, the
    active-set search runs out of support updates and Newton then certifies a solution."""
    A, B = _niu("RANDEICP_-1_1_50.mat")
    rng = np.random.default_rng(0)
    A = A + 1e-6 * np.abs(A).max() * np.triu(rng.standard_normal(A.shape), 1)
    r = meicp.solve_eicp(A, B)
    assert [a[:2] for a in r.attempts] == [("active-set", "max_iterations"), ("semismooth", "solved")]
    assert "does not prove" in r.attempts[0][2]
    assert r.method == "semismooth" and r.success and r.solutions[0].residual <= 1e-10


def test_auto_records_a_method_that_does_not_apply():
    """Symmetric A with an indefinite B: rayleigh refuses (recorded), the others run.
    Measured here: SLEPc's symmetric-definite solve fails on the indefinite B (PETSc error
    95, recorded), and Newton from its default start certifies a solution."""
    n = 20
    rng = np.random.default_rng(1)
    A = -rng.uniform(0.1, 1.0, (n, n))
    A = 0.5 * (A + A.T)
    B = np.diag(np.r_[rng.uniform(0.5, 2.0, n - 1), -1.0])
    r = meicp.solve_eicp(A, B)
    assert r.attempts[0][:2] == ("rayleigh", "not_applicable")
    assert "positive definite" in r.attempts[0][2]
    assert [a[:2] for a in r.attempts[1:]] == [("active-set", "petsc_error"), ("semismooth", "solved")]
    assert r.success and r.solutions[0].residual <= 1e-10


def test_semismooth_starts_from_the_best_candidate_in_the_window(monkeypatch):
    """When rayleigh and the active-set fail, Newton starts from the smallest-residual
    candidate with λ ≥ lam_min and a positive entry on J; without one, from its default."""
    A, B = _niu("RANDEICP_-1_1_50.mat")
    problem = EiCPProblem.from_data(A, B)
    good = meicp.solve_eicp(A, B, method="rayleigh").solutions[0]
    near = certify_pair(problem, good.lam * (1 + 1e-4), good.x)
    far = certify_pair(problem, good.lam * 0.5, np.ones(50))
    below = certify_pair(problem, -1.0, good.x)
    negative = certify_pair(problem, good.lam, -np.ones(50))
    assert eicp_solve._best_start(problem, [far, near, negative], None)["lam0"] == near.lam
    assert eicp_solve._best_start(problem, [far, below], 0.0)["lam0"] == far.lam
    assert eicp_solve._best_start(problem, [below], 0.0) == {}

    def failing(name, candidates):
        def run(p, **kw):
            return eicp_solve.EiCPResult(method=name, status="max_iterations", message=f"{name} gave up",
                                         candidates=candidates)
        return run

    seen = {}
    real = eicp_solve.SOLVERS["semismooth"]

    def semismooth(p, **kw):
        seen.update(kw)
        return real(p, **kw)

    monkeypatch.setitem(eicp_solve.SOLVERS, "rayleigh", failing("rayleigh", [far]))
    monkeypatch.setitem(eicp_solve.SOLVERS, "active-set", failing("active-set", [near]))
    monkeypatch.setitem(eicp_solve.SOLVERS, "semismooth", semismooth)
    r = meicp.solve_eicp(A, B)
    assert [a[:2] for a in r.attempts] == [("rayleigh", "max_iterations"), ("active-set", "max_iterations"),
                                          ("semismooth", "solved")]
    assert seen["lam0"] == near.lam and np.array_equal(seen["x0"], near.x)
    assert r.lam == pytest.approx(good.lam, rel=1e-12)


def test_when_every_method_fails_the_candidates_are_kept(monkeypatch):
    A, B = _niu("RANDEICP_-1_1_50.mat")
    problem = EiCPProblem.from_data(A, B)
    bad = certify_pair(problem, 0.0, np.ones(50))
    for name in ("rayleigh", "active-set", "semismooth"):
        monkeypatch.setitem(eicp_solve.SOLVERS, name,
                            lambda p, name=name, **kw: eicp_solve.EiCPResult(
                                method=name, status="not_converged", message="no", candidates=[bad]))
    r = meicp.solve_eicp(A, B)
    assert not r.success and r.status == "not_converged" and not r.solutions
    assert _names(r) == ["rayleigh", "active-set", "semismooth"] and len(r.candidates) == 3


def test_explicit_methods_are_unchanged():
    r = meicp.solve_eicp(SMALL_A, np.eye(2), method="rayleigh", sense="both")
    assert r.method == "rayleigh" and r.attempts == []


@pytest.mark.mpi(min_size=2)
def test_auto_on_two_ranks(comm):
    """A pencil distributed over the ranks gets the parallel method only; NumPy input with a
    communicator (as `meicp eicp` passes) runs the serial methods alike on every rank."""
    import scipy.sparse as sp

    from meicp.petsc.mat import mat_from_scipy
    from meicp.petsc.selfcheck import laplacian_rows

    m = 12
    n = m * m
    K = laplacian_rows(m, m, 0, n).tocsr()
    Mass = sp.diags(np.linspace(1.0, 2.0, n)).tocsr()
    J = np.arange(0, n, 7)
    Ak, Bk = mat_from_scipy(comm, -K), mat_from_scipy(comm, Mass)
    assert eicp_solve.auto_order(EiCPProblem.from_data(Ak, Bk, J)) == ["active-set"]
    par = meicp.solve_eicp(Ak, Bk, J=J, target=0.0)
    assert par.success and _names(par) == ["active-set"] and par.solutions[0].residual <= 1e-10
    Ak.destroy()
    Bk.destroy()
    r = meicp.solve_eicp(*_niu("NEP_rdb200.mtx.mat"), comm=comm)
    assert r.success and _names(r) == ["rayleigh"]
    assert len(set(comm.allgather(r.lam))) == 1
