"""The damped flutter search past the dense limit (issue 31, docs/damping.md "damped flutter at
scale"): complex shift-and-invert on the companion form of λ²B + λD − A.  Against the dense
companion QZ of the same pencil (every certified mode one of its eigenvalues, the fastest found
the dense fastest), its pairs re-checked on Q built independently, and what it never claims."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import meicp
from meicp.contact.damped import damping_matrix
from meicp.contact.flutter import pencil_flutter
from meicp.contact.problem import pencil
from meicp.core import limits
from meicp.eicp.quadratic import quadratic_spectrum
from meicp.examples import two_layer_scene
from meicp.io.scene import scene_from_dict

from .test_damping import damped

#: a frictional interface and a base contact, 60 columns: past the proxy's 32, so the
#: targets are not the scene's own eigenvalues
SCENES = {
    "interface": damped(two_layer_scene(60, (3, 3), bottom="fixed", stiffness=(2.0, 1.0), density=(1.0, 1.0),
                                        interface={"kind": "frictional", "friction": 1.0, "states": "slip+"}),
                        eta=(0.02, 0.02)),
    "base": damped(two_layer_scene(60, (3, 3), mu=1.0, states="slip+"), eta=(0.02, 0.05)),
}


@pytest.mark.parametrize("name", sorted(SCENES))
def test_the_search_finds_the_dense_fastest_damped_modes(name):
    scene = SCENES[name]
    dense = meicp.analyze(scene)
    search = meicp.analyze(scene, flutter_dense_max=10)
    assert dense.flutter is True and dense.flutter_growth.exact
    assert search.flutter is True and search.stable is False
    assert search.divergence is dense.divergence or search.divergence is None
    assert "companion form" in search.flutter_evidence and "not a proof" in search.flutter_evidence
    assert search.flutter_growth.loose and not search.flutter_growth.exact  # the ceiling: proved, far above
    lam_dense = np.array([np.sqrt(m.sigma) for m in dense.flutter_modes])
    for mode in search.flutter_modes:  # every certified mode is an eigenvalue of the pencil
        lam = np.sqrt(mode.sigma)
        assert np.min(np.abs(lam_dense - lam)) <= 1e-10 * abs(lam)
        assert mode.residual <= 1e-10
    # the fastest found is the dense fastest here, and never above it
    assert search.flutter_modes[0].growth_rate == pytest.approx(dense.flutter_modes[0].growth_rate, rel=1e-10)
    assert search.flutter_growth.lower <= dense.flutter_growth.upper


def test_the_search_pairs_solve_the_quadratic_pencil_built_independently():
    scene = SCENES["interface"]
    with pencil(scene) as pen:
        found = pencil_flutter(pen, scene, dense_max=10)
        A, B, D = pen.A.toarray(), pen.B.toarray(), damping_matrix(pen).toarray()
    assert found.flutter is True and found.modes
    for m in found.modes:
        lam = np.sqrt(m.sigma)
        r = (lam * lam * B + lam * D - A) @ m.x
        scale = abs(lam) ** 2 * np.abs(B).sum(0).max() + abs(lam) * np.abs(D).sum(0).max() + np.abs(A).sum(0).max()
        assert np.linalg.norm(r) / (scale * np.linalg.norm(m.x)) <= 1e-10
        assert lam.real > 0 and lam.imag > 0
    # and the complete spectrum has them
    spectrum = quadratic_spectrum(A, B, D)
    for m in found.modes:
        assert np.min(np.abs(spectrum.lam - np.sqrt(m.sigma))) <= 1e-9


def test_a_target_far_from_every_eigenvalue_proves_nothing():
    """Nothing certified near a target is *undecided*, never "no flutter"."""
    scene = SCENES["base"]
    with pencil(scene) as pen:
        found = pencil_flutter(pen, scene, dense_max=10, targets=[complex(40.0, 300.0)], nev=1, ncv=4)
    assert found.flutter is None and not found.modes
    assert "not a proof that none exists" in found.evidence


def test_a_damped_scene_past_every_dense_limit_is_unstable_by_its_flutter(monkeypatch):
    """Past the enumeration's limits, where the damped Rayleigh bound proves nothing and the
    undamped pencil has no mode to follow, the condensed λ-windows prove the damped divergence
    absent (tests/test_damped_windows.py checks them against the enumeration), and the search's
    certified flutter mode decides the verdict."""
    monkeypatch.setattr(limits, "ENUMERATE_N", 10)
    r = meicp.analyze(SCENES["base"], flutter_dense_max=10)
    assert r.divergence is False and r.proofs[0].test == "damped-condensed-windows"
    assert "no undamped divergence mode to follow" in r.evidence and "damped Rayleigh bound at τ" in r.evidence
    assert r.flutter is True and r.stable is False and r.status == "solved"


# ------------------------------------------------------------------ the damped Rayleigh bound


def _slipping(mu, eta=(0.05, 0.02), states="slip+"):
    return damped(two_layer_scene(6, (2, 2), mu=mu, states=states), eta=eta)


@pytest.mark.parametrize("states", ["slip+", "slip-"])
def test_the_friction_shift_bounds_sym_d_from_below(states):
    """sym(D) + ν·B ⪰ 0 with the ν of the Gershgorin discs (dense eigenvalues), at several μ."""
    import scipy.linalg as sl

    from meicp.contact.damped_rayleigh import friction_shift
    from meicp.lattice.assembly import mass_matrix_scipy

    indefinite = []
    for mu in (0.1, 1.0, 5.0, 20.0):
        with pencil(_slipping(mu, states=states)) as pen:
            nu, why = friction_shift(pen.maps, pen.lattice.damping(), mass_matrix_scipy(pen.lattice.model))
            D = damping_matrix(pen).toarray()
            B = pen.B.toarray()
        assert nu is not None and "Gershgorin" in why
        lowest = sl.eigvalsh(0.5 * (D + D.T) + nu * B, B)[0]
        assert lowest >= -1e-12
        indefinite.append(sl.eigvalsh(0.5 * (D + D.T), B)[0] < 0)
    # and it is not vacuous: at large μ sym(D) itself is indefinite (the friction rows)
    assert any(indefinite)


def test_the_damped_rayleigh_bound_never_contradicts_the_enumeration(monkeypatch):
    """Where the bound proves "no λ ≥ 0" the enumeration of every support finds no damped
    divergence mode; where the enumeration finds one the bound proves nothing."""
    from meicp.contact.damped_rayleigh import damped_rayleigh_bound

    proved = found = 0
    for mu in (0.05, 0.2, 0.5, 1.0, 2.0, 3.0, 5.0):
        for states in ("slip+", "slip-"):
            scene = _slipping(mu, states=states)
            with pencil(scene) as pen:
                ok, statement = damped_rayleigh_bound(pen)
            exact = meicp.analyze(scene, flutter=False)  # enumeration (small)
            assert exact.divergence is not None
            if ok:
                proved += 1
                assert exact.divergence is False, (mu, states, statement)
                assert "a proof" in statement
            found += exact.divergence is True
    assert proved >= 2 and found >= 2  # both branches are exercised

    # past the enumeration's limits the verdict is the bound's (or undecided), never "stable" by default
    monkeypatch.setattr(limits, "ENUMERATE_N", 10)
    r = meicp.analyze(_slipping(0.05), flutter=False)
    assert r.divergence is False and r.proofs[0].test == "damped-rayleigh"
    r = meicp.analyze(_slipping(5.0), flutter=False)  # the bound fails; the undamped mode, followed, is one
    assert r.divergence is True and r.proofs[0].test == "quadratic-followed"


def test_the_growth_watch_stops_a_solve_only_where_no_ritz_value_grows():
    """The damped search's stopping test (a speed heuristic): after its restarts it stops a
    solve whose last Ritz values all map to Re λ < 0, never one with a growing one, and never
    before its restarts; a solve that converged or reached its cap ends as SLEPc's would."""
    from meicp.petsc import import_slepc
    from meicp.petsc.flutter_quadratic import GrowthWatch

    reason = import_slepc().EPS.ConvergedReason
    lam0 = complex(0.05, 1.4)
    decaying = [1.0 / (complex(-0.01, 1.3) - lam0), 1.0 / (complex(-0.2, 1.5) - lam0)]
    growing = decaying + [1.0 / (complex(0.001, 1.41) - lam0)]
    watch = GrowthWatch(lam0, restarts=3, budget=1000, tol=1e-8)
    for its in (1, 2):  # before its restarts: iterating, whatever the Ritz values
        watch.monitor(None, its, 0, decaying, [1e-2 ** its] * 2)
        assert watch.stopping(None, its + 1, 500, 0, 2) == reason.ITERATING
    watch.monitor(None, 3, 0, growing, [1e-6] * 3)  # converging fast: only growth decides
    assert watch.stopping(None, 4, 500, 0, 2) == reason.ITERATING and not watch.gave_up
    watch.monitor(None, 4, 0, decaying, [1e-7] * 2)
    assert watch.stopping(None, 5, 500, 0, 2) == reason.DIVERGED_ITS and watch.gave_up
    assert watch.gave_up == "no Ritz value with Re λ ≥ 0"
    other = GrowthWatch(lam0, restarts=3, budget=1000, tol=1e-8)
    assert other.stopping(None, 7, 500, 2, 2) == reason.CONVERGED_TOL
    assert other.stopping(None, 500, 500, 0, 2) == reason.DIVERGED_ITS and not other.gave_up
    # growing Ritz values whose estimates stall (0.25 → 0.09 in 8 restarts, as measured at
    # 10⁶ DOFs) stop at a budget of 60, go on at one they would meet
    for budget, stops in ((60, True), (1000, False)):
        slow = GrowthWatch(lam0, restarts=3, budget=budget, tol=1e-8)
        for its in range(1, 10):
            slow.monitor(None, its, 0, growing, [0.25 * (0.09 / 0.25) ** ((its - 1) / 8)] * 3)
        assert (slow.stopping(None, 10, 500, 0, 2) == reason.DIVERGED_ITS) is stops
        assert ("too slowly" in slow.gave_up) is stops
    # estimates SLEPc has not made yet (0) are not progress
    unset = GrowthWatch(lam0, restarts=3, budget=60, tol=1e-8)
    for its in range(1, 10):
        unset.monitor(None, its, 0, growing, [0.25 * (0.09 / 0.25) ** ((its - 1) / 8), 0.0, 0.0])
    assert unset.stopping(None, 10, 500, 0, 2) == reason.DIVERGED_ITS
    fast = GrowthWatch(lam0, restarts=3, budget=60, tol=1e-8)
    for its in range(1, 5):  # 100-fold per restart: converging
        fast.monitor(None, its, 0, growing, [1e-2 ** its] * 3)
    assert fast.stopping(None, 5, 500, 0, 2) == reason.ITERATING


def test_with_vanishing_damping_the_search_finds_undamped_eigenvalues():
    """η = 1e-9: every mode the damped search certifies (σ = λ²) is, to 1e-7, a flutter
    eigenvalue of the undamped pencil from its dense QZ — the two paths share no code but the
    lattice."""
    base = two_layer_scene(60, (3, 3), mu=1.0, states="slip+")
    undamped = meicp.analyze(base, flutter_dense_max=5000)
    search = meicp.analyze(damped(base, eta=(1e-9, 1e-9)), flutter_dense_max=10)
    assert undamped.flutter is True and search.flutter is True
    sigmas = np.array([m.sigma for m in undamped.flutter_modes])
    for mode in search.flutter_modes:
        assert np.min(np.abs(sigmas - mode.sigma)) <= 1e-7 * abs(mode.sigma)


def test_no_target_is_searched_where_the_damped_proxy_has_no_flutter():
    """μ = 0.05 with damping: the damped proxy is proved flutter-free, so the search at scale
    searches nothing (the λ-line's guesses cost 15 eigen-solves at 10⁶ DOFs for nothing) and
    says so; undecided, never "no flutter"."""
    scene = damped(two_layer_scene(60, (3, 3), mu=0.05, states="slip+"), eta=(0.02, 0.05))
    dense = meicp.analyze(scene)
    r = meicp.analyze(scene, flutter_dense_max=10)
    assert dense.flutter is False  # the lattice itself has none: nothing was missed here
    assert r.flutter is None and "no target searched" in r.flutter_evidence
    assert "a proof for the proxy, not for the lattice" in r.flutter_evidence


@pytest.mark.parametrize("name", sorted(SCENES))
def test_the_growth_ceiling_bounds_the_whole_damped_spectrum(name):
    """Past the dense limit the bracket's upper end is the Bendixson-type ceiling: finite,
    loose, and above every eigenvalue's Re λ of the dense companion spectrum."""
    scene = SCENES[name]
    r = meicp.analyze(scene, flutter_dense_max=10)
    g = r.flutter_growth
    assert g.upper is not None and g.loose and not g.exact and "a proof" in g.evidence
    with pencil(scene) as pen:
        spec = quadratic_spectrum(pen.A.toarray(), pen.B.toarray(), damping_matrix(pen).toarray())
    assert np.max(spec.lam.real) <= g.upper
    assert g.lower <= g.upper


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), n=st.integers(2, 8))
def test_quadratic_ceiling_bounds_random_pencils(seed, n):
    """λ²B + λD − A with B diagonal positive and A, D arbitrary: the ceiling from the exact
    field-of-values ratios (eigenvalues of the scaled symmetric and skew parts) is above every
    eigenvalue's real part."""
    from meicp.contact.flutter_growth import quadratic_ceiling

    rng = np.random.default_rng(seed)
    b = rng.uniform(0.5, 2.0, n)
    A, D = rng.normal(size=(n, n)) * rng.uniform(0.1, 3), rng.normal(size=(n, n)) * rng.uniform(0.01, 1)
    s = 1 / np.sqrt(b)
    scaled = lambda M: s[:, None] * M * s[None, :]
    sym = lambda M: 0.5 * (M + M.T)
    skew = lambda M: 0.5 * (M - M.T)
    gamma = np.linalg.eigvalsh(sym(scaled(A)))[-1]
    beta = np.max(np.abs(np.linalg.eigvals(skew(scaled(A)))), initial=0.0)
    nu = max(0.0, -np.linalg.eigvalsh(sym(scaled(D)))[0])
    delta = np.max(np.abs(np.linalg.eigvals(skew(scaled(D)))), initial=0.0)
    spec = quadratic_spectrum(A, np.diag(b), D)
    assert np.max(spec.lam.real) <= quadratic_ceiling(gamma, beta, nu, delta) * (1 + 1e-9) + 1e-12


def test_a_rigid_slide_the_damping_does_not_reach_gives_no_flutter_mode():
    """Free sides, top held only vertically, Kelvin–Voigt damping alone: a rigid slide has
    Av = Dv = 0, so λ = 0 is double (a Jordan block) and rounding splits it by √η into pairs
    at |λ| ≈ 1e-8 that pass the residual gate; the search certified three of them (found by a
    review).  None is a mode: the dense verdict is undecided, and so must the search be."""
    from meicp.io.scene import scene_from_dict

    d = {"lattice": {"nx": 5, "spacing": 1.0, "shear": -0.16555930734164404},
         "layers": [{"name": "L0", "rows": 2, "stiffness": 5.984269182142555, "density": 1.8306675418823382,
                     "viscosity": 8.177426244671553},
                    {"name": "L1", "rows": 3, "stiffness": 2.6335602858967535, "density": 1.12603252639075,
                     "viscosity": 5.153188638245612}],
         "boundary": {"top": "fixed_y", "bottom": "contact", "left": "free", "right": "free"},
         "contact": {"friction": 0.3, "states": "slip-"},
         "embedded": [{"name": "E", "host": "L1", "row": 1, "rows": 1, "column": 1, "columns": 3,
                       "stiffness": 16.12986256205148, "density": 1.0, "viscosity": 16.12986256205148}]}
    scene = scene_from_dict(d)
    assert meicp.analyze(scene).flutter is None
    r = meicp.analyze(scene, flutter_dense_max=10)
    assert r.flutter is None and not r.flutter_modes


def test_a_real_eigenvalue_computed_off_the_axis_is_no_flutter_mode(monkeypatch):
    """Dashpots of η = 1e3 / 1e5 / 1: the companion search converged the real eigenvalue
    λ = 0.0045294566 (50 digits: Im 6e-46) as three values 2e-9 … 2e-8 off the axis, which a
    margin over ‖Q'(λ)‖ (huge here) certified as flutter.  Their eigenvectors are nearly real:
    the conjugate pair's condition bound rejects them."""
    scene = scene_from_dict({
        "lattice": {"nx": 2, "shear": 0.4247565318883201},
        "layers": [{"name": "L0", "rows": 2, "stiffness": 1.4903099700333364, "density": 1.3654134593500704,
                    "viscosity": 1000.0},
                   {"name": "L1", "rows": 1, "stiffness": 1.448826615902407, "density": 1.2080179184842506,
                    "viscosity": 100000.0},
                   {"name": "L2", "rows": 1, "stiffness": 3.4555784023531877, "density": 0.7382311136070208,
                    "viscosity": 1.0}],
        "boundary": {"top": "fixed_x", "bottom": "contact", "left": "fixed_y", "right": "free"},
        "contact": {"friction": 5.0, "states": "slip+"},
        "interfaces": [{"below": "L1", "kind": "frictional", "friction": 0.5, "states": "slip+"}]})
    r = meicp.analyze(scene, flutter_dense_max=0)
    assert r.flutter is not True and not r.flutter_modes
    assert meicp.analyze(scene).flutter is not True  # the dense path agrees


def test_a_double_eigenvalue_on_the_imaginary_axis_is_no_flutter_mode(monkeypatch):
    """At interface μ = 2 exactly a damped branch crosses Re λ = 0 where it meets an undamped
    mode: a double eigenvalue ±1.6e-9 + 1.1011i in rounding (0 in exact arithmetic); the search
    certified λ = 5e-9 + 1.1011i.  The partner pair's condition bound (their eigenvectors
    nearly parallel) rejects it."""
    scene = scene_from_dict({
        "lattice": {"nx": 2},
        "layers": [{"name": "L0", "rows": 2, "stiffness": 4.9623258741477505, "density": 1.557285180121884},
                   {"name": "L1", "rows": 2, "stiffness": 1.8155394920065286, "density": 1.2830415859607371,
                    "viscosity": 10.0},
                   {"name": "L2", "rows": 2, "stiffness": 0.5405974571202203, "density": 0.8917580235114427}],
        "boundary": {"top": "free", "bottom": "contact", "left": "free", "right": "fixed_y"},
        "contact": {"friction": 2.0, "states": "slip+"},
        "interfaces": [{"below": "L1", "kind": "frictional", "friction": 2.0, "states": "slip-"}]})
    monkeypatch.setattr(limits, "ENUMERATE_N", 0)
    r = meicp.analyze(scene, flutter_dense_max=0)
    assert all(np.sqrt(complex(m.sigma)).real > 1e-6 for m in r.flutter_modes), r.flutter_modes


def test_an_inaccurate_copy_of_a_mode_does_not_hide_it():
    """A 2-DOF pencil under mass damping: SLEPc returned the mode σ = −4.8577 + 1.1844i and a
    copy failing the residual gate with the same eigenvector; as a partner its angle 0 made
    the mode's condition bound infinite (the mode undecided).  Partners are the pairs that
    pass the gate, other than the mode itself."""
    scene = scene_from_dict({
        "lattice": {"nx": 2, "shear": 0.5750987534519004},
        "layers": [{"name": "L0", "rows": 1, "stiffness": 3.3816421311312554, "density": 0.5291613806026279},
                   {"name": "L1", "rows": 1, "stiffness": 1.874226481977097, "density": 1.4080900170501343}],
        "boundary": {"top": "fixed_y", "bottom": "contact", "left": "fixed_x", "right": "free"},
        "contact": {"friction": 5.0, "states": "slip-"}, "damping": {"mass": 0.001}})
    dense, searched = meicp.analyze(scene), meicp.analyze(scene, flutter_dense_max=0)
    assert dense.flutter is True and searched.flutter is True
    assert searched.flutter_growth.lower <= dense.flutter_growth.upper * (1 + 1e-9)
    assert abs(searched.flutter_modes[0].sigma - dense.flutter_modes[0].sigma) <= 1e-8
