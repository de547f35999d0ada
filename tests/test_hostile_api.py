"""Hostile input to the API, the problem files and the ``lcp``/``classify``/``eicp``
subcommands (issue 11): every case has one exact outcome, a ProblemError whose message
names what is wrong, or an honest status — never a false "solved", "no solution" or
"stable", never a crash or a traceback.  docs/hostile-input.md lists the cases.

Plus hypothesis properties: matrix scalings from 1e-300 to 1e300 against the enumeration
of the unscaled problem (the oracle)."""

from __future__ import annotations

import json
import re
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import h5py
import numpy as np
import pytest
import scipy.io
import scipy.sparse as sp
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

import meicp
from meicp.core.errors import ProblemError
from meicp.eicp.problem import EiCPProblem, certify_pair
from meicp.io import problem_files
from meicp.io.problem_files import read_problem
from meicp.lcp.problem import LCPProblem

from .conftest import ROOT, meicp_cmd, run

#: seed 002 §6: a P-matrix (tridiag(−1, 2, −1)) whose LCP with q = (−2, 4, −4) has x = (1, 0, 2)
M3 = np.array([[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 2.0]])
Q3 = np.array([-2.0, 4.0, -4.0])
X3 = np.array([1.0, 0.0, 2.0])
#: docs/design.md §4.4: EiCP(A, I) has exactly the three eigenvalues −1, −2, −(3 + √5)/2
A2 = -np.array([[1.0, 1.0], [1.0, 2.0]])
LAMS2 = np.array([-1.0, -2.0, -(3 + 5 ** 0.5) / 2])


def _bad_csr(column: int, n: int = 3) -> sp.csr_matrix:
    """tridiag(−1, 2, −1) with its second stored column index replaced (SciPy's constructor
    does not check index ranges; compiled code then reads outside the arrays)."""
    S = sp.csr_matrix(np.array([[2.0, -1, 0], [-1, 2, -1], [0, -1, 2]]))
    indices = S.indices.copy()
    indices[1] = column
    return sp.csr_matrix((S.data, indices, S.indptr), shape=(n, n))


def _decreasing_indptr() -> sp.csr_matrix:
    S = sp.csr_matrix(M3)
    indptr = S.indptr.copy()
    indptr[1], indptr[2] = indptr[2], indptr[1]
    return sp.csr_matrix((S.data, S.indices, indptr), shape=(3, 3))


def _coo_out_of_range() -> sp.coo_matrix:
    """A COO matrix whose row index 7 lies outside its 3 rows (set after construction)."""
    A = sp.coo_matrix(M3)
    A.row = A.row.copy()
    A.row[0] = 7
    return A


def _graded(scale_rows):
    D = np.diag(scale_rows)
    return D @ M3, D @ Q3


# ---------------------------------------------------------------------------------------
# API: bad arguments are a ProblemError naming the argument
# ---------------------------------------------------------------------------------------

API_ERRORS = [
    ("lcp-tol-negative", lambda: meicp.solve_lcp(M3, Q3, tol=-1), r"^tol must lie in \(0, 0.01\]"),
    ("lcp-tol-inf", lambda: meicp.solve_lcp(M3, Q3, tol=np.inf, method="enumerate"), r"^tol must lie in"),
    ("lcp-tol-nan", lambda: meicp.solve_lcp(M3, Q3, tol=np.nan), r"^tol must lie in"),
    ("lcp-tol-0.9", lambda: meicp.solve_lcp(M3, Q3, tol=0.9, method="enumerate"), r"^tol must lie in"),
    ("lcp-tol-string", lambda: meicp.solve_lcp(M3, Q3, tol="1e-8"), r"^tol must be a real number"),
    ("lcp-max-iter-fraction", lambda: meicp.solve_lcp(M3, Q3, method="pgs", max_iter=1.5),
     r"^max_iter must be an integer, got 1.5"),
    ("lcp-max-iter-zero", lambda: meicp.solve_lcp(M3, Q3, method="pgs", max_iter=0), r"^max_iter must be ≥ 1"),
    ("lcp-omega-nan", lambda: meicp.solve_lcp(M3, Q3, method="pgs", omega=np.nan), r"^omega must be a finite"),
    ("lcp-complex-M", lambda: meicp.solve_lcp(M3 + 1j * np.eye(3), Q3), r"^M is complex \(complex128\)"),
    ("lcp-complex-q", lambda: meicp.solve_lcp(M3, Q3 + 0j), r"^q is complex"),
    ("lcp-complex-sparse-M", lambda: meicp.solve_lcp(sp.csr_matrix(M3 * (1 + 1j)), Q3), r"^M is complex"),
    ("lcp-csr-column-1e8", lambda: meicp.solve_lcp(_bad_csr(10 ** 8), Q3),
     r"^M: column index 100000000 out of range \[0, 3\)"),
    ("lcp-csr-column-5-enumerate", lambda: meicp.solve_lcp(_bad_csr(5), Q3, method="enumerate"),
     r"^M: column index 5 out of range"),
    ("lcp-csr-negative-column", lambda: meicp.solve_lcp(_bad_csr(-1), Q3), r"^M: column index -1 out of range"),
    ("lcp-csr-decreasing-indptr", lambda: meicp.solve_lcp(_decreasing_indptr(), Q3), r"^M: indptr decreases at row"),
    ("lcp-coo-row-out-of-range", lambda: meicp.solve_lcp(_coo_out_of_range(), Q3), r"^M: row index 7 out of range"),
    ("lcp-nan-M", lambda: meicp.solve_lcp(np.where(np.eye(3) > 0, np.nan, M3), Q3), r"^M contains NaN or Inf"),
    ("lcp-strings", lambda: meicp.solve_lcp([["a", "b"], ["c", "d"]], [1, 2]), r"^M is not a numeric matrix"),
    ("lcp-not-square", lambda: meicp.solve_lcp(np.ones((2, 3)), [1, 2]), r"^M must be square"),
    ("lcp-q-length", lambda: meicp.solve_lcp(M3, [1.0, 2.0]), r"^q has length 2, expected 3"),
    ("lcp-empty", lambda: meicp.solve_lcp(np.zeros((0, 0)), []), r"^M is empty"),
    ("lcpproblem-complex", lambda: LCPProblem.from_data(M3.astype(complex), Q3), r"^M is complex"),
    ("classify-tol-negative", lambda: meicp.classify(M3, tol=-1), r"^tol must lie in"),
    ("classify-exact-limit-100", lambda: meicp.classify(M3, exact_limit=100), r"^exact_limit must be ≤ 20"),
    ("classify-exact-limit-fraction", lambda: meicp.classify(M3, exact_limit=1.7), r"^exact_limit must be an integer"),
    ("classify-dense-limit-huge", lambda: meicp.classify(M3, dense_limit=10 ** 9), r"^dense_limit must be ≤ 20000"),
    ("lcp-max-n-huge", lambda: meicp.solve_lcp(M3, Q3, method="enumerate", max_n=40), r"^max_n must be ≤ 26"),
    ("eicp-max-j-huge", lambda: meicp.solve_eicp(A2, np.eye(2), method="enumerate", max_j=40), r"^max_j must be ≤ 26"),
    ("classify-game-limit-negative", lambda: meicp.classify(M3, game_limit=-1), r"^game_limit must be ≥ 0"),
    ("classify-complex", lambda: meicp.classify(M3 * 1j), r"^M is complex"),
    ("classify-csr-column-1e8", lambda: meicp.classify(_bad_csr(10 ** 8)), r"^M: column index 100000000"),
    ("game-complex", lambda: meicp.game_value(M3 + 1j), r"^M is complex"),
    ("eicp-tol-negative", lambda: meicp.solve_eicp(A2, np.eye(2), tol=-1), r"^tol must lie in"),
    ("eicp-lam-min-nan", lambda: meicp.solve_eicp(A2, np.eye(2), lam_min=np.nan),
     r"^lam_min must be a finite number, got nan"),
    ("eicp-lam-min-inf", lambda: meicp.solve_eicp(A2, np.eye(2), lam_min=-np.inf), r"^lam_min must be a finite"),
    ("eicp-lam-min-string", lambda: meicp.solve_eicp(A2, np.eye(2), lam_min="0"), r"^lam_min must be a real number"),
    ("eicp-lam-max-below", lambda: meicp.solve_eicp(A2, np.eye(2), lam_min=1.0, lam_max=0.0, method="enumerate"),
     r"^lam_max = 0.0 is below lam_min = 1.0"),
    ("eicp-target-nan", lambda: meicp.solve_eicp(A2, np.eye(2), method="active-set", target=np.nan),
     r"^target must be a finite number"),
    ("eicp-nev-zero", lambda: meicp.solve_eicp(A2, np.eye(2), method="active-set", nev=0), r"^nev must be ≥ 1"),
    ("eicp-nev-fraction", lambda: meicp.solve_eicp(A2, np.eye(2), method="active-set", nev=2.5),
     r"^nev must be an integer"),
    ("eicp-give-up-zero", lambda: meicp.solve_eicp(A2, np.eye(2), method="active-set", give_up_after=0),
     r"^give_up_after must be ≥ 1"),
    ("eicp-give-up-text", lambda: meicp.solve_eicp(A2, np.eye(2), method="active-set", give_up_after="x"),
     r"^give_up_after must be an integer"),
    ("eicp-J-fraction", lambda: meicp.solve_eicp(A2, np.eye(2), J=[1.7]), r"^J has a non-integer index 1.7"),
    ("eicp-J-out-of-range", lambda: meicp.solve_eicp(A2, np.eye(2), J=[0, 5]), r"^J has index 5 out of range"),
    ("eicp-J-repeated", lambda: meicp.solve_eicp(A2, np.eye(2), J=[1, 1]), r"^J repeats index 1"),
    ("eicp-J-nan", lambda: meicp.solve_eicp(A2, np.eye(2), J=[np.nan]), r"^J has a non-integer index nan"),
    ("eicp-complex-A", lambda: meicp.solve_eicp(A2 + 0j, np.eye(2)), r"^A is complex"),
    ("eicp-complex-B", lambda: meicp.solve_eicp(A2, np.eye(2) * 1j), r"^B is complex"),
    ("eicp-zero-B", lambda: meicp.solve_eicp(A2, np.zeros((2, 2)), method="semismooth"), r"^B is zero"),
    ("eicp-csr-column-1e8", lambda: meicp.solve_eicp(_bad_csr(10 ** 8), sp.eye(3, format="csr")),
     r"^A: column index 100000000"),
    ("eicp-shapes", lambda: meicp.solve_eicp(M3, np.eye(2)), r"^A and B must have the same shape"),
    ("eicp-x0-nan", lambda: meicp.solve_eicp(A2, np.eye(2), method="semismooth", x0=[np.nan, 1.0]),
     r"^x0 must be a finite vector"),
    ("eicp-lam0-inf", lambda: meicp.solve_eicp(A2, np.eye(2), method="semismooth", lam0=np.inf),
     r"^lam0 must be a finite number"),
    ("eicpproblem-J-fraction", lambda: EiCPProblem.from_data(A2, np.eye(2), J=[0.5]), r"^J has a non-integer index"),
]


@pytest.mark.parametrize("call, pattern", [c[1:] for c in API_ERRORS], ids=[c[0] for c in API_ERRORS])
def test_api_refuses_bad_arguments(call, pattern):
    with pytest.raises(ProblemError, match=pattern):
        call()


# ---------------------------------------------------------------------------------------
# API: bad scaling gets the true answer or an honest failure, never a false claim
# ---------------------------------------------------------------------------------------

def test_lcp_scaled_beyond_double_precision_is_out_of_range_not_infeasible():
    """M·1e300, q·1e-300 (a P-matrix: a solution exists, x = 1e-600·(1, 0, 2) underflows).
    Before: enumeration "proved" there is no solution."""
    r = meicp.solve_lcp(M3 * 1e300, Q3 * 1e-300, method="enumerate")
    assert r.status == "out_of_range" and not r.success and "has a solution" in r.message
    assert "support [0, 2]" in r.message
    r = meicp.solve_lcp(M3 * 1e300, Q3 * 1e-300)  # auto: every method fails, none claims a proof
    assert not r.success and r.status != "infeasible" and r.attempts[-1][1] == "out_of_range"
    r = meicp.solve_lcp(M3 * 1e-300, Q3 * 1e300, method="enumerate")  # x = 1e600·(1, 0, 2) overflows
    assert r.status == "out_of_range"


@pytest.mark.parametrize("scale", [1e150, 1e-150, 1e-300])
def test_lcp_scaled_within_range_is_solved(scale):
    r = meicp.solve_lcp(M3 * scale, Q3, method="enumerate")
    assert r.success and np.allclose(r.x * scale, X3, rtol=1e-12)


def test_lcp_row_scaled_by_1e300_is_held_row_by_row():
    """A row scaled by 1e-300: with one global certificate scale, x = 0 on that row passed
    (w = −1e-300 "≈ 0"); row by row it does not, and the true solution is found."""
    Mg, qg = _graded([1.0, 1e-300, 1.0])
    for method in ("enumerate", "lemke", "auto"):
        r = meicp.solve_lcp(Mg, qg, method=method)
        assert r.success and np.allclose(r.x, X3), (method, r.summary())
    from meicp.lcp.problem import certify, LCPResult

    wrong = certify(LCPProblem.from_data(*_graded([1.0, 1e-300, 1e-300])), LCPResult(), np.array([1.0, 0.0, 0.0]))
    assert not wrong.success  # w = (0, 1e-300, −4e-300): the last row is violated by 100 %


def test_loose_certificate_no_longer_accepts_w_minus_2():
    """tol = 0.9 'solved' with w = −2 before; 1e-2 is the loosest accepted and gives x = (1, 0, 2)."""
    r = meicp.solve_lcp(M3, Q3, tol=1e-2, method="enumerate")
    assert r.success and np.allclose(r.x, X3) and r.w.min() >= 0


def test_classify_is_scale_invariant_and_tol_is_checked():
    """A symmetric Z-matrix scaled by 1e300 or 1e-300 is classified as unscaled (classify
    with tol = −1 called it neither symmetric nor Z before: now an error, above)."""
    ref = meicp.classify(M3).classes()
    for s in (1e300, 1e-300):
        got = meicp.classify(M3 * s).classes()
        assert got == ref and got["symmetric"] and got["z_matrix"] and got["m_matrix"]


def test_game_value_scales_with_the_matrix():
    g = meicp.game_value(M3 * 1e300)
    assert g.success and np.isclose(g.value / 1e300, 0.2, rtol=1e-9)


@pytest.mark.parametrize("a, b", [(1e300, 1e-300), (1e-300, 1e300)])
def test_eicp_lambda_beyond_double_precision_is_undecided_not_no_solution(a, b):
    """EiCP(A·a, I·b): λ = (a/b)·{−1, −2, −2.618}, beyond double precision.  Before: "no solution"."""
    r = meicp.solve_eicp(A2 * a, np.eye(2) * b, method="enumerate")
    assert r.status == "undecided" and not r.solutions
    assert "3 candidate(s) have λ beyond double precision" in r.message
    assert r.coverage["out_of_range"] == 3


@pytest.mark.parametrize("method", ["rayleigh", "active-set", "semismooth"])
def test_iterative_eicp_methods_under_extreme_scaling(method):
    """The iterative methods run on the pencil scaled to max|A| = max|B| = 1 and map λ back:
    beyond double precision an honest out_of_range (before: overflow warnings, PETSc error 77
    in active-set), within it the exact λ (1e300·λ of the unscaled pencil)."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no overflow on the way
        r = meicp.solve_eicp(A2 * 1e300, np.eye(2) * 1e-300, method=method)
        assert r.status == "out_of_range" and not r.solutions and "beyond double precision" in r.message
        r = meicp.solve_eicp(A2 * 1e150, np.eye(2) * 1e-150, method=method)
    assert r.success and all(np.isclose(s.lam / 1e300, LAMS2, rtol=1e-10).any() for s in r.solutions)


def test_eicp_scaled_within_range_is_solved():
    r = meicp.solve_eicp(A2 * 1e150, np.eye(2) * 1e-150, method="enumerate")
    assert r.success and np.allclose(np.sort([s.lam for s in r.solutions]) / 1e300, np.sort(LAMS2), rtol=1e-12)


def test_eicp_window_beyond_every_solution_is_a_true_proof():
    """lam_min = 1e300 is a legitimate EiCP window: no solution lies in it (a proof)."""
    r = meicp.solve_eicp(A2, np.eye(2), lam_min=1e300, method="enumerate")
    assert r.status == "no_solution" and "in [1e+300, None]" in r.message


@pytest.mark.parametrize("B", [np.diag([1.0, -1.0, 0.0]), np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 0.0]])],
                         ids=["indefinite-singular", "skew-singular"])
def test_semismooth_without_a_start_eigenvalue_is_a_failure_status(B):
    """Singular B with x0ᵀBx0 = 0: a ZeroDivisionError traceback before."""
    r = meicp.solve_eicp(M3, B, method="semismooth")
    assert r.status == "bad_start" and not r.success and "give lam0" in r.message


def test_an_option_value_petsc_cannot_use_is_named_as_such():
    """-meicp_as_eps_tol abc was reported as "PETSc error 63 … a different target may avoid it"."""
    r = meicp.solve_eicp(A2, np.eye(2), method="active-set", options={"eps_tol": "abc"})
    assert r.status == "petsc_error" and not r.success
    assert "Input string abc has no numeric value; check the -meicp_as_* options" in r.message
    assert "different target" not in r.message


def _scene_with_density(tmp_path: Path, layer: str, rho: float) -> Path:
    text = (ROOT / "data" / "scenes" / "two_layers.toml").read_text()
    blocks = text.split("[[layers]]")
    blocks = [re.sub(r"density = [0-9.e+-]+", f"density = {rho!r}", b) if f'name = "{layer}"' in b else b
              for b in blocks]
    path = tmp_path / f"rho_{layer}.toml"
    path.write_text("[[layers]]".join(blocks))
    return path


@pytest.mark.parametrize("layer, sigma", [("A", 0.32866195834394 / 1e-16), ("B", 0.33127976635687)])
def test_a_layer_of_density_1e16_keeps_its_mode(tmp_path, layer, sigma):
    """Density 1e-16 in one layer of two_layers.toml: before, enumeration returned no mode and
    analyze said STABLE (a proof), though σ ≈ 0.33/ρ (light bottom layer A) or σ ≈ 0.331
    (light top layer B) exists.  The enumeration of the scaled pencil finds it, certified
    row by row."""
    r = meicp.analyze(_scene_with_density(tmp_path, layer, 1e-16), method="enumerate")
    assert r.stable is False and r.eicp[0].status == "solved"
    assert len(r.modes) == 1 and np.isclose(r.modes[0].sigma, sigma, rtol=1e-9)
    assert r.modes[0].residual <= 1e-10


def test_row_wise_certificate_rejects_the_spurious_modes_of_a_graded_pencil(tmp_path):
    """Density 1e-12: seven spurious "modes" (row residual ≈ 1) passed the global certificate."""
    r = meicp.analyze(_scene_with_density(tmp_path, "A", 1e-12), method="enumerate")
    assert len(r.modes) == 1 and np.isclose(r.modes[0].sigma, 0.32866195834394e12, rtol=1e-9)


# ---------------------------------------------------------------------------------------
# Problem files
# ---------------------------------------------------------------------------------------

def _dat(M, q, extra: str = "") -> str:
    n = len(q)
    return (f"{n}\n0\n{n} {n}\n{n} {n}\n" + " ".join(repr(float(v)) for v in np.asarray(M).T.ravel()) + "\n"
            + " ".join(repr(float(v)) for v in q) + "\n" + extra)


def _h5_csr(path: Path, **members) -> Path:
    S = sp.csr_matrix(M3)
    fields = {"data": S.data, "indices": S.indices, "indptr": S.indptr, "shape": np.array(S.shape)}
    fields.update(members)
    with h5py.File(path, "w") as f:
        g = f.create_group("M")
        for key, value in fields.items():
            g[key] = value
        f["q"] = Q3
    return path


def _h5(path: Path, **datasets) -> Path:
    with h5py.File(path, "w") as f:
        for key, value in datasets.items():
            f[key] = value
    return path


def _write(path: Path, content) -> Path:
    (path.write_bytes if isinstance(content, bytes) else path.write_text)(content)
    return path


def _symlink(path: Path, target: str) -> Path:
    path.symlink_to(target)
    return path


def _fifo(path: Path) -> Path:
    import os

    os.mkfifo(path)  # reading it would block for ever
    return path


def _mat(path: Path, **variables) -> Path:
    scipy.io.savemat(path, variables)
    return path


def _column_index(value):
    S = sp.csr_matrix(M3)
    indices = S.indices.copy()
    indices[1] = value
    return indices


#: (id, file builder (tmp dir → path), names for read_problem, message pattern)
FILE_ERRORS = [
    ("dat-n-fraction", lambda d: _write(d / "a.dat", "3.7\n0\n" + _dat(M3, Q3)[2:]), ("M", "q"),
     r"a\.dat: n \(the problem size\) must be an integer, got '3\.7'"),
    ("dat-n-inf", lambda d: _write(d / "a.dat", "inf\n0\n3 3\n3 3\n"), ("M", "q"), r"n \(the problem size\) must be an integer, got 'inf'"),
    ("dat-n-1e300", lambda d: _write(d / "a.dat", "1e300\n0\n"), ("M", "q"), r"n \(the problem size\) = 1e300 is out of range"),
    ("dat-n-negative", lambda d: _write(d / "a.dat", "-3\n0\n"), ("M", "q"), r"n \(the problem size\) = -3 is out of range"),
    ("dat-binary-nul", lambda d: _write(d / "a.dat", b"3\n0\n\x00\x01\x02" * 10), ("M", "q"), r"a\.dat: binary data \(a NUL byte at offset 4\)"),
    ("dat-binary-garbage", lambda d: _write(d / "a.dat", bytes(range(128, 256)) * 4), ("M", "q"),
     r"a\.dat: expected a number for n \(the problem size\) at token 1"),
    ("dat-truncated", lambda d: _write(d / "a.dat", _dat(M3, Q3)[:-12]), ("M", "q"), r"a\.dat: file ends early: expected q"),
    ("dat-empty", lambda d: _write(d / "a.dat", ""), ("M", "q"), r"a\.dat: file ends early: expected n"),
    ("dat-nan-entry", lambda d: _write(d / "a.dat", _dat(M3, Q3).replace("2.0", "nan", 1)), ("M", "q"),
     r"a\.dat: M \(3x3, column-major\) has a non-finite entry \(nan\) at position 0"),
    ("dat-word", lambda d: _write(d / "a.dat", "2 0 2 2 2 2 1 x 1 1 -1 -1"), ("M", "q"), r"expected a number for M .* got 'x'"),
    ("dat-header-mismatch", lambda d: _write(d / "a.dat", "3\n0\n2 2\n2 2\n1 0 0 1\n1 1 1\n"), ("M", "q"),
     r"dense header 2x2/2x2 does not match n = 3"),
    ("dat-storage-type", lambda d: _write(d / "a.dat", "3\n7\n"), ("M", "q"), r"unknown storage type 7"),
    ("dat-block-column-index", lambda d: _write(d / "a.dat", "2\n1\n2 2\n1\n1 1\n2\n2\n2\n1\n0 1\n5\n0\n2 1 1 2\n-1 -1\n"),
     ("M", "q"), r"the block column index\[0\] = 5 is out of range \[0, 0\]"),
    ("dat-block-ends", lambda d: _write(d / "a.dat", "2\n1\n2 2\n1\n2 2\n1 1\n2\n"), ("M", "q"),
     r"the block row ends \[1, 1\] must increase strictly up to n = 2"),
    ("device-dev-zero", lambda d: Path("/dev/zero"), ("M", "q"), r"^/dev/zero: not a regular file"),
    ("symlink-to-dev-zero", lambda d: _symlink(d / "zero.dat", "/dev/zero"), ("M", "q"), r"zero\.dat: not a regular file"),
    ("fifo", lambda d: _fifo(d / "pipe.h5"), ("M", "q"), r"pipe\.h5: not a regular file"),
    ("directory", lambda d: d, ("M", "q"), r"not a regular file"),
    ("missing-file", lambda d: d / "missing.dat", ("M", "q"), r"missing\.dat: no such file"),
    ("unknown-suffix", lambda d: _write(d / "a.txt", "1"), ("M", "q"), r"unknown file type '\.txt'"),
    ("h5-csr-column-5", lambda d: _h5_csr(d / "a.h5", indices=_column_index(5)), ("M", "q"),
     r"a\.h5: CSR group 'M': column index 5 out of range \[0, 3\)"),
    ("h5-csr-column-1e8", lambda d: _h5_csr(d / "a.h5", indices=_column_index(10 ** 8)), ("M", "q"),
     r"CSR group 'M': column index 100000000 out of range"),
    ("h5-csr-decreasing-indptr", lambda d: _h5_csr(d / "a.h5", indptr=np.array([0, 4, 2, 7])), ("M", "q"),
     r"CSR group 'M': indptr decreases at row 1 \(4 then 2\)"),
    ("h5-csr-indptr-length", lambda d: _h5_csr(d / "a.h5", indptr=np.array([0, 2, 7])), ("M", "q"),
     r"indptr has length 3, expected 4"),
    ("h5-csr-indptr-end", lambda d: _h5_csr(d / "a.h5", indptr=np.array([0, 2, 5, 9])), ("M", "q"),
     r"indptr runs from 0 to 9 but there are 7 indices"),
    ("h5-csr-shape-negative", lambda d: _h5_csr(d / "a.h5", shape=np.array([-3, 3])), ("M", "q"),
     r"M/shape must be two nonnegative integers"),
    ("h5-csr-float-indices", lambda d: _h5_csr(d / "a.h5", indices=sp.csr_matrix(M3).indices + 0.5), ("M", "q"),
     r"M/indices must be an integer dataset"),
    ("h5-csr-missing-member", lambda d: _csr_without_indptr(d / "a.h5"), ("M", "q"),
     r"CSR group 'M' lacks \['indptr'\]"),
    ("h5-csr-complex-data", lambda d: _h5_csr(d / "a.h5", data=sp.csr_matrix(M3).data * 1j), ("M", "q"),
     r"a\.h5: M/data is complex"),
    ("h5-complex-M", lambda d: _h5(d / "a.h5", M=M3 + 1j, q=Q3), ("M", "q"), r"a\.h5: M is complex \(complex128\)"),
    ("h5-complex-q", lambda d: _h5(d / "a.h5", M=M3, q=Q3 * 1j), ("M", "q"), r"a\.h5: q is complex"),
    ("h5-string-M", lambda d: _h5(d / "a.h5", M=np.array([b"abc"]), q=Q3), ("M", "q"), r"M must be a real numeric dataset"),
    ("h5-3d-M", lambda d: _h5(d / "a.h5", M=np.ones((2, 2, 2)), q=Q3), ("M", "q"), r"M must have 0 or 1 or 2 dimensions"),
    ("h5-nan-M", lambda d: _h5(d / "a.h5", M=M3 * np.nan, q=Q3), ("M", "q"), r"a\.h5: M contains NaN or Inf"),
    ("h5-missing-q", lambda d: _h5(d / "a.h5", M=M3), ("M", "q"), r"a\.h5: no dataset 'q'"),
    ("h5-not-hdf5", lambda d: _write(d / "a.h5", "not hdf5"), ("M", "q"), r"a\.h5: not a readable HDF5 file"),
    ("h5-q-length", lambda d: _h5(d / "a.h5", M=M3, q=Q3[:2]), ("M", "q"), r"a\.h5: q has length 2, expected 3"),
    ("h5-J-fraction", lambda d: _h5(d / "a.h5", A=A2, B=np.eye(2), J=[1.7]), ("A", "B", "J"),
     r"a\.h5: J has a non-integer index 1\.7"),
    ("h5-A-B-shapes", lambda d: _h5(d / "a.h5", A=M3, B=np.eye(2)), ("A", "B", "J"), r"A and B differ in shape"),
    ("mat-empty", lambda d: _write(d / "a.mat", b""), ("A", "B", "J"), r"a\.mat: empty file, not a MATLAB \.mat file"),
    ("mat-garbage", lambda d: _write(d / "a.mat", b"MATLAB 5.0 MAT-file" + bytes(range(256)) * 2), ("A", "B", "J"),
     r"a\.mat: not a readable MATLAB \.mat file"),
    ("mat-complex-A", lambda d: _mat(d / "a.mat", A=A2 * 1j, B=np.eye(2)), ("A", "B", "J"), r"a\.mat: A is complex"),
    ("mat-J-fraction", lambda d: _mat(d / "a.mat", A=A2, B=np.eye(2), J=np.array([[1.7]])), ("A", "B", "J"),
     r"a\.mat: J has a non-integer index 1\.7"),
    ("mat-J-out-of-range", lambda d: _mat(d / "a.mat", A=A2, B=np.eye(2), J=np.array([[0.0, 4.0]])), ("A", "B", "J"),
     r"a\.mat: J has index 4 out of range \[0, 2\)"),
    ("mat-string-variable", lambda d: _mat(d / "a.mat", A="text", B=np.eye(2)), ("A", "B", "J"),
     r"a\.mat: A is a MATLAB char, not a numeric array"),
]


def _csr_without_indptr(path: Path) -> Path:
    with h5py.File(path, "w") as f:
        g = f.create_group("M")
        g["data"], g["indices"], g["shape"] = [1.0], [0], np.array([3, 3])
        f["q"] = Q3
    return path


@pytest.mark.parametrize("build, names, pattern", [c[1:] for c in FILE_ERRORS], ids=[c[0] for c in FILE_ERRORS])
def test_problem_files_refuse_hostile_content(tmp_path, build, names, pattern):
    with pytest.raises(ProblemError, match=pattern):
        read_problem(build(tmp_path), names=names)


def test_size_limits_apply_before_reading(tmp_path, monkeypatch):
    """A text file above MAX_TEXT_BYTES and a dataset above MAX_ENTRIES are refused from
    their size and metadata (the limits are lowered here; the defaults are 256 MiB, 2^28)."""
    monkeypatch.setattr(problem_files, "MAX_TEXT_BYTES", 64)
    with pytest.raises(ProblemError, match=r"larger than 64 bytes"):
        read_problem(_write(tmp_path / "a.dat", _dat(M3, Q3)))
    monkeypatch.setattr(problem_files, "MAX_TEXT_BYTES", 2 ** 20)
    monkeypatch.setattr(problem_files, "MAX_ENTRIES", 8)
    with pytest.raises(ProblemError, match=r"M has 9 entries, above the limit of 8"):
        read_problem(_h5(tmp_path / "a.h5", M=M3, q=Q3))
    with pytest.raises(ProblemError, match=r"n \(the problem size\) = 3 is out of range \[1, 2\]"):
        read_problem(_write(tmp_path / "b.dat", _dat(M3, Q3)))
    with pytest.raises(ProblemError, match=r"A has 9 entries"):
        read_problem(_mat(tmp_path / "a.mat", A=M3, B=np.eye(3)), names=("A", "B", "J"))


def test_a_byte_order_mark_and_integral_float_indices_are_accepted(tmp_path):
    data = read_problem(_write(tmp_path / "a.dat", b"\xef\xbb\xbf" + _dat(M3, Q3).encode()))
    assert np.array_equal(data["M"], M3) and np.array_equal(data["q"], Q3)
    data = read_problem(_mat(tmp_path / "a.mat", A=A2, B=np.eye(2), J=np.array([[1.0]])), names=("A", "B", "J"))
    assert data["J"].tolist() == [1]


# ---------------------------------------------------------------------------------------
# Subcommands: exit 2 with one message naming the flag or the file, exit 1 for an honest
# failure, no traceback (all cases run concurrently, each its own process)
# ---------------------------------------------------------------------------------------

def _files(d: Path) -> dict:
    out = {"seed.dat": _write(d / "seed.dat", _dat(M3, Q3)),
           "scaled.dat": _write(d / "scaled.dat", _dat(M3 * 1e300, Q3 * 1e-300)),
           "n37.dat": _write(d / "n37.dat", "3.7\n0\n" + _dat(M3, Q3)[2:]),
           "binary.dat": _write(d / "binary.dat", b"\x00\xff" * 64),
           "col5.h5": _h5_csr(d / "col5.h5", indices=_column_index(5)),
           "col1e8.h5": _h5_csr(d / "col1e8.h5", indices=_column_index(10 ** 8)),
           "complex.h5": _h5(d / "complex.h5", M=M3 + 1j * np.eye(3), q=Q3),
           "eicp.h5": _h5(d / "eicp.h5", A=A2, B=np.eye(2)),
           "eicp_scaled.h5": _h5(d / "eicp_scaled.h5", A=A2 * 1e300, B=np.eye(2) * 1e-300),
           "J17.mat": _mat(d / "J17.mat", A=A2, B=np.eye(2), J=np.array([[1.7]])),
           "empty.mat": _write(d / "empty.mat", b""),
           "zero.dat": _symlink(d / "zero.dat", "/dev/zero"),
           "two_layers.toml": ROOT / "data" / "scenes" / "two_layers.toml",
           "wide22.toml": _write(d / "wide22.toml", _two_layers(("nx = 5", "nx = 22"))),
           # 16 pairs (within the pair limit) on 464 retained DOFs: 6.5e12 flops, hours
           "deep16.toml": _write(d / "deep16.toml", _two_layers(("nx = 5", "nx = 16"), upper_rows=14)),
           # 16 pairs on an order-400 pencil: 4.2e12 flops, hours
           "eicp_deep16.h5": _h5(d / "eicp_deep16.h5", A=-np.eye(400), B=np.eye(400), J=np.arange(16)),
           # divergence born above σ = 0 near μ ≈ 494: no σ = 0 mode up to μ = 1000, μ_c = inf
           "born.toml": _write(d / "born.toml", _two_layers(("nx = 5", "nx = 6"), ("shear = 0.0", "shear = -0.5"),
                                                            ("friction = 3.0", "friction = 500.0"),
                                                            ('states = "slip+"', 'states = "slip-"'), upper_rows=6)),
           "never": d / "never"}  # an output directory no case may create
    return {k: str(v) for k, v in out.items()}


def _two_layers(*changes, upper_rows: int = 2) -> str:
    """two_layers.toml with (old, new) line edits and the upper layer's rows."""
    text = (ROOT / "data" / "scenes" / "two_layers.toml").read_text()
    for old, new in changes:
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    lower, upper = text.rsplit("rows = 2", 1)
    return f"{lower}rows = {upper_rows}{upper}"


#: (id, arguments with {file} placeholders, exit code, pattern in stderr (exit 2) or stdout)
CLI_CASES = [
    ("lcp-tol-negative", ["lcp", "{seed.dat}", "--tol", "-1"], 2, r"meicp lcp: error: argument --tol: the tolerance must lie in"),
    ("lcp-tol-inf-enumerate", ["lcp", "{seed.dat}", "--tol", "inf", "--method", "enumerate"], 2,
     r"argument --tol: the tolerance must lie in \(0, 0.01\] .*, got inf"),
    ("lcp-tol-word", ["lcp", "{seed.dat}", "--tol", "abc"], 2, r"argument --tol: not a number: 'abc'"),
    ("classify-exact-limit-100", ["classify", "{seed.dat}", "--exact-limit", "100"], 2,
     r"argument --exact-limit: the value must be ≤ 20, got 100"),
    ("classify-exact-limit-negative", ["classify", "{seed.dat}", "--exact-limit", "-1"], 2,
     r"argument --exact-limit: the value must be ≥ 0"),
    ("eicp-lam-min-nan", ["eicp", "{eicp.h5}", "--lam-min", "nan"], 2, r"argument --lam-min: the value must be a finite number, got nan"),
    ("eicp-lam-min-inf", ["eicp", "{eicp.h5}", "--lam-min", "inf"], 2, r"argument --lam-min: the value must be a finite"),
    ("eicp-target-nan", ["eicp", "{eicp.h5}", "--method", "active-set", "--target", "nan"], 2, r"argument --target:"),
    ("eicp-tol-zero", ["eicp", "{eicp.h5}", "--tol", "0"], 2, r"argument --tol: the tolerance must lie in"),
    ("lcp-csr-column-1e8", ["lcp", "{col1e8.h5}"], 2, r"CSR group 'M': column index 100000000 out of range \[0, 3\)"),
    ("classify-csr-column-1e8", ["classify", "{col1e8.h5}"], 2, r"column index 100000000 out of range"),
    ("lcp-csr-column-5-enumerate", ["lcp", "{col5.h5}", "--method", "enumerate"], 2, r"column index 5 out of range"),
    ("lcp-csr-column-5-auto", ["lcp", "{col5.h5}"], 2, r"column index 5 out of range"),
    ("lcp-complex", ["lcp", "{complex.h5}"], 2, r"complex\.h5: M is complex"),
    ("lcp-dev-zero", ["lcp", "/dev/zero"], 2, r"/dev/zero: not a regular file"),
    ("lcp-symlink-to-dev-zero", ["lcp", "{zero.dat}"], 2, r"zero\.dat: not a regular file"),
    ("lcp-n-fraction", ["lcp", "{n37.dat}"], 2, r"n37\.dat: n \(the problem size\) must be an integer, got '3\.7'"),
    ("lcp-binary", ["lcp", "{binary.dat}"], 2, r"binary\.dat: binary data"),
    ("eicp-J-fraction", ["eicp", "{J17.mat}"], 2, r"J17\.mat: J has a non-integer index 1\.7"),
    ("eicp-empty-mat", ["eicp", "{empty.mat}"], 2, r"empty\.mat: empty file"),
    ("lcp-scaled-1e300", ["lcp", "{scaled.dat}"], 1, r"enumerate: out_of_range .* has a solution"),
    ("lcp-scaled-1e300-json", ["lcp", "{scaled.dat}", "--json"], 1, r'"status": "out_of_range"'),
    ("eicp-scaled-1e300", ["eicp", "{eicp_scaled.h5}", "--method", "enumerate"], 1,
     r"enumerate: undecided, 0 solution\(s\) .* beyond double precision"),
    ("eicp-scaled-1e300-rayleigh", ["eicp", "{eicp_scaled.h5}", "--method", "rayleigh"], 1,
     r"rayleigh: out_of_range, 0 solution\(s\) .* λ = 2\^1995·λ̃ is beyond double precision"),
    ("lcp-seed-still-solves", ["lcp", "{seed.dat}"], 0, r"x = \[1\. 0\. 2\.\]"),
    # a negative number in exponent form is a value, not an unknown option (argparse: "expected one argument")
    ("eicp-target-minus-1e6", ["eicp", "{eicp.h5}", "--method", "active-set", "--target", "-1e6"], 0,
     r"active-set: solved, 1 solution"),
    ("eicp-target-minus-inf", ["eicp", "{eicp.h5}", "--method", "active-set", "--target", "-inf"], 2,
     r"argument --target: the value must be a finite number, got -inf"),
    ("solve-target-minus-1e6", ["solve", "{two_layers.toml}", "--method", "active-set", "--target", "-1E+6",
                                "--no-output", "-q"], 0, r"verdict +UNSTABLE"),
    # -o "" used to fall back to the default directory silently
    ("solve-output-empty", ["solve", "{two_layers.toml}", "-o", "", "-q"], 2,
     r"meicp solve: error: argument -o/--output: an empty path names no directory"),
    ("lattice-output-empty", ["lattice", "{two_layers.toml}", "-o", ""], 2,
     r"meicp lattice: error: argument -o/--output: an empty path names no directory"),
    # 2^22 supports (hours) used to start; refused before any work, nothing written
    ("solve-enumerate-22-pairs", ["solve", "{wide22.toml}", "--method", "enumerate", "-o", "{never}", "-q"], 2,
     r"meicp: error: method 'enumerate' visits all 2\^\|J\| supports: \|J\| = 22 complementarity pairs is "
     r"4,194,304 supports, past the limit of 16 pairs .*; use --method auto or --method active-set"),
    # 16 pairs passed the pair limit whatever the order (hours to days); refused by work
    ("solve-enumerate-16-pairs-deep", ["solve", "{deep16.toml}", "--method", "enumerate", "-o", "{never}", "-q"], 2,
     r"meicp: error: method 'enumerate' solves 2\^\|J\| dense eigen-problems of order up to r: \|J\| = 16, "
     r"r = 464 is about 6\.5e\+12 flops .* past the limit of 2e\+12 .*ENUMERATE_MAX_FLOPS\); use --method auto "
     r"or --method active-set, .* max_j=16"),
    ("eicp-enumerate-16-pairs-order-400", ["eicp", "{eicp_deep16.h5}", "--method", "enumerate"], 2,
     r"\|J\| = 16, r = 400 is about 4\.2e\+12 flops \(2\^\|J\|·r³, ~2\.33 h on one core\), past the limit"),
    ("eicp-all-16-pairs-order-400", ["eicp", "{eicp_deep16.h5}", "--all"], 2, r"r = 400 is about 4\.2e\+12 flops"),
    # μ_c = inf and an upper end inf were JSON null (unknown), then the string "inf"; now null
    # with a flag (format_version 2): the float inf of results.h5, without a string for a number
    ("solve-critical-friction-inf-json", ["solve", "{born.toml}", "--critical-friction", "--no-flutter", "--json",
                                          "--no-output", "-q"], 0,
     r'"critical_friction": \{\n\s*"value": null,\n\s*"found": false,\n\s*"lower": 1000\.0,\n\s*"upper": null,'
     r'(.|\n)*"value_infinite": 1,\n\s*"upper_infinite": 1\n'),
]


@pytest.fixture(scope="module")
def cli_outcomes(tmp_path_factory):
    files = _files(tmp_path_factory.mktemp("hostile_cli"))

    def one(case):
        args = [files[a[1:-1]] if a.startswith("{") else a for a in case[1]]
        return case[0], run(meicp_cmd() + args, timeout=120)

    with ThreadPoolExecutor(max_workers=4) as pool:
        return dict(pool.map(one, CLI_CASES), _files=files)


@pytest.mark.parametrize("name, code, pattern", [(c[0], c[2], c[3]) for c in CLI_CASES], ids=[c[0] for c in CLI_CASES])
def test_cli_subcommands_on_hostile_input(cli_outcomes, name, code, pattern):
    out = cli_outcomes[name]
    assert out.returncode == code, (out.stdout, out.stderr)
    assert "Traceback" not in out.stderr and "Warning" not in out.stderr, out.stderr
    text = out.stderr if code == 2 else out.stdout
    assert re.search(pattern, text), text
    if code == 2:  # one message: argparse's usage lines and one error line, or one error line
        errors = [line for line in out.stderr.splitlines() if "error:" in line]
        assert len(errors) == 1, out.stderr
    if name.endswith("-json"):
        data = json.loads(out.stdout)  # valid JSON: no NaN or Infinity literals
        assert data["success"] is (code == 0)
    if "{never}" in dict((c[0], c[1]) for c in CLI_CASES)[name]:
        assert not (Path(cli_outcomes["_files"]["never"])).exists()  # nothing half-written


# ---------------------------------------------------------------------------------------
# Properties: scalings from 1e-300 to 1e300 against the enumeration of the unscaled problem
# ---------------------------------------------------------------------------------------

_exponents = st.integers(min_value=-300, max_value=300)
_small = st.integers(min_value=2, max_value=4)


def _p_matrix(rng, n):
    """A random P-matrix: strictly row diagonally dominant with a positive diagonal."""
    M = rng.uniform(-1, 1, (n, n))
    np.fill_diagonal(M, np.abs(M).sum(axis=1) + rng.uniform(0.1, 1.0, n))
    return M


def _pow10(e) -> float:
    """10^e as a float64: inf or 0 beyond the range, no OverflowError."""
    with np.errstate(over="ignore", under="ignore"):
        return float(np.power(10.0, float(e)))


def _normal(*arrays) -> bool:
    """Finite, and no subnormal entry (those have lost digits: not the same problem)."""
    return all(np.all(np.isfinite(a)) and np.all((a == 0) | (np.abs(a) >= np.finfo(float).tiny)) for a in arrays)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(n=_small, seed=st.integers(0, 2 ** 31), em=_exponents, eq=_exponents,
       rows=st.lists(st.integers(-8, 8), min_size=4, max_size=4))
def test_lcp_enumeration_under_scaling_never_contradicts_the_oracle(n, seed, em, eq, rows):
    """LCP(D·q·10^eq, D·M·10^em) with a P-matrix M (a unique solution always exists) and row
    scalings D = 10^rows: the answer is the oracle's x·10^(eq−em) (the oracle: the same
    enumeration unscaled), or out_of_range when that is beyond double precision — never
    "infeasible", never another x."""
    rng = np.random.default_rng(seed)
    M, q = _p_matrix(rng, n), rng.uniform(-1, 1, n)
    D = 10.0 ** np.array(rows[:n], dtype=float)
    with np.errstate(over="ignore", under="ignore"):
        Ms, qs = D[:, None] * M * _pow10(em), D * q * _pow10(eq)
    assume(_normal(Ms, qs))
    oracle = meicp.solve_lcp(M, q, method="enumerate")
    assert oracle.success and len(oracle.solutions) == 1
    r = meicp.solve_lcp(Ms, qs, method="enumerate")
    assert r.status in ("solved", "out_of_range"), r.summary()
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):
        expected = np.where(oracle.x == 0, 0.0, oracle.x * _pow10(eq - em))
    if r.success:
        assert np.allclose(r.x, expected, rtol=1e-8, atol=1e-8 * np.abs(expected).max())
    else:  # only when x (or w = Mx + q, of size |q|) is beyond double precision
        assert abs(eq - em) + 2 * max(abs(e) for e in rows[:n]) > 280, (em, eq, rows)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(n=_small, seed=st.integers(0, 2 ** 31), ea=_exponents, eb=_exponents,
       mass=st.lists(st.integers(-16, 16), min_size=4, max_size=4))
def test_eicp_enumeration_under_scaling_never_contradicts_the_oracle(n, seed, ea, eb, mass):
    """EiCP(A·10^ea, B·10^eb) with symmetric A and a diagonal B = diag(10^mass) (graded like
    the densities of layers): with B positive definite a solution always exists, so the
    answer is never "no_solution"; every certified solution, mapped back (λ·10^(eb−ea)), is
    certified on the unscaled A, B as well; and when the scaled enumeration and the unscaled
    one (the oracle) are both complete (no unverified candidate, nothing out of range) they
    list the same λ."""
    rng = np.random.default_rng(seed)
    A = rng.uniform(-1, 1, (n, n))
    A = A + A.T
    B = np.diag(10.0 ** np.array(mass[:n], dtype=float))
    with np.errstate(over="ignore", under="ignore"):
        As, Bs = A * _pow10(ea), B * _pow10(eb)
    assume(_normal(As, Bs))
    r = meicp.solve_eicp(As, Bs, method="enumerate")
    assert r.status in ("solved", "undecided"), r.message
    unscaled = EiCPProblem.from_data(A, B)
    for s in r.solutions:
        with np.errstate(over="ignore", under="ignore"):  # two half steps: no subnormal on the way
            lam = s.lam * _pow10((eb - ea) / 2) * _pow10((eb - ea) / 2)
        if np.isfinite(lam) and lam != 0:
            assert certify_pair(unscaled, lam, s.x).residual <= 1e-8, (s.lam, lam)
    oracle = meicp.solve_eicp(A, B, method="enumerate")
    assert oracle.status in ("solved", "undecided"), oracle.message
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):
        ref = np.sort([s.lam for s in oracle.solutions]) * _pow10(ea - eb)
    complete = lambda res: res.status == "solved" and not res.coverage["unverified"] and not res.coverage["out_of_range"]
    if complete(r) and complete(oracle) and np.all(np.isfinite(ref)):
        got = np.sort([s.lam for s in r.solutions])
        assert got.size == ref.size and np.allclose(got, ref, rtol=1e-6, atol=1e-12 * np.abs(ref).max()), (got, ref)
