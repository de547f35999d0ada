"""The harness itself: conventions (errors, results, validation, options) and the
serial PETSc/SLEPc path, plus process-level checks of the 2-rank behaviour."""

import time

import numpy as np
import pytest
import scipy.sparse as sp

import meicp
from meicp.core import validation as v
from meicp.core.errors import ConvergenceError, MeicpError, ProblemError, SolverNotFound
from meicp.core.results import Result

from .conftest import meicp_cmd, mpirun, run


def test_exception_family():
    for cls in (ProblemError, ConvergenceError, SolverNotFound):
        assert issubclass(cls, MeicpError)
    assert issubclass(ProblemError, ValueError)
    err = SolverNotFound("foo", ["lemke", "enumerate"])
    assert "foo" in str(err) and "enumerate, lemke" in str(err)
    partial = Result(status="max_iterations")
    assert ConvergenceError("no", partial).result is partial
    assert meicp.ProblemError is ProblemError


def test_result_success_follows_status():
    r = Result()
    assert not r.success
    r.status = "solved"
    assert r.success
    r.status = "certificate_failed"
    assert not r.success


@pytest.mark.parametrize("bad, words", [
    (np.ones((2, 3)), "square"),
    (np.ones(3), "2-D"),
    (np.zeros((0, 0)), "empty"),
    (np.array([[1.0, np.nan], [0.0, 1.0]]), "NaN"),
    (sp.csr_matrix(np.array([[np.inf, 0.0], [0.0, 1.0]])), "NaN or Inf"),
    ([["a", "b"], ["c", "d"]], "numeric"),
])
def test_as_matrix_rejects(bad, words):
    with pytest.raises(ProblemError, match=words):
        v.as_matrix(bad, "M")


def test_as_matrix_names_the_argument():
    with pytest.raises(ProblemError, match=r"^A must be square"):
        v.as_matrix(np.ones((2, 3)), "A")


def test_as_vector():
    assert v.as_vector([[1], [2]], 2).shape == (2,)
    with pytest.raises(ProblemError, match="length 3, expected 2"):
        v.as_vector([1, 2, 3], 2)
    with pytest.raises(ProblemError, match="NaN"):
        v.as_vector([1, np.nan], 2)


def test_symmetry_and_spd():
    A = np.array([[2.0, -1.0], [-1.0, 2.0]])
    v.check_spd(A)
    v.check_spd(sp.diags([1.0, 2.0]).tocsr())
    with pytest.raises(ProblemError, match="symmetric"):
        v.check_symmetric(np.array([[1.0, 2.0], [0.0, 1.0]]))
    with pytest.raises(ProblemError, match="positive definite: smallest eigenvalue -1"):
        v.check_spd(np.array([[1.0, 2.0], [2.0, 1.0]]))
    with pytest.raises(ProblemError, match="diagonal entry 1"):
        v.check_spd(sp.diags([1.0, -2.0]).tocsr(), "M")
    # symmetric to a relative tolerance, not exactly
    v.check_symmetric(np.array([[1e6, 1.0], [1.0 + 1e-9, 1e6]]))


def test_index_sets():
    assert v.as_index_set(None, 3).tolist() == [0, 1, 2]
    assert v.as_index_set([2, 0], 3).tolist() == [0, 2]
    assert v.as_index_set(np.array([True, False, True]), 3).tolist() == [0, 2]
    with pytest.raises(ProblemError, match="index 3 out of range"):
        v.as_index_set([0, 3], 3)
    with pytest.raises(ProblemError, match="repeats index 1"):
        v.as_index_set([1, 1], 3)
    with pytest.raises(ProblemError, match="integer"):
        v.as_index_set([0.5], 3)


def test_options_precedence_and_cleanup():
    from meicp.petsc import import_petsc, import_slepc
    from meicp.petsc.options import OptionsScope

    PETSc, SLEPc = import_petsc(), import_slepc()
    db = PETSc.Options()
    db.setValue("tprec_eps_ncv", "24")  # as if given on the command line
    try:
        # an unread code default (e.g. a MUMPS option when the user picked another solver)
        # is not reported; an unread option of the user's is
        with OptionsScope("tprec_", {"eps_nev": 2, "eps_ncv": 10, "default_unread": 1},
                          {"eps_nev": 3, "bogus": 1}) as scope:
            eps = SLEPc.EPS().create(PETSc.COMM_SELF)
            eps.setOptionsPrefix("tprec_")
            eps.setFromOptions()
            nev, ncv, _ = eps.getDimensions()
            eps.destroy()
        assert (nev, ncv) == (3, 24)  # scene beats code default, command line beats both
        assert scope.unused == ["tprec_bogus"]
        assert not db.hasName("tprec_eps_nev") and not db.hasName("tprec_bogus")
        assert not db.hasName("tprec_default_unread")
        assert db.hasName("tprec_eps_ncv")  # not ours to delete
    finally:
        db.delValue("tprec_eps_ncv")


def test_reduced_pencil_solver_is_a_context_manager_that_keeps_its_options():
    """Options stay in the database for every solve and leave it with the solver; the ones
    no solve read are reported once, when it closes."""
    import scipy.sparse as sp

    from meicp.petsc import import_petsc
    from meicp.petsc.mat import mat_from_scipy
    from meicp.petsc.reduced_pencil import ReducedPencilSolver

    db = import_petsc().Options()
    n = 6
    A = mat_from_scipy(None, sp.diags(-np.arange(1.0, n + 1)))
    B = mat_from_scipy(None, sp.identity(n))
    try:
        with ReducedPencilSolver(A, B, symmetric=True, target=0.0, spurious=-1e3, nev=2, prefix="trp_",
                                 options={"eps_tol": 1e-11, "unread": 1}) as solver:
            for removed in (np.array([], dtype=np.int64), np.array([0])):
                assert not db.hasName("trp_eps_tol")  # only during a solve
                lams = [lam for lam, _, _ in solver.solve(removed)]
                assert max(lams) == pytest.approx(-1.0 if removed.size == 0 else -2.0)
            assert solver.unused_options == ["trp_unread"] and solver.solves == 2
        assert not db.hasName("trp_eps_tol") and not db.hasName("trp_unread")
    finally:
        A.destroy()
        B.destroy()


def test_serial_distributed_matrix_and_slepc_against_scipy():
    from meicp.petsc.mat import mat_from_scipy, mat_to_scipy
    from meicp.petsc.selfcheck import ghep_selfcheck, laplacian_rows

    r = ghep_selfcheck(None, nx=9, ny=7, nev=4)
    assert r["max_rel_error"] < 1e-10
    assert r["max_residual"] < 1e-8
    A = laplacian_rows(5, 4, 0, 20)
    assert abs(mat_to_scipy(mat_from_scipy(None, A)) - A).max() == 0


def test_info_command_runs():
    out = run(meicp_cmd() + ["info"])
    assert out.returncode == 0, out.stderr
    for word in ("petsc", "slepc", "mpi4py", "h5py", "petsc has MUMPS", "ranks"):
        assert word in out.stdout
    assert "3.18" in out.stdout


def test_cli_unknown_command_is_a_usage_error():
    out = run(meicp_cmd() + ["no-such-command"])
    assert out.returncode == 2 and "invalid choice" in out.stderr


def test_exception_on_one_rank_ends_the_run_promptly(tmp_path):
    """Rank 1 raises while rank 0 waits in a collective: the job must end in seconds."""
    script = tmp_path / "boom.py"
    script.write_text(
        "from mpi4py import MPI\n"
        "comm = MPI.COMM_WORLD\n"
        "if comm.rank == 1:\n"
        "    raise RuntimeError('boom on rank 1')\n"
        "comm.Barrier()\n")
    t0 = time.monotonic()
    out = run(mpirun(2) + [meicp_cmd()[0], "-m", "mpi4py", str(script)], timeout=60)
    assert out.returncode != 0
    assert "boom on rank 1" in out.stderr
    assert time.monotonic() - t0 < 30


def test_cli_error_on_one_rank_aborts_and_collective_error_prints_once(tmp_path):
    """The CLI's own handler: a ProblemError on every rank prints once and exits 2; a failure
    on one rank only aborts the job instead of hanging the other rank."""
    script = tmp_path / "cli_err.py"
    script.write_text(
        "import sys\n"
        "from mpi4py import MPI\n"
        "from meicp.cli import main as m\n"
        "from meicp.core.errors import ProblemError\n"
        "def fail(args):\n"
        "    if sys.argv[1] == 'all' or MPI.COMM_WORLD.rank == 1:\n"
        "        raise ProblemError('layers[1].density must be positive')\n"
        "    MPI.COMM_WORLD.Barrier()\n"
        "    return 0\n"
        "import meicp.cli.info as info\n"
        "info.run = fail\n"
        "sys.exit(m.main(['info']))\n")
    out = run(mpirun(2) + [meicp_cmd()[0], str(script), "all"], timeout=60)
    assert out.returncode == 2, out.stderr
    assert out.stderr.count("layers[1].density must be positive") == 1
    t0 = time.monotonic()
    out = run(mpirun(2) + [meicp_cmd()[0], str(script), "one"], timeout=60)
    assert out.returncode != 0
    assert "[rank 1]" in out.stderr and "layers[1].density" in out.stderr
    assert time.monotonic() - t0 < 30
