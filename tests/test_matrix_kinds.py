"""Matrix kinds by dispatch (``meicp.core.matrix``): every operation gives the same on a NumPy
array, a SciPy CSR matrix and a PETSc Mat (registered by ``meicp.petsc.mat``), and the
PETSc-based methods join the registries of ``solve_eicp`` / ``solve_lcp`` when meicp is
imported, without starting PETSc."""

import sys

import numpy as np
import pytest
import scipy.sparse as sp

from meicp.core import matrix
from meicp.core.errors import MeicpError, PetscSolveError, ProblemError

from .conftest import run


@pytest.fixture
def kinds():
    from meicp.petsc.mat import mat_from_scipy

    dense = np.array([[4.0, -1.0, 0.0], [-1.0, 3.0, 2.5], [0.0, 2.5, -7.0]])
    mat = mat_from_scipy(None, sp.csr_matrix(dense))
    yield {"ndarray": dense, "csr": sp.csr_matrix(dense), "petsc": mat}
    mat.destroy()


def test_every_operation_agrees_across_kinds(kinds):
    x = np.array([1.0, -2.0, 0.5])
    dense = kinds["ndarray"]
    for kind, M in kinds.items():
        assert matrix.is_petsc_mat(M) == (kind == "petsc")
        assert tuple(matrix.matrix_shape(M)) == (3, 3)
        assert matrix.matrix_comm(M) is None  # one rank: the canonical serial comm
        assert np.array_equal(matrix.to_dense(M), dense)
        assert np.array_equal(matrix.to_scipy(M).toarray(), dense)
        assert np.allclose(matrix.matvec(M, x), dense @ x)
        assert matrix.max_abs_entry(M) == 7.0
        assert np.array_equal(matrix.row_max_abs(M), [4.0, 3.0, 7.0])
        assert matrix.is_symmetric(M, 1e-12)
        checked = matrix.checked_matrix(M, "M")  # a PETSc Mat is checked in place, not copied
        assert checked is M if kind == "petsc" else np.array_equal(matrix.to_dense(checked), dense)
        scaled = matrix.ldexp(M, 3)
        assert np.array_equal(matrix.to_dense(scaled), 8 * dense) and scaled is not M
        matrix.release(scaled)


def test_a_petsc_mat_is_checked_like_the_others(kinds):
    from meicp.petsc.mat import mat_from_scipy

    bad = mat_from_scipy(None, sp.csr_matrix(np.array([[1.0, np.nan], [0.0, 1.0]])))
    try:
        with pytest.raises(ProblemError, match="M contains NaN or Inf"):
            matrix.checked_matrix(bad, "M")
    finally:
        bad.destroy()


def test_petsc_errors_become_meicps_own():
    from meicp.petsc import import_petsc
    from meicp.petsc.options import petsc_errors

    PETSc = import_petsc()
    A = PETSc.Mat().createAIJ(2)  # never assembled: PETSc refuses to multiply by it
    x, y = PETSc.Vec().createSeq(2), PETSc.Vec().createSeq(2)
    try:
        with pytest.raises(PetscSolveError) as caught:
            with petsc_errors("a test"):
                A.mult(x, y)
    finally:
        for obj in (A, x, y):
            obj.destroy()
    assert isinstance(caught.value, MeicpError) and caught.value.ierr == 73  # PETSC_ERR_ARG_WRONGSTATE
    assert str(caught.value) == f"PETSc error 73 in a test: {caught.value.line}"
    assert "unassembled" in caught.value.line and not caught.value.line.startswith("[")


def test_importing_meicp_registers_the_petsc_kind_and_methods_without_starting_petsc():
    out = run([sys.executable, "-c",
               "import sys, meicp\n"
               "from meicp.eicp.solve import available_methods as e\n"
               "from meicp.lcp.solve import available_methods as l\n"
               "print('petsc4py' in sys.modules, e(), l())"])
    assert out.returncode == 0, out.stderr
    assert out.stdout.split()[0] == "False"
    for name in ("active-set", "semismooth", "newton", "tao"):
        assert f"'{name}'" in out.stdout
