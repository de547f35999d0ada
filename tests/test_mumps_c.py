"""MUMPS through its C interface (meicp.petsc.mumps_c): the C structure matches the library
(MUMPS writes its version and default controls where the structure says); the complex factor
of the flutter search solves to rounding on one and two ranks; the Schur series of the
condensation equals the dense Schur complement at every σ, in any order of σ; MUMPS' errors
and refused controls are raised on every rank, not left as a wrong factor."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from meicp.petsc import mumps_c

pytestmark = pytest.mark.skipif(mumps_c.load("z")[0] is None or mumps_c.load("d")[0] is None, reason="no MUMPS C library of a known version")


def _system(n: int = 300, seed: int = 3):
    rng = np.random.default_rng(seed)
    M = sp.random(n, n, density=0.02, random_state=seed, format="csr")
    M = M + 1j * sp.random(n, n, density=0.02, random_state=seed + 1, format="csr")
    M = (M + sp.diags(4.0 + 1j * rng.standard_normal(n))).tocsr()
    return M, rng.standard_normal(n) + 1j * rng.standard_normal(n)


def test_the_structure_is_the_libraries_own():
    """After JOB = −1 MUMPS has written its version string and its default controls into the
    structure: were a field before them misplaced, neither would read back right."""
    with mumps_c.ComplexFactor(None, sp.identity(2, dtype=complex, format="csr"), 0, 2) as f:
        assert f.version.startswith(mumps_c.VERSIONS)
        assert f.id.icntl[6] == 2 and f.id.icntl[17] == 3  # what meicp set, after MUMPS' defaults
        assert f.id.infog[0] == 0
    assert mumps_c.ctypes_size() == 8360  # sizeof(ZMUMPS_STRUC_C) in zmumps_c.h of MUMPS 5.5.1


@pytest.mark.parametrize("icntl, cntl", [({}, {}), ({15: -2}, {}), ({35: 2}, {7: 1e-12})])
def test_a_complex_system_is_solved_to_rounding(icntl, cntl):
    M, b = _system()
    with mumps_c.ComplexFactor(None, M, 0, M.shape[0], icntl=icntl, cntl=cntl) as f:
        x = f.solve(b)
        assert f.flops > 0
    assert np.linalg.norm(M @ x - b) <= 1e-12 * np.linalg.norm(b)
    x_ref = sp.linalg.spsolve(M.tocsc(), b)
    assert np.linalg.norm(x - x_ref) <= 1e-10 * np.linalg.norm(x_ref)


def test_a_singular_matrix_raises_the_mumps_error():
    M = sp.csr_matrix(np.array([[1.0, 2.0], [2.0, 4.0]], dtype=complex))
    with pytest.raises(mumps_c.MumpsError, match="INFOG"):
        mumps_c.ComplexFactor(None, M, 0, 2)


@pytest.mark.mpi(min_size=2)
def test_two_ranks_solve_what_one_does(comm):
    from meicp.petsc.mat import ownership

    M, b = _system(401)  # an odd order: uneven rows per rank
    lo, hi = ownership(M.shape[0], comm.Get_rank(), comm.Get_size())
    with mumps_c.ComplexFactor(comm, M[lo:hi], lo, M.shape[0]) as f:
        x = np.concatenate(comm.allgather(f.solve(b[lo:hi])))
    assert np.linalg.norm(M @ x - b) <= 1e-12 * np.linalg.norm(b)
    M2 = sp.csr_matrix(np.array([[1.0, 2.0], [2.0, 4.0]], dtype=complex))
    with pytest.raises(mumps_c.MumpsError):  # on both ranks: none is left waiting
        mumps_c.ComplexFactor(comm, M2[comm.Get_rank():comm.Get_rank() + 1], comm.Get_rank(), 2)


@pytest.mark.parametrize("options, match", [
    ({"st_mat_mumps_icntl_18": 0}, r"ICNTL\(18\) of the complex MUMPS factor of the flutter search is set by meicp"),
    ({"st_mat_mumps_icntl_99": 1}, r"MUMPS has no ICNTL\(99\)"),
    ({"st_mat_mumps_cntl_16": 0.1}, r"MUMPS has no CNTL\(16\)"),
    ({"st_mat_mumps_icntl_14": "lots"}, r"is not an integer"),
])
def test_hostile_factor_options_name_the_option(options, match):
    """A control the interface owns, one MUMPS does not have, or a value of the wrong kind is
    a ProblemError naming it, before MUMPS reads anything."""
    from meicp.core.errors import ProblemError
    from meicp.petsc.flutter import SlidingPencilOps, complex_shift_solve
    from meicp.petsc.mat import mat_from_scipy

    M, _ = _system(40)
    A = mat_from_scipy(None, (M.real + M.real.T).tocsr())
    B = mat_from_scipy(None, sp.identity(40, format="csr"))
    try:
        with SlidingPencilOps(A, B) as ops, pytest.raises(ProblemError, match=match):
            complex_shift_solve(ops, 1.0 + 0.5j, nev=1, ncv=8, options=options)
    finally:
        A.destroy()
        B.destroy()


def _bordered(n: int = 60, k: int = 8, seed: int = 5):
    """H(σ) = [[K + σM, Pᵀ], [P, 0]] (K SPD, M diagonal): symmetric indefinite, as the
    condensation's bordered matrix; Schur rows: k of the first block and the k extra rows."""
    rng = np.random.default_rng(seed)
    G = sp.random(n, n, density=0.1, random_state=seed, format="csr")
    K = (G @ G.T + sp.diags(np.full(n, 2.0))).tocsr()
    M = sp.diags(rng.uniform(0.5, 2.0, n))
    J = np.sort(rng.choice(n, k, replace=False))
    P = sp.csr_matrix((rng.standard_normal(k), (np.arange(k), J)), shape=(k, n))
    H0 = sp.bmat([[K, P.T], [P, None]], format="csr")
    H1 = sp.bmat([[M, sp.csr_matrix((n, k))], [sp.csr_matrix((k, n)), None]], format="csr")
    pattern = (abs(H0) + abs(H1)).tocsr()
    pattern.sort_indices()
    r = np.repeat(np.arange(n + k), np.diff(pattern.indptr))

    def on(X):  # X's values on the union pattern, explicit zeros kept
        values = np.asarray(X.tocsr()[r, pattern.indices]).ravel()
        return sp.csr_matrix((values, pattern.indices.copy(), pattern.indptr.copy()), shape=pattern.shape)
    return on(H0), on(H1), np.concatenate([J, n + np.arange(k)])


def dense_schur_of(H: sp.csr_matrix, rows: np.ndarray) -> np.ndarray:
    D = H.toarray()
    rest = np.setdiff1d(np.arange(D.shape[0]), rows)
    return D[np.ix_(rows, rows)] - D[np.ix_(rows, rest)] @ np.linalg.solve(D[np.ix_(rest, rest)], D[np.ix_(rest, rows)])


def _series_matches(comm):
    H0, H1, rows = _bordered()
    assert np.array_equal(H0.indices, H1.indices)
    with mumps_c.SchurSeries(comm, H0, H1, rows) as series:
        for sigma in (0.3, 0.0, 2.0, 0.3):  # a refactorisation, not a fresh analysis, after the first
            S = series(sigma)
            ref = dense_schur_of(H0 + sigma * H1, rows)
            assert np.abs(S - ref).max() <= 1e-12 * np.abs(ref).max()
            assert np.array_equal(S, S.T)


def test_the_schur_series_is_the_dense_schur_complement_at_every_sigma():
    _series_matches(None)


@pytest.mark.mpi(min_size=2)
def test_the_schur_series_on_two_ranks(comm):
    _series_matches(comm)


def _quadratic_series_matches(comm):
    """With H₂ the series factors H₀ + σH₁ + σ²H₂ (the damped condensation's quadratic pencil)."""
    H0, H1, rows = _bordered()
    H2 = H1.copy()
    H2.data = np.abs(H2.data) * 0.5
    with mumps_c.SchurSeries(comm, H0, H1, rows, H2=H2) as series:
        for lam in (0.4, 0.0, 1.5):
            S = series(lam)
            ref = dense_schur_of(H0 + lam * H1 + lam * lam * H2, rows)
            assert np.abs(S - ref).max() <= 1e-12 * np.abs(ref).max()


def test_the_quadratic_schur_series_is_the_dense_schur_complement():
    _quadratic_series_matches(None)


@pytest.mark.mpi(min_size=2)
def test_the_quadratic_schur_series_on_two_ranks(comm):
    _quadratic_series_matches(comm)


def test_the_schur_series_refuses_two_patterns():
    H0, H1, rows = _bordered()
    H1 = H1.copy()
    H1.eliminate_zeros()
    with pytest.raises(ValueError, match="one pattern"):
        mumps_c.SchurSeries(None, H0, H1, rows)


def test_without_dmumps_the_series_falls_back_to_petsc(monkeypatch):
    """Where no DMUMPS of a known version loads, schur_series makes one PETSc factorisation
    per σ: the same Schur complements."""
    from meicp.petsc import schur

    H0, H1, rows = _bordered()
    with schur.schur_series(None, H0, H1, rows) as direct:
        expected = [direct(s) for s in (0.0, 0.7)]
    real_load = mumps_c.load
    monkeypatch.setattr(mumps_c, "load", lambda arith="z": (None, "none here") if arith == "d" else real_load(arith))
    with schur.schur_series(None, H0, H1, rows) as fallback:
        assert not isinstance(fallback, mumps_c.SchurSeries)
        for S, sigma in zip(expected, (0.0, 0.7)):
            assert np.abs(fallback(sigma) - S).max() <= 1e-12 * np.abs(S).max()
    H2 = H1.copy()
    H2.data = np.abs(H2.data)
    with schur.schur_series(None, H0, H1, rows, H2) as fallback:
        ref = dense_schur_of(H0 + 0.7 * H1 + 0.49 * H2, rows)
        assert np.abs(fallback(0.7) - ref).max() <= 1e-12 * np.abs(ref).max()


def _interior_matches(comm):
    """The interior block H_II (every row not a Schur row) on the series' own instance: its
    inertia, full rank with a diagonal shift, is the dense one at shifts between the pencil's
    eigenvalues, and its solves are the dense ones (a vector or a block, after a block-low-rank
    factorisation too), the Schur rows of the solution 0."""
    import scipy.linalg as sl

    H0, H1, rows = _bordered()
    n = H0.shape[0]
    rest = np.setdiff1d(np.arange(n), rows)
    K, M = H0.toarray()[np.ix_(rest, rest)], H1.toarray()[np.ix_(rest, rest)]
    lam = sl.eigh(K, M, eigvals_only=True)
    host = comm is None or comm.Get_rank() == 0
    shift = np.zeros(n)
    shift[rest] = -1e-6 * np.abs(np.diag(K))
    b = np.random.default_rng(8).standard_normal((n, 2))
    # the condenser's own controls: block low rank chosen at the analysis, switched off for the
    # exact factorisations only
    with mumps_c.SchurSeries(comm, H0, H1, rows, defaults={35: 2}, cntl={7: 1e-14}) as series:
        for t, count in ((0.5 * lam[0], 0), (0.5 * (lam[2] + lam[3]), 3)):
            negative, null = series.factor(-t, diagonal=shift, exact=True)
            dense = K - t * M + np.diag(shift[rest])
            assert negative == count == int((np.linalg.eigvalsh(dense) < 0).sum()) and null == 0
            assert series.factored == (-t, True, True)
            x = series.solve(b if host else None)
            if host:
                assert np.abs(x[rest] - np.linalg.solve(dense, b[rest])).max() <= 1e-10 * np.abs(x).max()
                assert not x[rows].any()
            else:
                assert x is None
        series.factor(0.3)  # the series' own controls again (block low rank)
        x = series.solve(b[:, 0] if host else None)
        if host:
            assert x.shape == (n,)
            assert np.abs(x[rest] - np.linalg.solve(K + 0.3 * M, b[rest, 0])).max() <= 1e-10 * np.abs(x).max()
        shift[rows[-1]] = 1.0  # an extra row: no diagonal entry in the pattern
        with pytest.raises(ValueError, match="no diagonal entry"):
            series.factor(0.0, diagonal=shift)


def test_the_series_interior_inertia_and_solves():
    _interior_matches(None)


@pytest.mark.mpi(min_size=2)
def test_the_series_interior_inertia_and_solves_on_two_ranks(comm):
    _interior_matches(comm)


def test_a_library_of_another_version_is_not_loaded(monkeypatch):
    """A MUMPS whose structure may differ from MUMPS_STRUC_C is refused by load() with its
    version named, so the callers fall back (PETSc's Schur complements, the real 2n form)
    instead of raising later."""
    from meicp.petsc import schur

    monkeypatch.setattr(mumps_c, "_LIBS", {})
    monkeypatch.setattr(mumps_c, "_version_of", lambda entry: "5.7.3")
    entry, why = mumps_c.load("d")
    assert entry is None and "5.7.3" in why and "5.5" in why
    H0, H1, rows = _bordered()
    with schur.schur_series(None, H0, H1, rows) as fallback:
        assert not isinstance(fallback, mumps_c.SchurSeries)
