"""LCP solvers: seed 002's examples, Siconos' test set side by side with Siconos, property
tests against the enumeration oracle, failure reporting and bad input."""

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import meicp
from meicp.core.errors import ProblemError, SolverNotFound
from meicp.io.problem_files import read_problem, read_siconos_lcp
from meicp.lcp.problem import LCPProblem, relative_residual
from meicp.lcp.solve import solve_lcp

from .conftest import DATA, meicp_cmd, run
from .helpers import write_hdf5_problem

SICONOS_DIR = DATA / "siconos-lcp"
SICONOS_FILES = sorted(SICONOS_DIR.glob("*.dat"))
NO_SOLUTION = {"lcp_Pang_isolated_sol_perturbed.dat"}
DENSE_METHODS = ["lemke", "enumerate", "newton"]

SEED_EXAMPLES = [
    ([[2, -1], [-1, 2]], [-1, -2], [4 / 3, 5 / 3], [0, 0]),
    ([[2, -1, 0], [-1, 2, -1], [0, -1, 2]], [-2, 4, -4], [1, 0, 2], [0, 1, 0]),
]


@pytest.mark.parametrize("M, q, x, w", SEED_EXAMPLES)
@pytest.mark.parametrize("method", ["auto", "lemke", "enumerate", "pgs", "newton", "tao"])
def test_seed_002_worked_examples(M, q, x, w, method):
    r = solve_lcp(M, q, method=method)
    assert r.success, r.summary()
    assert np.allclose(r.x, x, atol=1e-12) and np.allclose(r.w, w, atol=1e-12)
    assert r.residual <= 1e-12


def test_certificate_is_recomputed_and_failure_is_not_success():
    p = LCPProblem.from_data([[2.0, -1.0], [-1.0, 2.0]], [-1.0, -2.0])
    assert relative_residual(p, np.array([4 / 3, 5 / 3]))[0] < 1e-15
    assert relative_residual(p, np.array([1.0, 1.0]))[0] > 0.1
    r = solve_lcp([[2.0, -1.0], [-1.0, 2.0]], [-1.0, -2.0], method="pgs", max_iter=1)
    assert not r.success and r.status == "max_iterations"


@pytest.mark.parametrize("path", SICONOS_FILES, ids=lambda p: p.stem)
def test_siconos_set_solved_or_proved_unsolvable(path):
    data = read_problem(path)
    r = solve_lcp(data["M"], data["q"])
    if path.name in NO_SOLUTION:
        assert r.status == "infeasible" and not r.success
        assert "no solution" in r.message
    else:
        assert r.success, (r.summary(), r.attempts)
        assert r.residual <= 1e-10


def test_sparse_block_files_equal_their_dense_twins():
    for stem in ("trivial", "deudeu", "ortiz"):
        Md, qd, _ = read_siconos_lcp(SICONOS_DIR / f"lcp_{stem}.dat")
        Mb, qb, _ = read_siconos_lcp(SICONOS_DIR / f"lcp_{stem}_block.dat")
        assert sp.issparse(Mb) and np.array_equal(Md, Mb.toarray()) and np.array_equal(qd, qb)


@pytest.mark.parametrize("path", [p for p in SICONOS_FILES if p.name not in NO_SOLUTION and "_block" not in p.name],
                         ids=lambda p: p.stem)
def test_agreement_with_siconos_lemke(path):
    """Where Siconos' Lemke and ours both succeed: same x when the solution is unique (the
    enumeration says so), otherwise both certified solutions of the same problem."""
    pytest.importorskip("siconos.numerics")
    from meicp.lcp.siconos import siconos_solve

    M, q, _ = read_siconos_lcp(path)
    ours = solve_lcp(M, q, method="lemke")
    theirs = siconos_solve(M, q, "lemke")
    if not (ours.success and theirs.success):
        # Lemke's known ray termination on the bimatrix game CPS_3, for both codes alike
        assert ours.status == "ray_termination" and path.stem == "lcp_CPS_3"
        assert not theirs.success
        return
    if len(q) <= 12:
        every = solve_lcp(M, q, method="enumerate").solutions
        if len(every) == 1:
            assert np.allclose(ours.x, theirs.x, rtol=1e-8, atol=1e-10)
            return
    assert ours.residual <= 1e-10 and theirs.residual <= 1e-8


# --- property tests against the enumeration oracle --------------------------------------

small = st.integers(min_value=1, max_value=6)


def _data(draw, n, kind):
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    A = rng.standard_normal((n, n))
    if kind == "spd":
        M = A @ A.T + 0.1 * np.eye(n)
    elif kind == "p":  # strictly row diagonally dominant with positive diagonal: a P-matrix
        M = A + np.diag(np.abs(A).sum(axis=1) + 0.1)
    else:
        M = A
    return M, rng.standard_normal(n)


@st.composite
def lcp_data(draw, kind):
    return _data(draw, draw(small), kind)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(lcp_data("p"))
def test_p_matrix_unique_solution_all_methods_agree(data):
    M, q = data
    every = solve_lcp(M, q, method="enumerate")
    assert every.success and len(every.solutions) == 1  # P-matrix: exactly one solution
    for method in ("lemke", "newton"):
        r = solve_lcp(M, q, method=method)
        assert r.success, r.summary()
        assert np.allclose(r.x, every.x, rtol=1e-8, atol=1e-10)


@settings(max_examples=40, deadline=None)
@given(lcp_data("spd"))
def test_spd_symmetric_methods_agree(data):
    M, q = data
    ref = solve_lcp(M, q, method="enumerate").x
    for method in ("pgs", "tao", "lemke"):
        r = solve_lcp(M, q, method=method)
        assert r.success and np.allclose(r.x, ref, rtol=1e-7, atol=1e-9), (method, r.summary())


@settings(max_examples=80, deadline=None)
@given(lcp_data("general"))
def test_general_matrix_lemke_never_contradicts_enumeration(data):
    M, q = data
    every = solve_lcp(M, q, method="enumerate")
    r = solve_lcp(M, q, method="lemke")
    if every.status == "infeasible":
        assert not r.success
    if r.success:
        assert every.success  # a certified solution exists, so enumeration must find one
        assert r.residual <= 1e-10
    if solve_lcp(M, q, method="auto").success:
        assert every.success


# --- sparse and PETSc paths -------------------------------------------------------------

def _laplacian(m, shift=0.05):
    from meicp.petsc.selfcheck import laplacian_rows

    return (laplacian_rows(m, m, 0, m * m) + shift * sp.eye(m * m)).tocsr()


@pytest.mark.parametrize("method", ["tao", "newton", "pgs", "auto"])
def test_sparse_spd_lcp(method):
    M = _laplacian(40)
    q = np.random.default_rng(3).standard_normal(M.shape[0])
    r = solve_lcp(M, q, method=method)
    assert r.success and r.residual <= 1e-10, r.summary()
    ref = solve_lcp(M, q, method="tao").x
    assert np.allclose(r.x, ref, atol=1e-9)


def test_newton_on_sparse_nonsymmetric():
    M = _laplacian(20).tolil()
    M[0, 1] = -2.0  # nonsymmetric; the added diagonal keeps it strictly diagonally dominant (P)
    M = (M + sp.diags(np.full(M.shape[0], 2.0))).tocsr()
    q = np.random.default_rng(5).standard_normal(M.shape[0])
    r = solve_lcp(M, q, method="newton")
    assert r.success, r.summary()
    assert solve_lcp(M, q, method="lemke").x == pytest.approx(r.x, abs=1e-9)
    with pytest.raises(ProblemError, match="symmetric"):
        solve_lcp(M, q, method="tao")
    with pytest.raises(ProblemError, match="symmetric"):
        solve_lcp(M, q, method="pgs")


def test_petsc_failure_is_reported_not_raised():
    r = solve_lcp([[1.0, 0.0], [0.0, -1.0]], [-1.0, -1.0], method="tao")
    assert not r.success and r.status == "petsc_error" and "PETSc error" in r.message


def test_ray_termination_message_and_auto_proves_infeasible():
    M, q = [[1.0, 0.0], [0.0, -1.0]], [-1.0, -1.0]   # x2 would need -x2 - 1 ≥ 0 with x2 ≥ 0
    r = solve_lcp(M, q, method="lemke")
    assert r.status == "ray_termination" and "copositive-plus" in r.message and r.x is None
    a = solve_lcp(M, q)
    assert a.status == "infeasible" and [t[0] for t in a.attempts][-1] == "enumerate"


def test_degenerate_problem_does_not_cycle():
    # Murty's / degenerate: q with ties and a singular M block
    M = np.array([[1.0, 2.0, 0.0], [0.0, 1.0, 2.0], [2.0, 0.0, 1.0]])
    q = np.array([-1.0, -1.0, -1.0])
    r = solve_lcp(M, q, method="lemke")
    assert r.success
    r = solve_lcp(np.zeros((3, 3)), np.zeros(3), method="lemke")
    assert r.success and np.all(r.x == 0)
    r = solve_lcp(np.ones((3, 3)), -np.ones(3), method="lemke")  # singular M, ties everywhere
    assert r.success


# --- bad input --------------------------------------------------------------------------

@pytest.mark.parametrize("M, q, words", [
    (np.ones((2, 3)), [1, 1], "square"),
    (np.eye(2), [1, 1, 1], "length 3, expected 2"),
    (np.array([[np.nan, 0], [0, 1]]), [1, 1], "NaN"),
    (np.eye(2), [np.inf, 1], "NaN or Inf"),
    (np.zeros((0, 0)), [], "empty"),
])
def test_bad_input(M, q, words):
    with pytest.raises(ProblemError, match=words):
        solve_lcp(M, q)


def test_unknown_method_lists_the_known_ones():
    with pytest.raises(SolverNotFound, match="lemke"):
        solve_lcp(np.eye(2), [1, 1], method="magic")


def test_enumerate_refuses_large_n():
    with pytest.raises(ProblemError, match="max_n"):
        solve_lcp(np.eye(30), np.ones(30), method="enumerate")


# --- files and CLI ----------------------------------------------------------------------

def test_hdf5_roundtrip_dense_and_sparse(tmp_path):
    M = _laplacian(5)
    q = -np.ones(25)
    write_hdf5_problem(tmp_path / "p.h5", M=M, q=q)
    write_hdf5_problem(tmp_path / "d.h5", M=M.toarray(), q=q)
    for name in ("p.h5", "d.h5"):
        d = read_problem(tmp_path / name)
        assert np.allclose(d["M"].toarray() if sp.issparse(d["M"]) else d["M"], M.toarray())
    assert not list(tmp_path.glob("*.part"))


def test_cli_lcp_and_json(tmp_path):
    import json

    out = run(meicp_cmd() + ["lcp", str(SICONOS_DIR / "lcp_CPS_1.dat"), "--all"])
    assert out.returncode == 0 and "2 solution(s)" in out.stdout
    out = run(meicp_cmd() + ["lcp", "--json", str(SICONOS_DIR / "lcp_Pang_isolated_sol_perturbed.dat")])
    data = json.loads(out.stdout)
    assert data["status"] == "infeasible" and data["success"] is False
    out = run(meicp_cmd() + ["lcp", str(tmp_path / "missing.dat")])
    assert out.returncode == 2 and "no such file" in out.stderr
    (tmp_path / "bad.dat").write_text("2 0 2 2 2 2 1 x 1 1 -1 -1")
    out = run(meicp_cmd() + ["lcp", str(tmp_path / "bad.dat")])
    assert out.returncode == 2 and "expected a number" in out.stderr


def test_public_names():
    assert meicp.solve_lcp is solve_lcp
    r = meicp.solve_lcp(np.eye(2), [-1, 1])
    for field in ("x", "w", "status", "success", "method", "iterations", "residual"):
        assert hasattr(r, field)


def test_a_non_finite_candidate_never_passes_the_certificate():
    from meicp.lcp.problem import LCPProblem, LCPResult, certify

    problem = LCPProblem.from_data(np.eye(2), np.array([-1.0, 1.0]))
    for bad in ([np.nan, 0.0], [np.inf, 0.0]):
        r = certify(problem, LCPResult(method="test"), np.array(bad))
        assert not r.success and r.residual == np.inf

