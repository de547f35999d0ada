"""The condensation onto the contact DOFs (serial), its certificates against the enumeration
oracle, and the condensed divergence proofs (issue 14, T1/T2)."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st
from hypothesis.extra.numpy import arrays
from scipy.linalg import eigh

from meicp.contact.condensation import condense, from_bordered_schur, pieces_of
from meicp.contact.condenser_certificates import held_factor, refined_solve
from meicp.contact.divergence.condensed import prove_no_divergence
from meicp.contact.lines import contact_lines
from meicp.contact.maps import reduced_system
from meicp.contact.problem import pencil
from meicp.eicp.solve import solve_eicp
from meicp.lattice.assembly import assemble_scipy
from meicp.lattice.model import LatticeModel
from meicp.lcp.certificates import (certified_mu_lower_bound, optimise_mu_scaling,
                                    optimise_scaling, pd_certificate)
from meicp.lcp.classes import classify
from meicp.petsc.schur import dense_schur, mumps_factor

from meicp.examples import two_layer_scene

from .helpers import interface_chain_scene


def split(nx=9, mu=1.3, states="slip-", shear=0.5, rows=(2, 2), **kw):
    scene = two_layer_scene(nx, rows, mu=mu, states=states, shear=shear, **kw)
    model = LatticeModel(scene)
    K, M = assemble_scipy(model)
    red = reduced_system(model, contact_lines(scene, model), ())
    return pieces_of(K, M, red), scene


def dense_G(p, sigma):
    H = p.H(sigma).toarray()
    J, F = p.J, p.F
    return H[np.ix_(J, J)] - H[np.ix_(J, F)] @ np.linalg.solve(H[np.ix_(F, F)], H[np.ix_(F, J)])


@pytest.mark.parametrize("states", ["slip+", "slip-"])
@pytest.mark.parametrize("sigma", [0.0, 0.7])
def test_condensation_by_solves_and_by_schur_match_dense_and_the_bound_covers_the_error(states, sigma):
    p, _ = split(states=states)
    G = dense_G(p, sigma)
    c = condense(p, sigma, mumps_factor(None), tau=0.05, xi=True)  # τ = 0.05 ≤ λ_min (checked below)
    assert np.linalg.norm(c.G() - G, 2) <= c.error() < 1e-7
    H, rows = p.bordered(sigma)
    s = from_bordered_schur(p, sigma, dense_schur(None, H, rows, symmetric=True), 0.0)
    assert np.allclose(s.G(), G, atol=1e-12 * np.abs(G).max())
    assert np.allclose(s.Z, c.Z, atol=1e-12 * np.abs(c.Z).max())
    F = p.F
    lam = eigh(p.Kt[F][:, F].toarray(), p.Mt[F][:, F].toarray(), eigvals_only=True)
    assert lam.min() > 0.05


def test_no_tau_means_no_error_bound():
    p, _ = split()
    assert not np.isfinite(condense(p, 0.0, mumps_factor(None)).error())


def test_scene_friction_and_unit_friction_pieces_agree():
    p, _ = split(mu=1.3)
    scene = two_layer_scene(9, (2, 2), mu=1.3, states="slip-", shear=0.5)
    model = LatticeModel(scene)
    K, M = assemble_scipy(model)
    red = reduced_system(model, contact_lines(scene, model), ())
    u = pieces_of(K, M, red, friction="unit")
    assert abs(u.N * 1.3 - p.N).max() < 1e-12
    with pytest.raises(ValueError, match="friction"):
        pieces_of(K, M, red, friction="bogus")


# --- certificates against the enumeration oracle -------------------------------------------

small = st.integers(2, 6).flatmap(lambda n: arrays(np.float64, (n, n), elements=st.integers(-4, 4).map(float)))


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(G=small, shift=st.integers(0, 6))
def test_a_certificate_never_claims_R0_where_enumeration_finds_a_solution(G, shift):
    G = G + shift * np.eye(G.shape[0])
    d, _ = optimise_scaling([G], iters=30)
    if pd_certificate(G, 0.0, d).proved:
        assert classify(G).r0 is True


def test_borderline_is_not_proved():
    assert not pd_certificate(np.diag([1.0, 1e-17, 2.0]), 0.0).proved
    assert pd_certificate(np.diag([1.0, 1e-6, 2.0]), 0.0).proved
    assert not pd_certificate(np.diag([1.0, 1e-6, 2.0]), 2e-6).proved      # the error bound eats the margin
    assert not pd_certificate(np.diag([1.0, 1e-6, 2.0]), 0.0, tol=1e-5).proved


def test_diagonal_scaling_proves_what_plain_definiteness_cannot():
    G = np.array([[1.0, 3.0], [0.0, 1.0]])           # P-matrix, sym(G) indefinite
    assert not pd_certificate(G, 0.0).proved
    d, value = optimise_scaling([G], iters=200)
    assert value > 0 and pd_certificate(G, 0.0, d).proved


def test_certified_mu_segment_holds_at_every_mu_and_stops_before_a_solution():
    rng = np.random.default_rng(3)
    n = 6
    X = rng.standard_normal((n, n))
    S = X @ X.T + n * np.eye(n)
    R = -np.abs(rng.standard_normal((n, n)))
    d, mu_d = optimise_mu_scaling(S, R)
    lo, c0, c1 = certified_mu_lower_bound(S, R, 0.0, 0.0, d, mu_d)
    assert 0 < lo <= mu_d
    for mu in np.linspace(0, lo, 7):
        assert classify(S + mu * R).r0 is True


# --- the proofs on scenes, against enumeration ------------------------------------------------

def has_mode(scene):
    pen = pencil(scene)
    r = solve_eicp(pen.A.toarray(), pen.B.toarray(), J=pen.J, method="enumerate", lam_min=0.0)
    return bool(r.solutions)


@pytest.mark.parametrize("states,mu", [("slip+", 1.0), ("slip-", 0.8), ("slip-", 3.0), ("slip+", 40.0)])
def test_a_proof_never_contradicts_enumeration(states, mu):
    scene = two_layer_scene(7, (2, 2), mu=mu, states=states, shear=0.5)
    proof = prove_no_divergence(None, pencil(scene), np.inf)
    if proof.proved:
        assert proof.test == "condensed-windows" and proof.window == (0.0, np.inf) and proof.margin > 0
        assert not has_mode(scene)
    else:
        assert proof.test == "" and proof.statement


def test_the_issue_scene_is_proved_stable_and_the_unstable_one_is_not():
    stable = prove_no_divergence(None, pencil(two_layer_scene(60, (2, 2), mu=1.0, states="slip+", shear=0.5)), 1.0)
    assert stable.proved and stable.window == (0.0, 1.0) and stable.samples >= 1
    t1 = prove_no_divergence(None, pencil(two_layer_scene(60, (2, 2), mu=1.0, states="slip+", shear=0.5)), 0.0)
    assert t1.proved and t1.test == "condensed-pd" and t1.window == (0.0, 0.0)
    unstable = prove_no_divergence(None, pencil(two_layer_scene(60, (2, 2), mu=3.0, states="slip-", shear=0.5)), 1.0)
    assert not unstable.proved and unstable.window == () and "σ = 0 not excluded" in unstable.statement


def test_held_factor_proves_a_held_lattice_and_its_refined_solves_are_those_of_k_ff():
    p, _ = split()
    F = p.F
    KFF, MFF = p.Kt[F][:, F].tocsr(), p.Mt[F][:, F].tocsr()
    factor, tau, why = held_factor(None, KFF, MFF)
    try:
        lam = eigh(KFF.toarray(), MFF.toarray(), eigvals_only=True, subset_by_index=[0, 0])[0]
        assert factor is not None and why == "" and 0 < tau < lam
        rhs = np.random.default_rng(3).standard_normal((F.size, 3))
        exact = np.linalg.solve(KFF.toarray(), rhs)
        x = refined_solve(factor, KFF)(rhs)
        assert np.abs(x - exact).max() <= 1e-12 * np.abs(exact).max()
    finally:
        factor.destroy()


@pytest.mark.parametrize("gap", [0.0, 1e-15, -1e-3])
def test_held_factor_refuses_a_lattice_that_is_not_held_or_is_held_only_within_rounding(gap):
    import scipy.sparse as sp
    KFF = sp.csr_matrix(np.array([[1.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0 + gap]]))
    factor, tau, why = held_factor(None, KFF, sp.identity(3, format="csr"))
    assert factor is None and tau is None and "not proved positive definite" in why


@pytest.mark.parametrize("states,mu,sigma_max", [("slip+", 1.0, np.inf), ("slip-", 0.8, np.inf), ("slip-", 3.0, 1.0),
                                                 ("slip+", 1.0, 1.0)])
def test_the_schur_method_proves_what_the_solves_method_proves(states, mu, sigma_max):
    scene = two_layer_scene(12, (2, 2), mu=mu, states=states, shear=0.5)
    by_solves = prove_no_divergence(None, pencil(scene), sigma_max, method="solves")
    by_schur = prove_no_divergence(None, pencil(scene), sigma_max, method="schur")
    assert by_schur.proved == by_solves.proved
    if by_schur.proved:
        assert by_schur.test == by_solves.test and not has_mode(scene)


def test_a_huge_tolerance_leaves_it_undecided():
    scene = two_layer_scene(20, (2, 2), mu=1.0, states="slip+", shear=0.5)
    assert not prove_no_divergence(None, pencil(scene), 1.0, tol=0.9).proved


def test_a_non_diagonal_b_is_undecided_beyond_sigma_zero():
    """A one-row layer between two frictional interfaces keeps B non-diagonal (no per-pair
    centre of mass there): the windows past σ = 0 are refused, saying why."""
    proof = prove_no_divergence(None, pencil(interface_chain_scene(8, 3.0)), 1.0)
    assert not proof.proved and "diagonal B" in proof.statement


def test_a_frictional_interface_is_proved_on_every_window():
    """Centre-of-mass coordinates: B diagonal, so the σ-windows apply to an interface too."""
    scene = two_layer_scene(8, (2, 2), bottom="fixed", stiffness=(2.0, 1.0), density=(1.0, 1.0),
                            interface={"kind": "frictional", "friction": 3.0, "states": "slip+"})
    proof = prove_no_divergence(None, pencil(scene), 1.0)
    assert proof.proved and not has_mode(scene)
    with pytest.raises(ValueError, match="sigma_max"):
        prove_no_divergence(None, pencil(interface_chain_scene(8, 3.0)), -1.0)


def test_the_low_rank_schur_complement_is_the_full_rank_one_to_rounding():
    # the default is MUMPS' block-low-rank factorisation (SCHUR_LOW_RANK); on a lattice whose
    # fronts it compresses (10⁵ DOFs: a coarser threshold visibly moves the result; below
    # about 4·10⁴ MUMPS compresses nothing) it must agree with the full-rank Schur complement to
    # rounding, relative to the largest entry (of Z)
    p, _ = split(nx=250, rows=(100, 100), states="slip+", mu=1.0)
    H, rows = p.bordered(0.01)
    full = dense_schur(None, H, rows, symmetric=True, options={"mat_mumps_icntl_35": 0})
    default = dense_schur(None, H, rows, symmetric=True)
    coarse = dense_schur(None, H, rows, symmetric=True, options={"mat_mumps_cntl_7": 1e-4})
    scale = np.abs(full).max()
    assert np.abs(default - full).max() <= 1e-13 * scale
    assert np.abs(coarse - full).max() > 1e-9 * scale


def _condenser(scene):
    from meicp.contact.condenser import Condenser

    model = LatticeModel(scene)
    return Condenser(None, reduced_system(model, contact_lines(scene, model), ()), *assemble_scipy(model),
                     method="schur")


def test_the_schur_condenser_certifies_a_sharp_tau_on_its_own_series():
    """On the Schur series' instance (one analysis): τ ≤ λ_min(K̃_FF, M̃_FF), and sharp (half
    SLEPc's estimate, proved by a full-rank inertia), the measured error small; the kept solves
    with K̃_FF are exact after the series has factored other matrices since."""
    with _condenser(two_layer_scene(40, (3, 3), mu=1.0, states="slip+", shear=0.5)) as cond:
        assert cond.prepare(need_tau=True, keep_factor=True) and cond.why == ""
        KFF, MFF = cond.blocks_FF
        lam = eigh(KFF.toarray(), MFF.toarray(), eigvals_only=True, subset_by_index=[0, 0])[0]
        assert 0.45 * lam < cond.tau < lam and cond.tau_scale == cond.tau
        assert cond.relative_error < 1e-10
        cond.at(0.5)  # the series now holds 𝓗(0.5)
        rhs = np.random.default_rng(4).standard_normal(KFF.shape[0])
        with cond.factor_FF(0.0) as solve:
            x = solve(rhs)
        exact = np.linalg.solve(KFF.toarray(), rhs)
        assert np.abs(x - exact).max() <= 1e-11 * np.abs(exact).max()


@pytest.mark.parametrize("need_tau", [True, False])
def test_the_schur_condenser_refuses_a_lattice_that_is_not_held(need_tau):
    # the top free and every base node but one separated: pinned at one node, the lattice turns
    scene = two_layer_scene(6, (2, 2), mu=1.0, states=["slip+"] + ["separated"] * 5, top="free")
    with _condenser(scene) as cond:
        assert not cond.prepare(need_tau=need_tau)
        assert "not proved positive definite" in cond.why and "not held" in cond.why


def test_without_dmumps_the_condenser_proves_what_it_proves_on_its_series(monkeypatch):
    """The PETSc fallback (no DMUMPS of a known version: held factor, sharper τ by inertia) and
    the series' own instance prove the same windows."""
    from meicp.petsc import mumps_c

    scene = two_layer_scene(30, (2, 2), mu=3.0, states="slip+", shear=0.5)
    on_series = prove_no_divergence(None, pencil(scene), np.inf, method="schur")
    real_load = mumps_c.load
    monkeypatch.setattr(mumps_c, "load", lambda arith="z": (None, "none here") if arith == "d" else real_load(arith))
    by_petsc = prove_no_divergence(None, pencil(scene), np.inf, method="schur")
    assert on_series.proved and by_petsc.proved and on_series.test == by_petsc.test == "condensed-windows"


def test_an_estimate_past_lambda_min_falls_back_to_the_tiny_tau(monkeypatch):
    """Half an estimate of λ_min that is not below λ_min is not certified (the full-rank inertia
    of K̃_FF − tM̃_FF − 2ηD has negative pivots): the proof falls back to t = 0, a τ at the
    rounding level, still certified, while the windows are still split at half the estimate."""
    from meicp.contact import condenser

    scene = two_layer_scene(40, (3, 3), mu=1.0, states="slip+", shear=0.5)
    with _condenser(scene) as cond:
        KFF, MFF = cond.blocks_FF
        lam = eigh(KFF.toarray(), MFF.toarray(), eigvals_only=True, subset_by_index=[0, 0])[0]
        monkeypatch.setattr(condenser, "inverse_estimate", lambda *a, **k: 10.0 * lam)
        assert cond.prepare(need_tau=True)
        assert 0 < cond.tau < 1e-6 * lam and cond.tau_scale == 5.0 * lam
