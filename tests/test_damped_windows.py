"""Condensed λ-windows (issue 31, deliverable 2; docs/damping.md, "condensed λ-windows"): a
proof past the enumeration that the damped quadratic MEiCP has no real λ ≥ 0, for damping that
is not proportional (the layers' relaxation times differ: the seeds' case).  Against the
enumeration of the quadratic MEiCP on lattices small enough for both."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

import meicp
from meicp.contact import damped as damped_module
from meicp.contact.damped_windows import (DampedPieces, Sample, ordering_spread, damped_pieces,
                                          prove_no_damped_divergence, window_margin)
from meicp.contact.problem import pencil
from meicp.eicp.quadratic import solve_quadratic_eicp
from meicp.examples import two_layer_scene

from .test_damping import INTERFACE, TWO_LAYERS, damped


def random_lattice(seed: int):
    """A random small damped lattice, base contact or frictional interface, with viscosities
    not proportional to the stiffnesses (one layer may have none) and sometimes a mass term."""
    rng = np.random.default_rng(seed)
    mu = float(rng.choice([0.1, 0.3, 0.6, 1.0, 2.0, 3.0]))
    state = str(rng.choice(["slip+", "slip-"]))
    k = (float(rng.uniform(0.5, 5)), float(rng.uniform(0.5, 5)))
    rows = (int(rng.integers(2, 4)), int(rng.integers(1, 3)))
    nx, shear = int(rng.integers(2, 6)), float(rng.uniform(-0.5, 0.5))
    if rng.random() < 0.5:
        scene = two_layer_scene(nx, rows, bottom="fixed", stiffness=k, density=(1.0, 1.5), shear=shear,
                                interface={"kind": "frictional", "friction": mu, "states": state})
    else:
        scene = two_layer_scene(nx, rows, mu=mu, states=state, shear=shear, stiffness=k)
    eta = (float(rng.choice([0.0, 0.01, 0.1, 0.5])), float(rng.choice([0.01, 0.1, 0.5, 2.0])))
    return damped(scene, eta=eta, mass=float(rng.choice([0.1])) if rng.random() < 0.3 else None)


def enumerated(scene):
    with pencil(scene) as pen:
        return solve_quadratic_eicp(pen.A.toarray(), pen.B.toarray(), pen.damping().toarray(), pen.J)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2 ** 32 - 1))
def test_a_proof_is_never_wrong(seed):
    """Whenever the windows prove, the enumeration of every support finds no solution."""
    scene = random_lattice(seed)
    with pencil(scene) as pen:
        proof = prove_no_damped_divergence(pen)
    if proof.proved:
        assert enumerated(scene).status == "no_solution"


def test_the_windows_decide_what_the_enumeration_proves_stable():
    """Power, on a fixed family: every lattice the enumeration proves free of damped divergence
    (101 of 128 here) is proved by the windows — the damped Rayleigh bound proves 60 of them —
    and none with a mode is."""
    counts = {"stable": 0, "proved": 0, "modes": 0}
    for seed in range(128):
        scene = random_lattice(seed)
        truth = enumerated(scene).status
        with pencil(scene) as pen:
            proved = prove_no_damped_divergence(pen).proved
        if truth == "no_solution":
            counts["stable"] += 1
            counts["proved"] += proved
        else:
            counts["modes"] += 1
            assert not proved
    assert counts["stable"] >= 90 and counts["proved"] >= 0.95 * counts["stable"], counts


def test_at_scale_the_seeds_scene_is_decided(monkeypatch):
    """A frictional interface between layers of different stiffness and the same viscosity (not
    proportional: the damped proportional path does not apply; extensive_interface.toml's layers,
    6 columns wide), past the enumeration: the damped
    Rayleigh bound proves nothing, no damped mode is found, the windows prove stability."""
    scene = damped(two_layer_scene(6, (5, 5), bottom="fixed", stiffness=(1.0, 4.0), density=(1.0, 2.0),
                                   interface={"kind": "frictional", "friction": 1.0, "states": "slip+"}),
                   eta=(0.02, 0.02))
    assert enumerated(scene).status == "no_solution"
    monkeypatch.setattr(damped_module, "enumeration_is_small", lambda *a: False)
    r = meicp.analyze(scene, flutter=False)
    assert r.divergence is False and r.proofs[0].test == "damped-condensed-windows"
    assert "damped Rayleigh bound at τ" in r.evidence and "condensed λ-windows: G(λ) ∈ R₀" in r.evidence


def test_a_divergence_mode_leaves_it_undecided_or_found(monkeypatch):
    """two_layers.toml at μ = 3 with η 0.1 / 0.01 has a damped divergence mode (λ ≈ 0.586): the
    windows cannot prove its absence, and the path at scale never says stable."""
    scene = damped(TWO_LAYERS, eta=(0.1, 0.01))
    with pencil(scene) as pen:
        assert not prove_no_damped_divergence(pen).proved
    monkeypatch.setattr(damped_module, "enumeration_is_small", lambda *a: False)
    assert meicp.analyze(scene, flutter=False).divergence is not False


def test_a_lattice_of_contact_rows_only_is_condensed_to_nothing():
    """Every retained DOF a contact DOF (two one-row layers, top and bottom fixed): G(λ) = H_JJ(λ)."""
    scene = damped(two_layer_scene(4, (2, 1), bottom="fixed", stiffness=(2.0, 1.0),
                                   interface={"kind": "frictional", "friction": 0.3, "states": "slip+"}),
                   eta=(0.1, 0.2))
    with pencil(scene) as pen:
        pieces, _ = damped_pieces(pen)
        assert pieces.F.size == 0
        proof = prove_no_damped_divergence(pen)
    assert proof.proved is (enumerated(scene).status == "no_solution") and proof.proved


def test_not_tried_where_B_is_not_diagonal():
    """A one-row layer between two frictional interfaces couples contact and free DOFs through
    the mass: the windows say they do not apply."""
    d = INTERFACE.to_dict()
    d["layers"] = [{"name": "A", "rows": 2, "stiffness": 2.0, "density": 1.0, "viscosity": 0.1},
                   {"name": "B", "rows": 1, "stiffness": 1.0, "density": 1.0, "viscosity": 0.05},
                   {"name": "C", "rows": 2, "stiffness": 1.5, "density": 1.0, "viscosity": 0.02}]
    d["interfaces"] = [{"below": "A", "kind": "frictional", "friction": 0.3, "states": "slip+"},
                       {"below": "B", "kind": "frictional", "friction": 0.3, "states": "slip+"}]
    from meicp.io.scene import scene_from_dict
    with pencil(scene_from_dict(d)) as pen:
        proof = prove_no_damped_divergence(pen)
    assert not proof.proved and "not tried" in proof.statement


def test_the_window_bound_holds_between_its_ends():
    """The bound 𝓜(λ) ⪯ sym(WG(λ)) the certificate rests on, checked on a grid inside windows of
    a small interface against G(λ) itself (no rounding allowance needed: exact blocks)."""
    scene = damped(INTERFACE.with_friction(0.5), eta=(0.05, 0.2))
    with pencil(scene) as pen:
        pieces, _ = damped_pieces(pen)
        F, J = pieces.F, pieces.J
        U = pieces.U().toarray()

        def exact(lam):
            X = np.linalg.inv(pieces.H_FF(lam).toarray())
            return Sample(lam, U @ X @ U.T, 0.0)

        HJJ = pieces.H_JJ()
        rng = np.random.default_rng(5)
        for lo, hi in [(0.0, 0.05), (0.05, 0.4), (0.4, 2.0)]:
            a, b = exact(lo), exact(hi)
            w = rng.uniform(0.5, 2.0, J.size)
            for lam in np.linspace(lo, hi, 7):
                from meicp.contact.damped_windows import G_at, window_parts
                (M0, M1, M2), _ = window_parts(HJJ, a, b, w, 0.0).at(float(np.mean(w)))
                WG = w[:, None] * G_at(HJJ, exact(lam))
                gap = 0.5 * (WG + WG.T) - (M0 + lam * M1 + lam * lam * M2)
                assert np.linalg.eigvalsh(gap).min() >= -1e-10 * np.abs(WG).max()


def test_the_ordering_spread_is_zero_away_from_zero_and_tiny_at_it():
    pieces = DampedPieces(*([None] * 5), J=np.arange(1), slack=1e-15, nu=0.0)
    assert ordering_spread(pieces, 1e-6, 0.1, 0.5) == 0.0
    assert 0 < ordering_spread(pieces, 1e-6, 0.0, 0.5) <= 1e-9
    assert ordering_spread(pieces, 0.0, 0.0, 0.5) == np.inf
    assert window_margin([np.eye(1)] * 3, Sample(0.0, np.zeros((4, 4)), 0.0), Sample(1.0, np.zeros((4, 4)), 0.0),
                         np.ones(1), np.inf)[0] == -np.inf
