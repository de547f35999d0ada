"""Flutter of steady sliding (docs/flutter.md): the verdict, the dense path against an
independent QZ, the large-scale search forced on small scenes, the residual gate, symmetry,
borderline pairs, grazing branches, hostile values of the new keyword and scene key."""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest
import scipy.linalg as sl

import meicp
from meicp.contact import flutter as fl
from meicp.contact import flutter_proxy as fp
from meicp.contact import proxy as strip
from meicp.contact.problem import pencil
from meicp.contact.result import growth_frequency
from meicp.core import limits
from meicp.core.errors import ProblemError
from meicp.examples import two_layer_scene
from meicp.io.scene import scene_from_dict
from meicp.core.matrix import to_dense

from .conftest import ROOT, meicp_cmd, run
from .helpers import interface_chain_scene
from .test_damping import damped

SCENES = ROOT / "data" / "scenes"


def lattice(nx: int, rows: tuple[int, int], mu: float, states="slip+", *, shear: float = 0.0, solver=None):
    """Two layers (k = 1 / 5, ρ = 1 / 2) on a rough base, top fixed, sides free."""
    d = {"lattice": {"nx": nx, "spacing": 1.0, "shear": shear},
         "layers": [{"name": "A", "rows": rows[0], "stiffness": 1.0, "density": 1.0},
                    {"name": "B", "rows": rows[1], "stiffness": 5.0, "density": 2.0}],
         "boundary": {"top": "fixed", "bottom": "contact"},
         "contact": {"friction": mu, "states": states}}
    if solver:
        d["solver"] = solver
    return scene_from_dict(d)


def qz_fastest(scene):
    """Growth rate and frequency of the fastest non-real σ of the sliding pencil, by
    scipy.linalg.eig on (A, B) and numpy's complex square root (independent of meicp's
    classification and of its cancellation-free formula)."""
    with pencil(scene) as pen:
        A, B = pen.A.toarray(), pen.B.toarray()
    w = sl.eig(A, B, right=False)
    w = w[np.isfinite(w) & (np.abs(w.imag) > 1e-8 * np.abs(w).max())]
    lam = np.sqrt(w.astype(complex))
    k = int(np.argmax(lam.real))
    return lam[k].real, abs(lam[k].imag), len(w) // 2


def rel(a, b):
    return abs(a - b) / abs(b)


@pytest.mark.parametrize("sigma", [-4.0 + 1e-9j, -1.75 + 0.12j, 2.0 + 3.0j, -1e-6 + 1e-12j, 1e-3 + 1e-8j])
def test_growth_and_frequency_have_no_cancellation(sigma):
    g, f = growth_frequency(sigma)
    assert abs(complex(g, f) ** 2 - sigma) <= 4e-16 * abs(sigma) and g > 0 and f >= 0


@pytest.mark.parametrize("scene", [lattice(20, (2, 2), 0.3), lattice(20, (2, 2), 3.0, shear=0.5),
                                   lattice(12, (3, 3), 1.0, states="slip-")],
                         ids=["mu0.3", "mu3-sheared", "slip-"])
def test_fastest_flutter_mode_matches_qz(scene):
    r = meicp.analyze(scene)
    g, f, pairs = qz_fastest(scene)
    assert r.flutter is True and "a proof" in r.flutter_evidence
    m = r.flutter_modes[0]
    assert rel(m.growth_rate, g) <= 1e-8 and rel(m.frequency, f) <= 1e-8
    assert len(r.flutter_modes) == pairs
    assert all(x.residual <= fl.RESIDUAL_TOL for x in r.flutter_modes)
    growth = [x.growth_rate for x in r.flutter_modes]
    assert growth == sorted(growth, reverse=True)
    # the shape is in natural numbering, unit norm, zero on the fixed top row
    assert m.x.shape == (scene.n_dofs,) and np.isclose(np.linalg.norm(m.x), 1.0)
    assert np.all(m.x[-2 * scene.nx:] == 0) and m.x.dtype == complex
    assert m.support.tolist() == list(range(scene.nx))


@pytest.mark.parametrize("chain, how", [(False, "QR"), (True, "QZ")])
def test_frictional_interface_flutter_matches_qz(chain, how):
    """Centre-of-mass coordinates make an interface's B diagonal (the scaled QR); a one-row
    layer between two interfaces keeps a non-diagonal, nonsymmetric B (QZ).  Both agree with
    QZ of the pencil."""
    scene = interface_chain_scene(5, 0.8, sides="free") if chain else meicp.load_scene(
        SCENES / "frictional_interface.toml")
    r = meicp.analyze(scene)
    with pencil(scene) as pen:
        B = pen.B.toarray()
        assert (np.count_nonzero(B - np.diag(np.diag(B))) > 0) == chain
    if r.flutter is True:
        g, f, _ = qz_fastest(scene)
        assert how in r.flutter_evidence and rel(r.flutter_modes[0].growth_rate, g) <= 1e-8
    else:
        assert r.flutter is False and not r.flutter_modes


def test_verdicts_compose_on_the_shipped_scene():
    """two_layers.toml: μ = 3 diverges and flutters; μ = 1 only flutters (meicp said STABLE
    there before issue 15); μ = 0.3 does neither (proved both ways)."""
    scene = meicp.load_scene(SCENES / "two_layers.toml")

    def at(mu):
        return meicp.analyze(scene.with_friction(mu))

    r3, r1, r03 = at(3.0), at(1.0), at(0.3)
    assert (r3.divergence, r3.flutter, r3.stable, r3.verdict) == (True, True, False, "UNSTABLE")
    assert (r1.divergence, r1.flutter, r1.stable) == (False, True, False)
    assert (r03.divergence, r03.flutter, r03.stable, r03.verdict) == (False, False, True, "STABLE")
    doc = r1.to_dict()
    assert doc["divergence"] is False and doc["flutter"] is True and doc["flutter_modes"][0]["growth_rate"] > 0
    assert "flutter: FLUTTER" in r1.summary() and "divergence: NO DIVERGENCE" in r1.summary()


def test_frictionless_sliding_is_proved_flutter_free():
    r = meicp.analyze(lattice(10, (2, 2), 0.0))
    assert r.flutter is False and r.flutter_modes == [] and "symmetric" in r.flutter_evidence


def test_flutter_false_leaves_it_undecided():
    scene = lattice(10, (2, 2), 0.3)
    for r in (meicp.analyze(scene, flutter=False),
              meicp.analyze(dataclasses.replace(scene, solver=dataclasses.replace(scene.solver, flutter=False)))):
        assert r.flutter is None and r.flutter_modes == [] and "not analysed" in r.flutter_evidence
        assert r.divergence is False and r.stable is None and r.verdict == "UNDECIDED"


@pytest.mark.parametrize("value", ["yes", 1, None.__class__, 0.0])
def test_hostile_flutter_keyword(value):
    with pytest.raises(ProblemError, match="flutter must be True or False"):
        meicp.analyze(lattice(4, (1, 1), 0.3), flutter=value)


@pytest.mark.parametrize("value", ['"yes"', "1", "[true]"])
def test_hostile_flutter_scene_key(tmp_path, value):
    text = (SCENES / "two_layers.toml").read_text()
    path = tmp_path / "s.toml"
    path.write_text(text.replace("[solver]", f"[solver]\nflutter = {value}") if "[solver]" in text
                    else text + f"\n[solver]\nflutter = {value}\n")
    with pytest.raises(ProblemError, match="flutter"):
        meicp.load_scene(path)


def _block_pencil(eps: float):
    """One 2×2 block [[a, ε], [−ε, a]] (σ = a ± iε) among well separated real eigenvalues,
    hidden by a random orthogonal similarity."""
    rng = np.random.default_rng(0)
    n = 40
    T = np.diag(-np.linspace(1.0, 20.0, n))
    T[0, 0] = T[1, 1] = -5.55
    T[0, 1], T[1, 0] = eps, -eps
    Q, _ = np.linalg.qr(rng.standard_normal((n, n)))
    return Q @ T @ Q.T, np.eye(n)


def test_clear_pair_is_flutter():
    r = fl.dense_flutter(*_block_pencil(1e-3))
    assert r.flutter is True and len(r.modes) == 1 and abs(r.modes[0].sigma - (-5.55 + 1e-3j)) < 1e-12


@pytest.mark.parametrize("eps", [1e-15, 1e-17, 0.0])
def test_rounding_level_pair_is_undecided(eps):
    r = fl.dense_flutter(*_block_pencil(eps))
    assert r.flutter is None and r.counts["borderline"] >= 1 and not r.modes


def test_real_nonsymmetric_spectrum_is_proved_flutter_free():
    rng = np.random.default_rng(1)
    n = 30
    T = np.triu(rng.standard_normal((n, n)), 1) + np.diag(-np.linspace(1, 10, n))
    S = rng.standard_normal((n, n)) + n * np.eye(n)
    r = fl.dense_flutter(S @ T @ np.linalg.inv(S), np.eye(n))
    assert r.flutter is False and r.counts["certified_real"] == n and "a proof" in r.evidence


def test_a_mode_failing_the_residual_gate_is_not_reported():
    with pencil(lattice(20, (2, 2), 3.0)) as pen:
        r = fl.dense_flutter(pen.A, pen.B, residual_tol=1e-30)
    assert not r.modes and r.rejected and r.flutter is None and "residual gate" in r.evidence


def test_grazing_branches_bracket_the_contact():
    states = ["slip+"] * 8
    states[3] = "grazing"
    scene = lattice(8, (2, 2), 1.0, states=states)
    with pencil(scene, grazing_case=((0, 3, "slip+"),)) as pen:
        branches = fl.grazing_branches(pen.lines)
    assert [label for label, _ in branches] == ["separated", "sliding base:slip+"]
    assert branches[0][1][0].states[3] == "separated" and branches[1][1][0].states[3] == "slip+"
    assert fl.combine_branches([True, None]) is None and fl.combine_branches([False, False]) is False
    assert fl.combine_branches([True, True]) is True
    r = meicp.analyze(scene)
    assert "separated" in r.flutter_evidence and "sliding" in r.flutter_evidence
    if r.flutter:
        assert {m.branch for m in r.flutter_modes} == {"separated", "sliding base:slip+"}


def _forced_search(comm):
    """The large-scale path on a 928-DOF pencil, against dense QZ of the same pencil."""
    scene = lattice(32, (8, 8), 2.0)
    with pencil(scene, comm=comm) as pen:
        got = fl.pencil_flutter(pen, scene, comm, dense_max=0)
        ref = fl.pencil_flutter(pen, scene, comm)
    return got, ref


def test_large_scale_search_forced_on_a_small_scene():
    got, ref = _forced_search(None)
    assert ref.flutter is True and ref.complete
    assert got.flutter is True and not got.complete and "not a proof" in got.evidence
    mode, mode_ref = got.modes[0], ref.modes[0]
    g, f = growth_frequency(mode.sigma)
    g_ref, f_ref = growth_frequency(mode_ref.sigma)
    assert rel(g, g_ref) <= 1e-8 and rel(f, f_ref) <= 1e-8 and mode.residual <= fl.RESIDUAL_TOL
    assert abs(abs(np.vdot(mode.x, mode_ref.x)) - 1) < 1e-6
    # every mode the search certified is one of QZ's
    assert all(min(abs(m.sigma - r.sigma) for r in ref.modes) <= 1e-8 * abs(m.sigma) for m in got.modes)


def test_search_without_a_mode_never_says_no_flutter():
    with pencil(lattice(20, (2, 2), 3.0)) as pen:
        r = fl.search_flutter(pen.A, pen.B, [-30.0 + 1e-3j], nev=1, ncv=8, residual_tol=1e-30)
    assert r.flutter is None and not r.modes and "not a proof" in r.evidence


def test_a_target_whose_pairs_all_fail_the_gate_is_moved_off_the_cluster(monkeypatch):
    """At 3·10⁵ DOFs the proxy's target sits in a cluster of ill-conditioned eigenvalues and
    every pair fails the gate; the search then retries above it.  Here the first solve's
    pairs are made to fail (residual 1): the retry must certify one of QZ's modes."""
    real = fl.complex_shift_solve
    calls = []

    def first_fails(ops, tau, **kw):
        pairs, info = real(ops, tau, **kw)
        calls.append(tau)
        return ([(s, x, 1.0) for s, x, _ in pairs] if len(calls) == 1 else pairs), info

    monkeypatch.setattr(fl, "complex_shift_solve", first_fails)
    scene = lattice(32, (8, 8), 2.0)
    with pencil(scene) as pen:
        ref = fl.pencil_flutter(pen, scene)
        tau = complex(fl.proxy_targets(scene, pen.lines, 1)[0])
        got = fl.search_flutter(pen.A, pen.B, [tau], nev=2, ncv=12)
        calls.clear()
        none = fl.search_flutter(pen.A, pen.B, [tau], nev=2, ncv=12, off_cluster_tries=0)
    assert len(calls) == 1 and none.flutter is None and not none.modes
    assert got.counts["moved"] == 1 and "moved off it" in got.evidence
    assert got.flutter is True and got.modes
    assert all(m.found_by == f"shift-invert at τ = {fl.off_cluster(tau, 0):.6g}" for m in got.modes)
    assert all(min(abs(m.sigma - r.sigma) for r in ref.modes) <= 1e-8 * abs(m.sigma) for m in got.modes)
    assert fl.off_cluster(tau, 0).imag > tau.imag and fl.off_cluster(tau, 1).imag > fl.off_cluster(tau, 0).imag


def test_a_target_where_nothing_converges_within_its_restarts_is_moved_off(monkeypatch):
    """Inside a cluster Krylov–Schur may converge nothing in SEARCH_RESTARTS restarts: the
    target moves off it, and only the last one gets LAST_RESTARTS."""
    real = fl.complex_shift_solve
    caps, bases = [], []

    def nothing_first(ops, tau, **kw):
        caps.append(kw["max_it"])
        bases.append(kw["ncv"])
        pairs, info = real(ops, tau, **kw)
        return ([] if len(caps) == 1 else pairs), info

    monkeypatch.setattr(fl, "complex_shift_solve", nothing_first)
    scene = lattice(32, (8, 8), 2.0)
    with pencil(scene) as pen:
        tau = complex(fl.proxy_targets(scene, pen.lines, 1)[0])
        got = fl.search_flutter(pen.A, pen.B, [tau], nev=2, ncv=12)
    assert got.flutter is True and got.counts["moved"] == 1 and "restarts" in got.evidence
    assert caps == [fl.SEARCH_RESTARTS, fl.LAST_RESTARTS]
    # the target moved off is searched with a wide basis: a narrow one cannot separate the
    # cluster's top edge (docs/benchmarks-notes.md, "RETRY_NCV")
    assert bases == [12, fl.RETRY_NCV] and f"basis of at least {fl.RETRY_NCV}" in got.evidence
    caps.clear()
    with pencil(scene) as pen:
        fl.search_flutter(pen.A, pen.B, [tau], nev=2, ncv=12, off_cluster_tries=0)
    assert caps == [fl.LAST_RESTARTS]


def test_real_ritz_values_of_the_real_form_are_skipped():
    """A real Ritz value θ of the real 2n form puts σ = τ + 1/θ exactly on the horizontal line
    through τ — what Krylov–Schur converges next to a target inside a cluster of
    ill-conditioned eigenvalues (pseudo-pairs): skipped and counted, the complex one kept."""
    from meicp.petsc import import_petsc
    from meicp.petsc.flutter import converged_pairs

    PETSc = import_petsc()
    template = PETSc.Mat().createAIJ((6, 6), nnz=1, comm=PETSc.COMM_SELF)
    template.assemble()

    class TwoRitzValues:  # the EPS calls converged_pairs makes
        values = [2.0 + 0j, 1.0 + 1.0j, 1.0 - 1.0j]

        def getConverged(self):
            return len(self.values)

        def getIterationNumber(self):
            return 1

        def getEigenvalue(self, i):
            return self.values[i]

        def getEigenvector(self, i, zr, zi):
            zr.set(1.0)
            zi.set(0.25)

    tau = -1.0 + 0.5j
    try:
        pairs, info = converged_pairs(TwoRitzValues(), template, tau, inverted=True, residual=lambda s, x: 0.0,
                                      gather=lambda x: x, comm=None)
    finally:
        template.destroy()
    assert info["real_ritz"] == 1 and info["nconv"] == 3 and len(pairs) == 1
    assert pairs[0][0] == pytest.approx(tau + 1 / (1.0 + 1.0j)) or pairs[0][0] == pytest.approx(
        (tau.conjugate() + 1 / (1.0 + 1.0j)).conjugate())
    assert info["radius"] == pytest.approx(abs(1 / (1.0 + 1.0j)))


def test_pseudo_pairs_following_the_target_get_no_stricter_solve():
    """Pairs that all lie within FOLLOWING·|τ| of the target are pseudo-pairs: when none passes
    the gate the search moves on at once instead of solving again at the strict tolerance;
    pairs spread over the disk still get the stricter solve."""
    from meicp.petsc.flutter import FOLLOWING, following, solve_tightened

    tau = -2.5 + 0.5j

    class Vec:
        def destroy(self):
            pass

    class Template:
        def createVecRight(self):
            return Vec()

    class Loose:  # an EPS that counts its solves
        solves = 0

        def solve(self):
            self.solves += 1

        def getTolerances(self):
            return (1e-8, 100)

        def getConverged(self):
            return 1

        def getEigenvector(self, i, zr, zi):
            pass

        def setTolerances(self, tol):
            pass

        def setInitialSpace(self, vectors):
            pass

    for values, solves in (([tau + 0.1 * FOLLOWING, tau - 0.5j * FOLLOWING], 1), ([tau + 0.01, tau], 2)):
        eps = Loose()
        pairs = [(v, None, 1e-9) for v in values]
        _, info = solve_tightened(eps, lambda: (pairs, {"iterations": 1}), Template(), 1e-10, 1e-10, [],
                                  pseudo=lambda p: following(p, tau))
        assert eps.solves == solves and info["solves"] == solves
        assert following(pairs, tau) is (solves == 1)
    assert not following([], tau)


def test_the_factors_are_analysed_in_node_blocks_only_when_they_divide_the_order():
    """MUMPS compresses blocks of |ICNTL(15)| rows, and factors wrongly, without an error,
    when they do not divide the order: on the 2n form blocks of 4 only for an even n (2n
    divisible by 4); on the complex n form blocks of 2 for an even n, none for an odd one."""
    from meicp.petsc.flutter import complex_defaults, shift_defaults

    assert shift_defaults(4, 24, 1e-10, n=1000)["st_mat_mumps_icntl_15"] == -4
    assert shift_defaults(4, 24, 1e-10, n=1001)["st_mat_mumps_icntl_15"] == -2
    assert complex_defaults(4, 24, 1e-10, n=1000)["st_mat_mumps_icntl_15"] == -2
    assert complex_defaults(4, 24, 1e-10, n=1001)["st_mat_mumps_icntl_15"] == 0
    assert complex_defaults(4, 24, 1e-10, n=1000, low_rank=1e-10)["st_mat_mumps_cntl_7"] == 1e-10
    assert "st_mat_mumps_icntl_35" not in shift_defaults(4, 24, 1e-10, n=1000)
    blr = shift_defaults(4, 24, 1e-10, n=1000, low_rank=1e-10)
    assert blr["st_mat_mumps_icntl_35"] == 2 and blr["st_mat_mumps_cntl_7"] == 1e-10


@pytest.mark.parametrize("parity, low_rank, form", [(0, None, "complex"), (1, None, "complex"),
                                                   (0, 1e-10, "complex"), (0, None, "real"), (1, None, "real"),
                                                   (0, 1e-10, "real")])
def test_search_on_even_and_odd_orders_with_and_without_low_rank_factors(parity, low_rank, form):
    """The search certifies QZ's modes whether the order is even (node blocks) or odd, with a
    full-rank or a block-low-rank factor, complex (ZMUMPS) or of the real 2n form."""
    scene = lattice(16, (3, 3), 2.0)
    with pencil(scene) as pen:
        n = pen.A.shape[0] - (pen.A.shape[0] % 2 != parity)
        A, B = pen.A[:n, :n].tocsr(), pen.B[:n, :n].tocsr()
    assert n % 2 == parity
    ref = fl.dense_flutter(A, B)
    tau = ref.modes[0].sigma + 0.01j
    got = fl.search_flutter(A, B, [tau], nev=2, ncv=12, low_rank=low_rank,
                            options={"real_form": True} if form == "real" else None)
    assert got.flutter is True and got.modes
    assert all(m.residual <= fl.RESIDUAL_TOL for m in got.modes)
    assert all(min(abs(m.sigma - r.sigma) for r in ref.modes) <= 1e-8 * abs(m.sigma) for m in got.modes)


def _large_and_spied(monkeypatch) -> list:
    """Every pencil counts as large (FLUTTER_OFF_CLUSTER_FROM, FLUTTER_SEARCH_LARGE = 50); the
    returned list receives (targets, keywords) of each search_flutter call."""
    monkeypatch.setattr(limits, "FLUTTER_OFF_CLUSTER_FROM", 50)
    monkeypatch.setattr(limits, "FLUTTER_SEARCH_LARGE", 50)
    seen = []
    real = fl.search_flutter

    def spy(A, B, targets, comm=None, **kw):
        seen.append((list(targets), kw))
        return real(A, B, targets, comm, **kw)

    monkeypatch.setattr(fl, "search_flutter", spy)
    return seen


def test_large_pencils_start_above_the_cluster(monkeypatch):
    """From FLUTTER_OFF_CLUSTER_FROM retained DOFs the proxy's target is moved up before the first
    solve (one factorisation instead of two where it lies in a cluster), with a basis of
    OFF_CLUSTER_NCV and a block-low-rank factor; the modes it certifies are QZ's."""
    seen = _large_and_spied(monkeypatch)
    scene = lattice(16, (3, 3), 2.0)
    with pencil(scene) as pen:
        assert pen.maps.retained.size >= 50
        got = fl.pencil_flutter(pen, scene, dense_max=0)
        ref = fl.pencil_flutter(pen, scene)
        tau = complex(fl.proxy_targets(scene, pen.lines, 1)[0])
    (targets, kw), = seen
    # the search's proxy solve runs on rank 0 with bounded BLAS threads: the same σ to rounding
    assert len(targets) == 1 and abs(targets[0] - fl.off_cluster(tau, 0)) <= 1e-10 * abs(tau)
    assert kw["ncv"] == fl.OFF_CLUSTER_NCV and kw["low_rank"] == fl.LOW_RANK_TOL
    assert "moved up off its cluster before the first solve" in got.evidence
    assert got.flutter is True and got.modes
    assert all(min(abs(m.sigma - r.sigma) for r in ref.modes) <= 1e-8 * abs(m.sigma) for m in got.modes)


@pytest.mark.mpi(min_size=2)
def test_same_flutter_modes_on_two_ranks(comm):
    from mpi4py import MPI

    scene = lattice(16, (3, 3), 2.0)
    one, two = meicp.analyze(scene, comm=MPI.COMM_SELF), meicp.analyze(scene, comm=comm)
    assert one.flutter is two.flutter is True and len(one.flutter_modes) == len(two.flutter_modes)
    for a, b in zip(one.flutter_modes, two.flutter_modes):
        assert abs(a.sigma - b.sigma) <= 1e-12 * abs(a.sigma) and abs(abs(np.vdot(a.x, b.x)) - 1) < 1e-8
    got, ref = _forced_search(comm)
    serial, _ = _forced_search(MPI.COMM_SELF)
    assert abs(got.modes[0].sigma - serial.modes[0].sigma) <= 1e-10 * abs(serial.modes[0].sigma)
    assert rel(growth_frequency(got.modes[0].sigma)[0], growth_frequency(ref.modes[0].sigma)[0]) <= 1e-8
    # the growth bracket: exact and the same on both (dense), a lower bound alone (search)
    assert one.flutter_growth.exact and two.flutter_growth.exact
    assert rel(one.flutter_growth.upper, two.flutter_growth.upper) <= 1e-12
    assert rel(got.growth.lower, serial.growth.lower) <= 1e-8 and not got.growth.exact
    assert rel(got.growth.upper, serial.growth.upper) <= 1e-12  # Bendixson's rectangle, the same on both


def test_solve_writes_and_prints_flutter(cli, tmp_path):
    import json

    import h5py

    out = tmp_path / "run"
    code, text, err = cli("solve", SCENES / "two_layers.toml", "-o", out, "--json", "-q")
    doc = json.loads(text)
    assert code == 0 and doc["divergence"] is True and doc["flutter"] is True and doc["stable"] is False
    fastest = doc["flutter_modes"][0]
    assert fastest["growth_rate"] > 0 and fastest["sigma_imag"] > 0 and fastest["residual"] <= 1e-10
    assert (out / "flutter_mode.png").is_file() and doc["output"]["flutter_png"].endswith("flutter_mode.png")
    with h5py.File(out / "results.h5") as f:
        assert f.attrs["flutter"] == 1 and f.attrs["divergence"] == 1 and f.attrs["n_flutter_modes"] == 3
        g = f["flutter_modes"]
        assert np.isclose(g["growth_rate"][0], fastest["growth_rate"], rtol=1e-12)
        assert g["x_real"].shape == g["x_imag"].shape == (3, 40) and g["sigma_imag"].attrs["units"] == "1"
        assert "long_name" in g["frequency"].attrs
    assert "flutter_0_imag" in (out / "lattice.xdmf").read_text()
    # the same directory again without flutter: no flutter_mode.png of the earlier run is left
    # beside a results.h5 that has no flutter mode
    code, text, err = cli("solve", SCENES / "two_layers.toml", "-o", out, "--no-flutter", "-q")
    assert not (out / "flutter_mode.png").exists()
    with h5py.File(out / "results.h5") as f:
        assert f.attrs["n_flutter_modes"] == 0
    code, text, _ = cli("solve", SCENES / "two_layers.toml", "--no-output", "--no-flutter", "-q")
    assert code == 0 and re.search(r"^flutter +FLUTTER UNDECIDED$", text, re.M)
    assert re.search(r"^divergence +DIVERGENCE$", text, re.M) and "not analysed" in text


def test_search_that_would_not_fit_in_memory_is_skipped_and_says_so(monkeypatch):
    from meicp.contact import flutter_verdict

    monkeypatch.setattr(flutter_verdict, "available_memory_on", lambda comm, need=None: (1000, "this machine"))
    scene = lattice(20, (2, 2), 3.0)
    with pencil(scene) as pen:
        r = fl.pencil_flutter(pen, scene, dense_max=0)
    assert r.flutter is None and not r.modes and r.evidence.startswith("not searched")
    damped_scene = damped(lattice(20, (2, 2), 3.0), eta=(0.02, 0.02))
    with pencil(damped_scene) as pen:
        r = fl.pencil_flutter(pen, damped_scene, dense_max=0)
    assert r.flutter is None and r.evidence.startswith("not searched: the damped flutter search")


def test_no_flutter_flag_takes_no_value():
    out = run(meicp_cmd() + ["solve", str(SCENES / "two_layers.toml"), "--no-output", "--no-flutter=yes"])
    assert out.returncode == 2 and "--no-flutter" in out.stderr and "Traceback" not in out.stderr


def test_search_without_a_proxy_on_a_frictional_interface_over_a_rough_base():
    """Two sliding contact lines (a rough base and a frictional interface): no strip proxy,
    λ-line targets; what it certifies is QZ's."""
    scene = two_layer_scene(24, (3, 3), mu=1.0, interface={"kind": "frictional", "friction": 0.5,
                                                            "states": "slip+"})
    with pencil(scene) as pen:
        got = fl.pencil_flutter(pen, scene, dense_max=0)
        ref = fl.pencil_flutter(pen, scene)
    assert "λ-line" in got.evidence and got.flutter in (True, None) and ref.flutter is True
    assert all(min(abs(m.sigma - r.sigma) for r in ref.modes) <= 1e-8 * abs(m.sigma) for m in got.modes)


@pytest.mark.parametrize("units", [1e-7, 1e7, 1e12])
def test_dense_verdict_does_not_depend_on_the_units(units):
    """Stiffness ×s, mass ÷s: every σ ×s², the verdict and the counts unchanged (the
    infinite-eigenvalue test once compared β with α unscaled: at s = 1e7 every finite σ of
    the frictional interface became "infinite" and flutter was "proved" absent)."""
    scene = meicp.load_scene(SCENES / "frictional_interface.toml")
    with pencil(scene) as pen:
        A, B = to_dense(pen.A), to_dense(pen.B)
    ref = fl.dense_flutter(A, B)
    got = fl.dense_flutter(units * A, B / units)
    assert ref.flutter is True and got.flutter is True
    assert got.counts == ref.counts and len(got.modes) == len(ref.modes)
    for m_got, m_ref in zip(got.modes, ref.modes):
        assert abs(m_got.sigma / units**2 - m_ref.sigma) <= 1e-8 * abs(m_ref.sigma)


def test_the_skew_bound_is_its_formula_and_bounds_every_imaginary_part():
    import scipy.sparse as sp

    from meicp.petsc.flutter import SlidingPencilOps
    from meicp.petsc.mat import destroying, mat_from_scipy

    rng = np.random.default_rng(5)
    A = rng.standard_normal((9, 9))
    d = rng.uniform(0.5, 2.0, 9)
    W = 0.5 * (A - A.T) / np.sqrt(np.outer(d, d))
    with destroying(mat_from_scipy(None, sp.csr_matrix(A)), mat_from_scipy(None, sp.diags(d, format="csr"))) as (Ap, Bp):
        with SlidingPencilOps(Ap, Bp) as ops:
            assert ops.skew_bound() == pytest.approx(np.abs(W).sum(axis=1).max(), rel=1e-14)
    sigma = sl.eigvals(A, np.diag(d))
    assert np.abs(sigma.imag).max() <= np.abs(W).sum(axis=1).max()


@pytest.fixture
def shifted_ops():
    """``(ops, τ)``: the sliding pencil of a 16-column lattice (μ = 2) as PETSc Mats with its
    :class:`SlidingPencilOps`, and a target just above its fastest flutter eigenvalue."""
    from meicp.petsc.flutter import SlidingPencilOps
    from meicp.petsc.mat import mat_from_scipy

    scene = lattice(16, (3, 3), 2.0)
    with pencil(scene) as pen:
        A_s, B_s = pen.A.tocsr(), pen.B.tocsr()
    tau = fl.dense_flutter(A_s, B_s).modes[0].sigma + 0.01j
    A, B = mat_from_scipy(None, A_s), mat_from_scipy(None, B_s)
    try:
        with SlidingPencilOps(A, B) as ops:
            yield ops, tau
    finally:
        A.destroy()
        B.destroy()


def test_complex_and_real_form_factors_return_the_same_pairs(shifted_ops):
    """The complex ZMUMPS factor of A − τB and the real LU of the 2n form K_τ are two
    factorisations of one operator: the same eigenvalues near τ, each pair's backward error
    recomputed on (A, B); the search says which factor it used."""
    from meicp.petsc.flutter import complex_shift_solve

    ops, tau = shifted_ops
    got, info = complex_shift_solve(ops, tau, nev=3, ncv=16)
    ref, ref_info = complex_shift_solve(ops, tau, nev=3, ncv=16, options={"real_form": True})
    assert info["factor"] == "complex" and ref_info["factor"] == "real 2n"
    assert len(got) >= 2 and all(res <= 1e-12 for _, _, res in got)
    nearest = sorted(ref, key=lambda p: abs(p[0] - tau))[:2]
    for sigma, _, _ in nearest:
        assert min(abs(sigma - g[0]) for g in got) <= 1e-10 * abs(sigma)


def test_a_loose_solve_whose_pairs_fail_the_gate_is_made_again_strictly(shifted_ops):
    """SLEPc at a loose tolerance converges pairs whose backward errors on (A, B) miss the
    gate: the same operator is solved again at the strict tolerance, from those pairs, and
    its pairs pass; without a strict tolerance the loose pairs are all there is."""
    from meicp.petsc.flutter import complex_shift_solve

    ops, tau = shifted_ops
    loose, loose_info = complex_shift_solve(ops, tau, nev=1, ncv=3, tol=1e-1, gate=1e-12)
    strict, strict_info = complex_shift_solve(ops, tau, nev=1, ncv=3, tol=1e-1, gate=1e-12, strict_tol=1e-13)
    assert loose_info["solves"] == 1 and loose and not any(res <= 1e-12 for _, _, res in loose)
    assert strict_info["solves"] == 2 and any(res <= 1e-12 for _, _, res in strict)
    assert strict_info["iterations"] > loose_info["iterations"]


def _interface_scene(nx, rows, mu, states="slip+"):
    return two_layer_scene(nx, rows, bottom="fixed", stiffness=(1.0, 6.0),
                           interface={"kind": "frictional", "friction": mu, "states": states})


def test_sliding_window_picks_the_middlemost_window_with_most_slips():
    states = ["stick"] * 10 + ["slip+"] * 4 + ["stick"] * 6 + ["slip-"] * 5 + ["stick"] * 5
    assert strip.sliding_window(states, 5) == 20
    assert strip.sliding_window(["slip+"] * 30, 10) == 10
    assert strip.sliding_window(["stick"] * 9, 3) == 3


def _three_layers(nx, rows=(6, 6, 6)):
    """Issue 29's shallow scene: k 1 / 3 / 1, ρ 1 / 1 / 2, on a rough base at μ = 0.3, slip−."""
    return scene_from_dict({"lattice": {"nx": nx, "spacing": 1.0, "shear": 0.4},
                            "layers": [{"name": n, "rows": r, "stiffness": k, "density": d}
                                       for n, r, k, d in zip("ABC", rows, (1.0, 3.0, 1.0), (1.0, 1.0, 2.0))],
                            "boundary": {"top": "fixed", "bottom": "contact", "left": "free", "right": "free"},
                            "contact": {"friction": 0.3, "states": "slip-"}})


def test_a_shallow_lattice_is_searched_from_its_whole_depth_too():
    """The fastest flutter modes of a shallow lattice span its depth: the 8-row base strip's
    targets miss them (27 % of QZ's fastest here), the whole-depth proxy's targets, moved up
    off their cluster, find QZ's fastest mode itself."""
    scene = _three_layers(48)
    with pencil(scene) as pen:
        ref = fl.pencil_flutter(pen, scene)  # dense: 1,584 retained DOFs
        strip_only = fl.pencil_flutter(pen, scene, dense_max=0,
                                       targets=fl.proxy_targets(scene, pen.lines, 3, depth=False))
        got = fl.pencil_flutter(pen, scene, dense_max=0)
    fastest = max(growth_frequency(m.sigma)[0] for m in ref.modes)
    found = [growth_frequency(m.sigma)[0] for m in got.modes]
    assert ref.complete and got.flutter is True and "and its whole depth (18 rows" in got.evidence
    assert "whole depth" not in strip_only.evidence  # targets given: the caller's
    assert max(growth_frequency(m.sigma)[0] for m in strip_only.modes) < 0.5 * fastest
    assert max(found) == pytest.approx(fastest, rel=1e-8)
    assert all(min(abs(m.sigma - r.sigma) for r in ref.modes) <= 1e-8 * abs(m.sigma) for m in got.modes)


def test_the_depth_proxy_is_the_whole_depth_of_a_shallow_scene_only():
    """More rows than the strip's and at most DEPTH_PROXY_ROWS: every row, PROXY_NX columns
    (the base's middle, or where the interface slides), the scene's own boundary; else none."""
    from meicp.contact.lines import contact_lines
    from meicp.lattice.model import LatticeModel

    for rows, whole in (((6, 6, 6), True), ((3, 3, 2), False), ((9, 9, 9), False)):
        scene = _three_layers(100, rows)
        lines = contact_lines(scene, LatticeModel(scene))
        proxy, near = strip.proxy_of(scene, lines, whole_depth=True)
        assert (proxy is not None) is whole
        if whole:
            assert proxy.nx == strip.PROXY_NX and proxy.ny == scene.ny and proxy.boundary == scene.boundary
            assert proxy.contact.states == ("slip-",) * strip.PROXY_NX and list(near) == [0, 1, 2]
    states = ["stick"] * 40 + ["slip-"] * 30 + ["stick"] * 30
    scene = _interface_scene(100, (6, 7), 0.5, states=states)
    line, = contact_lines(scene, LatticeModel(scene))
    proxy, near = strip.proxy_of(scene, [line], whole_depth=True)
    assert proxy.ny == scene.ny and proxy.boundary.bottom == scene.boundary.bottom == "fixed"
    assert [layer.rows for layer in proxy.layers] == [6, 7] and list(near) == [4, 5, 6, 7]
    itf, = (i for i in proxy.interfaces if i.kind == "frictional")
    assert itf.states.count("slip-") == 30


def test_interface_proxy_targets_give_certified_modes_and_only_a_lower_bound():
    """A frictional interface has its own strip proxy (rows on both sides of it): the search
    from its targets certifies modes that QZ finds on the whole pencil, and its fastest is
    reported as a lower bound of the fastest growth (here it is slower than QZ's fastest)."""
    scene = _interface_scene(48, (5, 5), 1.0)
    with pencil(scene) as pen:
        ref = fl.pencil_flutter(pen, scene)
        targets = fl.proxy_targets(scene, pen.lines, 3)
        got = fl.pencil_flutter(pen, scene, dense_max=0)
    assert ref.complete and len(targets) == 3 and "contact-strip proxy" in got.evidence
    assert got.flutter is True and got.modes
    assert all(min(abs(m.sigma - r.sigma) for r in ref.modes) <= 1e-8 * abs(m.sigma) for m in got.modes)
    assert got.growth.lower <= ref.growth.lower * (1 + 1e-12) <= got.growth.upper and not got.growth.exact


def test_interface_proxy_is_cut_where_the_interface_slides():
    """The proxy keeps PROXY_ROWS // 2 rows on each side (the cuts fixed) and the columns
    where most contacts slip; a scene with a rough base as well has no interface proxy."""
    states = ["stick"] * 40 + ["slip-"] * 30 + ["stick"] * 30
    scene = _interface_scene(100, (6, 7), 0.5, states=states)
    from meicp.contact.lines import contact_lines
    from meicp.lattice.model import LatticeModel
    line, = contact_lines(scene, LatticeModel(scene))
    proxy = strip.interface_proxy(scene, line)
    assert proxy.nx == strip.PROXY_NX and [layer.rows for layer in proxy.layers] == [strip.PROXY_ROWS // 2] * 2
    assert proxy.boundary.bottom == "fixed" and proxy.boundary.top == "fixed"
    itf, = (i for i in proxy.interfaces if i.kind == "frictional")
    assert itf.index == 0 and itf.states.count("slip-") == 30 and len(itf.states) == strip.PROXY_NX
    based = two_layer_scene(100, (6, 7), mu=1.0, interface={"kind": "frictional", "friction": 0.5, "states": states})
    lines = contact_lines(based, LatticeModel(based))
    assert strip.interface_proxy(based, lines[1]) is None


def test_large_interface_pencils_search_the_proxy_target_for_one_eigenpair(monkeypatch):
    """From FLUTTER_OFF_CLUSTER_FROM retained DOFs an interface-strip proxy's target is searched
    where it is, for one eigenpair with a basis of INTERFACE_NCV (a base proxy's is moved up);
    the modes it certifies are QZ's."""
    seen = _large_and_spied(monkeypatch)
    scene = _interface_scene(40, (4, 4), 1.0)
    with pencil(scene) as pen:
        got = fl.pencil_flutter(pen, scene, dense_max=0)
        ref = fl.pencil_flutter(pen, scene)
        tau = complex(fl.proxy_targets(scene, pen.lines, 1)[0])
    (targets, kw), = seen
    assert len(targets) == 1 and abs(targets[0] - tau) <= 1e-10 * abs(tau)  # rank 0's solve: σ to rounding
    assert kw["nev"] == 1 and kw["ncv"] == fl.INTERFACE_NCV
    assert f"searched at its σ for 1 eigenpair(s) with a basis of {fl.INTERFACE_NCV}" in got.evidence
    assert got.flutter is True and got.modes
    assert all(min(abs(m.sigma - r.sigma) for r in ref.modes) <= 1e-8 * abs(m.sigma) for m in got.modes)


@pytest.mark.parametrize("scene", [
    # a base under a lattice of 2 rows: the strip proxy has fewer rows than PROXY_NEAR_ROWS
    {"lattice": {"nx": 6, "shear": 0.3}, "layers": [{"name": "L0", "rows": 2, "stiffness": 1.0, "density": 1.0}],
     "boundary": {"top": "free", "bottom": "contact"}, "contact": {"friction": 2.0, "states": "slip-"}},
    # a frictional interface under a layer of 1 row
    {"lattice": {"nx": 5}, "layers": [{"name": "L0", "rows": 3, "stiffness": 1.0, "density": 1.0},
                                      {"name": "L1", "rows": 1, "stiffness": 1.0, "density": 1.0}],
     "boundary": {"top": "fixed", "bottom": "free", "left": "fixed", "right": "free"},
     "interfaces": [{"below": "L0", "kind": "frictional", "friction": 1.83,
                     "states": ["stick", "stick", "stick", "stick", "slip-"]}]},
], ids=["base-2-rows", "interface-1-row-above"])
def test_the_search_on_a_lattice_shallower_than_the_proxys_near_rows(scene):
    """The proxy's rows next to the contact are cut to the rows it has (an IndexError before,
    at default settings on a 2-row, 900-column lattice)."""
    sc = scene_from_dict(scene)
    dense, searched = meicp.analyze(sc), meicp.analyze(sc, flutter_dense_max=4)
    assert dense.flutter is True and searched.flutter is True
    assert searched.flutter_growth.lower <= dense.flutter_growth.upper * (1 + 1e-9)


def test_a_search_slepc_cannot_solve_is_undecided_not_a_crash():
    """Stiffness 1e-300 (a legal scene): SLEPc's projected problem fails in LAPACK (PETSc
    error 76); the target counts as failed and the evidence names it."""
    scene = two_layer_scene(5, (2, 2), mu=0.65, stiffness=(1e-300, 5e-300), states="slip+")
    assert meicp.analyze(scene).flutter is True  # dense
    r = meicp.analyze(scene, flutter_dense_max=4)
    assert r.flutter is None and "failed (PETSc error" in r.flutter_evidence


@pytest.mark.parametrize("target, mu", [(-2.2475, 0.6307632479061257), (-6.2475, 0.6307632479061257),
                                        (-6.2475, 0.6307632479061327)])
def test_a_split_pair_of_real_eigenvalues_is_no_flutter_mode(target, mu):
    """two_layers.toml's lattice scaled so that its onset collision σ* = −4.3195·s lies on a
    target of the search, μ within 1e-14 of it: every eigenvalue is real (40 digits), two of
    them 2.5e-9 apart; the search converged them as σ ± 6e-10i and certified them under
    MARGIN·η alone.  Their eigenvectors are nearly real (ρ ≈ 1e-8, every true mode measured
    ≥ 0.03): the conjugate pair's condition bound rejects them; the dense path agrees."""
    s = target / -4.3195068494
    scene = two_layer_scene(5, (2, 2), mu=mu, stiffness=(1.0 * s, 5.0 * s), states="slip+")
    r = meicp.analyze(scene, flutter_dense_max=4)
    assert r.flutter is not True and not r.flutter_modes
    assert meicp.analyze(scene).flutter is not True


def test_the_undamped_search_stops_a_stalled_solve():
    """The undamped search's stopping test (a speed heuristic, the stall half of the damped
    search's): a target whose best estimate stays at 1.5e-2 (μ = 0.002 on a 10⁵-DOF lattice:
    2.7 s a restart, toward 500) stops after its restarts; a converging one goes on."""
    from meicp.petsc import import_slepc
    from meicp.petsc.flutter import StallWatch

    reason = import_slepc().EPS.ConvergedReason
    stuck, converging = StallWatch(10, 60, 1e-8), StallWatch(10, 60, 1e-8)
    for its in range(1, 11):
        stuck.monitor(None, its, 0, [0.5j] * 8, [1.5e-2 * (1 + 0.1 * (its % 2))] * 8)
        converging.monitor(None, its, 0, [0.5j] * 8, [1e-1 * 0.5 ** its] * 8)
        if its < 10:  # never before its restarts
            assert stuck.stopping(None, its + 1, 500, 0, 8) == reason.ITERATING
    assert stuck.stopping(None, 11, 500, 0, 8) == reason.DIVERGED_ITS and "too slowly" in stuck.gave_up
    assert converging.stopping(None, 11, 500, 0, 8) == reason.ITERATING and not converging.gave_up
