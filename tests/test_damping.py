"""Damping (docs/damping.md, issue 31 foundation): the scene keys, C assembled like K with η,
the dense quadratic references (divergence by enumeration of supports, flutter by the
companion linearisation) against independent checks, and the paths that refuse damping."""

import dataclasses
import itertools

import numpy as np
import pytest
import scipy.linalg as sl
from hypothesis import given, settings, strategies as st

import meicp
from meicp.examples import two_layer_scene
from meicp.contact.damped import classify_spectrum
from meicp.contact.problem import pencil
from meicp.core import limits
from meicp.core.errors import ProblemError
from meicp.eicp.quadratic import (backward_error, companion, quadratic_spectrum, solve_quadratic_eicp)
from meicp.io.scene import load_scene, scene_from_dict

from .conftest import ROOT
from .helpers import bond_stiffness
from .test_lattice import seed_cell_K

SCENES = ROOT / "data" / "scenes"


def damped(scene, *, eta=None, mass=None, interface_eta=None):
    """``scene`` with viscosity ``eta`` (one per layer), ``[damping] mass`` and the bonded
    interface's own viscosity, read back by the parser."""
    d = scene.to_dict() if not isinstance(scene, dict) else scene
    for layer, value in zip(d["layers"], eta or ()):
        layer["viscosity"] = value
    if mass is not None:
        d["damping"] = {"mass": mass}
    if interface_eta is not None:
        d["interfaces"] = [{"below": d["layers"][0]["name"], "kind": "bonded", "viscosity": interface_eta}]
    return scene_from_dict(d)


TWO_LAYERS = load_scene(SCENES / "two_layers.toml")
CELL = {"lattice": {"nx": 2, "spacing": 1.3, "shear": 0.3},
        "layers": [{"name": "A", "rows": 1, "stiffness": 1.0, "density": 1.0},
                   {"name": "B", "rows": 1, "stiffness": 3.0, "density": 2.0}]}


# ------------------------------------------------------------------------------- scene keys


def test_damping_keys_are_read_and_absent_ones_leave_the_scene_undamped():
    assert not TWO_LAYERS.damped and TWO_LAYERS.damping is None
    assert all(layer.viscosity is None for layer in TWO_LAYERS.layers)
    s = damped(TWO_LAYERS, eta=(0.02, 0.05), mass=0.1, interface_eta=0.3)
    assert s.damped and [layer.viscosity for layer in s.layers] == [0.02, 0.05]
    assert s.damping.mass == 0.1 and s.interfaces[0].viscosity == 0.3
    assert scene_from_dict(s.to_dict()) == dataclass_without_source(s)
    zero = damped(TWO_LAYERS, eta=(0.0, 0.0), mass=0.0, interface_eta=0.0)
    assert not zero.damped


def dataclass_without_source(scene):
    return dataclasses.replace(scene, source="<dict>")


@pytest.mark.parametrize("where, value, message", [
    ("layers[0].viscosity", float("nan"), "layers[0].viscosity must be finite, got nan"),
    ("layers[1].viscosity", -0.1, "layers[1].viscosity must be >= 0, got -0.1"),
    ("layers[0].viscosity", float("inf"), "layers[0].viscosity must be finite, got inf"),
    ("layers[0].viscosity", "0.1", "layers[0].viscosity must be a number, got '0.1'"),
    ("damping.mass", -1.0, "damping.mass must be >= 0, got -1"),
    ("damping.mass", float("inf"), "damping.mass must be finite, got inf"),
    ("damping.mass", 1e308, "damping.mass = 1e+308 times the largest node mass"),
    ("damping.mas", 1.0, "unknown key damping.mas (did you mean mass?"),
    ("embedded[0].viscosity", -2.0, "embedded[0].viscosity must be >= 0, got -2"),
    ("interfaces[0].viscosity", float("nan"), "interfaces[0].viscosity must be finite, got nan"),
])
def test_bad_damping_values_are_errors_naming_the_key(where, value, message):
    d = TWO_LAYERS.to_dict()
    d["embedded"] = [{"name": "band", "host": "B", "stiffness": 3.0, "density": 1.0}]
    d["interfaces"] = [{"below": "A", "kind": "bonded"}]
    table, key = where.rsplit(".", 1)
    if table == "damping":
        d["damping"] = {key: value}
    else:
        name, index = table.rstrip("]").split("[")
        d[name][int(index)][key] = value
    with pytest.raises(ProblemError, match=None) as err:
        scene_from_dict(d, source="s.toml")
    assert message in str(err.value)


def test_a_frictional_interface_has_no_viscosity():
    d = TWO_LAYERS.to_dict()
    d["interfaces"] = [{"below": "A", "kind": "frictional", "friction": 0.5, "viscosity": 0.1}]
    with pytest.raises(ProblemError, match=r"interfaces\[0\].viscosity applies to kind = \"bonded\" only"):
        scene_from_dict(d)


def test_explicit_zero_damping_gives_todays_results():
    today = meicp.analyze(TWO_LAYERS)
    zero = meicp.analyze(damped(TWO_LAYERS, eta=(0.0, 0.0), mass=0.0))
    assert zero.damping is None and "damping" not in zero.to_dict()
    assert [m.sigma for m in zero.modes] == [m.sigma for m in today.modes]
    assert [m.sigma for m in zero.flutter_modes] == [m.sigma for m in today.flutter_modes]
    assert (zero.stable, zero.divergence, zero.flutter, zero.evidence) == \
        (today.stable, today.divergence, today.flutter, today.evidence)


# ------------------------------------------------------------------------------- assembly


def test_damping_of_a_sheared_four_node_cell_is_the_seed_formula_with_eta():
    """C of the sheared cell is the seed's 8×8 block formula (errata applied) with η in
    place of k: η_A, η_B inside the layers and their mean across; an interface's own η."""
    a, sh = 1.3, 0.3
    p = [(0, 0), (a, 0), (sh * a, a), (a + sh * a, a)]
    d = {**CELL, "layers": [dict(CELL["layers"][0], viscosity=0.2), dict(CELL["layers"][1], viscosity=0.6)]}
    C = meicp.assemble_damping(scene_from_dict(d)).toarray()
    assert np.abs(C - seed_cell_K(p, 0.2, 0.6, 0.4)).max() < 1e-15
    d["interfaces"] = [{"below": "A", "viscosity": 0.05}]
    C = meicp.assemble_damping(scene_from_dict(d)).toarray()
    assert np.abs(C - seed_cell_K(p, 0.2, 0.6, 0.05)).max() < 1e-15
    # the same bonds as K: η = k gives K itself
    same = {**CELL, "layers": [dict(layer, viscosity=layer["stiffness"]) for layer in CELL["layers"]]}
    K, _ = meicp.assemble(scene_from_dict(same))
    assert np.abs(meicp.assemble_damping(scene_from_dict(same)) - K).max() == 0


def test_damping_is_psd_with_the_rigid_translations_in_its_null_space_and_alpha_m():
    s = damped(two_layer_scene(6, (3, 2), mu=0.5, shear=0.2), eta=(0.02, 0.0))
    C = meicp.assemble_damping(s)
    K, M = meicp.assemble(s)
    assert C.shape == K.shape and (C != C.T).nnz == 0
    assert np.array_equal(C.indptr, K.indptr) and np.array_equal(C.indices, K.indices)  # K's pattern
    w = np.linalg.eigvalsh(C.toarray())
    assert w.min() > -1e-14 * w.max() and w.max() > 0
    n = s.n_nodes
    for shift in (np.tile([1.0, 0.0], n), np.tile([0.0, 1.0], n)):
        assert np.abs(C @ shift).max() < 1e-15
    # η = 0 in the upper layer: its bonds contribute nothing, the crossing ones the mean 0.01
    model = meicp.LatticeModel(s)
    ends, _, _ = model.bonds()
    eta = model.cmat[model.material()[ends[:, 0]], model.material()[ends[:, 1]]]
    ref = bond_stiffness(model.positions(), ends, eta)
    assert abs(C - ref).max() < 1e-15
    assert set(np.round(eta, 12)) == {0.0, 0.01, 0.02}
    with_mass = meicp.assemble_damping(damped(s, mass=0.7))
    assert abs(with_mass - C - 0.7 * M).max() < 1e-15


def test_petsc_damping_equals_the_scipy_one():
    from mpi4py import MPI
    from meicp.core.matrix import to_dense
    s = damped(TWO_LAYERS, eta=(0.02, 0.1), mass=0.3)
    C = meicp.assemble_damping(s, comm=MPI.COMM_SELF)
    try:
        assert np.abs(to_dense(C) - meicp.assemble_damping(s).toarray()).max() == 0
    finally:
        C.destroy()


# ------------------------------------------------------------------------------- dense references


def _random_problem(rng, n, *, friction=True):
    A = rng.normal(size=(n, n))
    B = np.diag(rng.uniform(0.5, 2.0, n))
    G = rng.normal(size=(n, n))
    D = 0.3 * G @ G.T
    if friction:  # friction rows make D nonsymmetric, sym(D) possibly indefinite
        D[0] += rng.normal(size=n)
    return A, B, D


def test_without_d_the_quadratic_enumeration_is_the_undamped_one():
    rng = np.random.default_rng(3)
    for _ in range(20):
        n = int(rng.integers(2, 6))
        A, B, _ = _random_problem(rng, n)
        J = np.sort(rng.choice(n, size=int(rng.integers(1, n + 1)), replace=False))
        q = solve_quadratic_eicp(A, B, np.zeros((n, n)), J)
        e = meicp.solve_eicp(A, B, J=J, method="enumerate", all_solutions=True, lam_min=0.0)
        assert q.status == ("no_solution" if e.status == "no_solution" else "solved")
        assert np.allclose(sorted(s.sigma for s in q.solutions), sorted(s.lam for s in e.solutions), rtol=1e-9)


def _brute_force(A, B, D, J):
    """Real λ ≥ 0 of the quadratic MEiCP, support by support, from the roots of
    det(λ²B + λD − A)_RR (interpolated on a circle) and an SVD null vector: no companion
    form.  Returns (robust, loose): λ whose ξ_S and dual slack exceed 1e-6, and those
    feasible to 1e-6."""
    n = A.shape[0]
    F = np.setdiff1d(np.arange(n), J)
    robust, loose = [], []
    for k in range(len(J) + 1):
        for S in itertools.combinations(J, k):
            R = np.sort(np.concatenate([F, np.array(S, dtype=int)])).astype(int)
            if R.size == 0:
                continue
            m = 2 * R.size + 1
            rho = 2.0
            z = rho * np.exp(2j * np.pi * np.arange(m) / m)
            vals = np.array([np.linalg.det((t * t * B + t * D - A)[np.ix_(R, R)]) for t in z])
            c = np.fft.fft(vals) / m / rho ** np.arange(m)  # c_j: coefficient of λ^j
            roots = np.roots(c[::-1][np.argmax(np.abs(c[::-1]) > 1e-12 * np.abs(c).max()):])
            for lam in roots[(np.abs(roots.imag) <= 1e-6 * np.maximum(1, np.abs(roots))) & (roots.real >= -1e-9)]:
                lam = float(lam.real)
                Q = lam * lam * B + lam * D - A
                xi = np.linalg.svd(Q[np.ix_(R, R)])[2][-1]
                inS = np.isin(R, S)
                rest = np.setdiff1d(J, S)
                for v in (xi, -xi):
                    v = v / np.abs(v).max()
                    slack = min([1.0] + list(v[inS]) + list(Q[np.ix_(rest, R)] @ v))
                    if slack > 1e-6:
                        robust.append(lam)
                    if slack > -1e-6:
                        loose.append(lam)
    return robust, loose


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2 ** 31), n=st.integers(2, 4), n_j=st.integers(0, 4), friction=st.booleans())
def test_quadratic_enumeration_against_brute_force(seed, n, n_j, friction):
    rng = np.random.default_rng(seed)
    A, B, D = _random_problem(rng, n, friction=friction)
    J = np.sort(rng.choice(n, size=min(n_j, n), replace=False))
    res = solve_quadratic_eicp(A, B, D, J)
    robust, loose = _brute_force(A, B, D, J)
    got = [s.lam for s in res.solutions]
    for lam in robust:  # every clearly feasible solution is found...
        assert any(abs(lam - g) <= 1e-6 * max(1, lam) for g in got), (lam, got)
    for g in got:  # ...and nothing else is reported
        assert any(abs(lam - g) <= 1e-6 * max(1, g) for lam in loose), (g, loose)
    for s in res.solutions:
        assert s.lam >= -1e-12 and s.residual <= 1e-10
        assert np.all(s.x[J] >= 0) and np.all(s.y[J] >= -1e-10 * np.abs(A).max())
        F = np.setdiff1d(np.arange(n), J)
        r = s.lam ** 2 * B @ s.x + s.lam * D @ s.x - A @ s.x
        assert np.abs(r - s.y).max() < 1e-12 and np.abs(s.y[F]).max(initial=0) < 1e-9
    assert res.status == ("solved" if got else "no_solution")


def test_quadratic_spectrum_against_the_second_linearisation_and_residuals():
    rng = np.random.default_rng(7)
    A, B, D = _random_problem(rng, 12)
    B[3, 4] = B[4, 3] = 0.2  # not diagonal: the QZ path
    for Bk in (np.diag(np.diag(B)), B):
        spec = quadratic_spectrum(A, Bk, D)
        L0, L1 = companion(A, Bk, D, second=True)
        other = sl.eigvals(L0, L1)
        assert spec.lam.size == other.size == 24
        for lam in spec.lam:
            assert np.min(np.abs(other - lam)) <= 1e-8 * max(1, abs(lam))
        assert np.all(spec.residual <= 1e-8)
        for k in range(spec.lam.size):
            assert backward_error(A, Bk, D, spec.lam[k], spec.x[:, k]) == pytest.approx(spec.residual[k])


def test_overdamped_pencil_has_only_real_eigenvalues_and_no_flutter():
    """B = I, D = 10·I, A = −diag(1..6) + a small friction coupling: λ² + 10λ + k has two
    real roots per k, far apart — every eigenvalue real and certified so, no flutter."""
    n = 6
    A = -np.diag(np.arange(1.0, n + 1))
    A[0, 1] = 0.05
    spec = quadratic_spectrum(A, np.eye(n), 10.0 * np.eye(n))
    assert np.all(np.abs(spec.lam.imag) < 1e-12)
    verdict = classify_spectrum(spec)
    assert verdict.flutter is False and verdict.growth.upper == 0.0
    assert verdict.counts["certified_real"] + verdict.counts["decaying"] == 2 * n


def test_an_undamped_oscillation_on_the_imaginary_axis_is_undecided_not_stable():
    """D = 0 with symmetric A ≺ 0, B = I: every λ = ±iω has Re λ = 0 up to rounding — neither
    growing nor decaying can be proved by the quadratic path, so flutter is undecided (the
    undamped path proves it absent through real σ; the damped one must not claim it)."""
    rng = np.random.default_rng(11)
    G = rng.normal(size=(5, 5))
    A = -(G @ G.T + np.eye(5))
    verdict = classify_spectrum(quadratic_spectrum(A, np.eye(5), np.zeros((5, 5))))
    assert verdict.flutter is None and not verdict.modes
    assert verdict.counts["borderline"] == 10 and 0 < verdict.growth.upper < 1e-12


# ------------------------------------------------------------------------------- analyze


def test_damped_divergence_on_two_layers_raises_the_growth_rate():
    """data/scenes/two_layers.toml (μ = 3, every base node slip+): λ = 0.5736 undamped,
    0.5763 with η = 0.02 in both layers (docs/damping.md): the viscous normal reaction enters
    the friction law."""
    undamped = meicp.analyze(TWO_LAYERS)
    r = meicp.analyze(damped(TWO_LAYERS, eta=(0.02, 0.02)))
    assert round(undamped.modes[0].growth_rate, 4) == 0.5736
    assert round(r.modes[0].growth_rate, 4) == 0.5763
    assert r.divergence is True and r.proofs[0].test == "quadratic-enumerate"
    assert r.damping.viscosity == {"A": 0.02, "B": 0.02} and r.to_dict()["damping"]["mass"] == 0.0
    assert "damping: Kelvin–Voigt damping: η(A) = 0.02, η(B) = 0.02" in r.summary()


def _quadratic_pencil(scene):
    """A, B, D of the scene's MEiCP, built here: D from meicp.assemble_damping and the maps."""
    with pencil(scene) as pen:
        C = meicp.assemble_damping(scene)
        return pen.A.toarray(), pen.B.toarray(), (pen.maps.P @ C @ pen.maps.Q).toarray(), pen.maps


def test_damped_modes_solve_the_quadratic_pencil_built_independently():
    s = damped(TWO_LAYERS, eta=(0.05, 0.01), mass=0.02)
    r = meicp.analyze(s)
    A, B, D, maps = _quadratic_pencil(s)
    for m in r.modes:  # divergence: (λ²B + λD − A)x = y, y = 0 off J
        x = np.linalg.lstsq(maps.Q.toarray(), m.x, rcond=None)[0]
        lam = m.growth_rate
        y = lam * lam * B @ x + lam * D @ x - A @ x
        F = np.setdiff1d(np.arange(x.size), maps.J)
        assert np.abs(y[F]).max() <= 1e-8 * np.abs(A).max() and np.all(x[maps.J] >= -1e-12)
    assert r.flutter is True and r.flutter_growth.exact
    for m in r.flutter_modes:
        x = np.linalg.lstsq(maps.Q.toarray(), m.x, rcond=None)[0]
        lam = m.growth_rate + 1j * m.frequency
        assert backward_error(A, B, D, lam, x) <= 1e-8
        assert m.growth_rate > 0 and m.frequency > 0
    # the fastest growth is the largest Re λ > 0 with Im λ ≠ 0 of the second linearisation
    L0, L1 = companion(A, B, D, second=True)
    lam = sl.eigvals(L0, L1)
    fastest = lam[(np.abs(lam.imag) > 1e-6)].real.max()
    assert r.flutter_growth.lower == pytest.approx(fastest, rel=1e-8)


#: a small frictional interface (6 × 4 nodes, 6 pairs slip+ at μ = 1): flutter, no divergence
INTERFACE = two_layer_scene(6, (2, 2), bottom="fixed", stiffness=(2.0, 1.0), density=(1.0, 1.0),
                            interface={"kind": "frictional", "friction": 1.0, "states": "slip+"})


@pytest.mark.parametrize("scene", [TWO_LAYERS, INTERFACE], ids=["two_layers", "interface"])
def test_vanishing_damping_gives_the_undamped_answers(scene):
    today = meicp.analyze(scene)
    r = meicp.analyze(damped(scene, eta=(1e-9, 1e-9)))
    assert r.damping is not None
    assert (r.divergence, r.flutter, r.stable) == (today.divergence, today.flutter, today.stable)
    assert [m.sigma for m in r.modes] == pytest.approx([m.sigma for m in today.modes], rel=1e-6)
    assert len(r.flutter_modes) == len(today.flutter_modes)
    assert r.flutter_growth.lower == pytest.approx(today.flutter_growth.lower, rel=1e-5)
    assert [m.sigma for m in r.flutter_modes] == pytest.approx([m.sigma for m in today.flutter_modes], rel=1e-5)


def test_damping_can_raise_or_lower_the_flutter_threshold():
    """Both effects of issue 31, computed: on the small frictional interface at μ = 0.855 the
    undamped sliding pencil is proved to grow at most 5e-7 (undecided: near-degenerate
    modes) while η = 0.02 in both layers gives a certified flutter mode growing 0.00198 (the
    destabilisation paradox: measured onsets 0.8687 undamped, 0.8431 damped, docs/damping.md);
    on two_layers.toml at μ = 1 the undamped flutter (growth 0.0077) is gone with η = 0.02
    (onsets 0.6308, 1.3845)."""
    u = meicp.analyze(INTERFACE.with_friction(0.855))
    d = meicp.analyze(damped(INTERFACE, eta=(0.02, 0.02)).with_friction(0.855))
    assert u.flutter is not True and u.flutter_growth.upper < 1e-6
    assert d.flutter is True and d.flutter_growth.exact and d.flutter_growth.lower > 1e-3
    u = meicp.analyze(TWO_LAYERS.with_friction(1.0))
    d = meicp.analyze(damped(TWO_LAYERS, eta=(0.02, 0.02)).with_friction(1.0))
    assert u.flutter is True and u.flutter_growth.lower > 5e-3
    assert d.flutter is False and d.flutter_growth.upper == 0.0
    # and the divergence growth rate rises with the viscosity of the base layer
    assert meicp.analyze(damped(TWO_LAYERS, eta=(0.1, 0.01)), flutter=False).modes[0].growth_rate > 0.586


def test_singular_damping_one_layer_without_viscosity_is_decided():
    r = meicp.analyze(damped(TWO_LAYERS, eta=(0.0, 0.05)))
    assert r.divergence is True and r.flutter is not None
    s = two_layer_scene(5, (2, 2), mu=0.3, states="stick")
    r = meicp.analyze(damped(s, eta=(0.0, 0.1)))
    assert r.divergence is False and r.flutter is False and r.stable is True


#: free sides, the top held only vertically, every base node slipping: the lattice can slide as a
#: whole at zero growth (K v = C v = 0 on the reduced DOFs), an exact λ = 0 mode
RIGID_SLIDE = {
    "lattice": {"nx": 3, "spacing": 1.0, "shear": 0.326},
    "layers": [{"name": "L0", "rows": 1, "stiffness": 2.78, "density": 1.19, "viscosity": 2.78},
               {"name": "L1", "rows": 2, "stiffness": 2.24, "density": 0.53, "viscosity": 2.24}],
    "boundary": {"top": "fixed_y", "bottom": "contact", "left": "free", "right": "free"},
    "contact": {"friction": 3.0, "states": "slip-"}, "damping": {"mass": 0.01}}


@pytest.mark.parametrize("eta", [1.0, 1e4])
def test_a_zero_growth_mode_under_heavy_dashpots_is_reported_at_zero(eta):
    """The rigid slide (λ = 0 exactly) under dashpots of η = 10⁴ was reported growing at
    λ = 2.07e-6 — its certificate's row scale, |λ|·max|D_i|, could not tell it from 0 — and
    under η = 1 at λ = −5.5e-13: a candidate within rounding of lam_min is tried there too, and
    the sharper certificate at λ = 0 reports the mode."""
    d = {**RIGID_SLIDE, "layers": [dict(layer, viscosity=eta * f) for layer, f in zip(RIGID_SLIDE["layers"], (1.0, 0.7))]}
    with pencil(scene_from_dict(d)) as pen:
        res = solve_quadratic_eicp(pen.A.toarray(), pen.B.toarray(), pen.damping().toarray(), pen.J)
    assert res.status == "solved" and [s.lam for s in res.solutions] == [0.0]


def test_an_exact_zero_growth_mode_computed_below_zero_is_found_not_proved_absent(monkeypatch):
    """The companion form puts the rigid slide's λ = 0 at about −4e-12, below the enumeration's
    rounding floor (eps·s): it is certified at λ = 0 itself, as the proportional path (the
    undamped MEiCP, σ = 0 within rounding) finds it."""
    scene = scene_from_dict(RIGID_SLIDE)
    with pencil(scene) as pen:
        A, B, D = pen.A.toarray(), pen.B.toarray(), pen.damping().toarray()
        J = pen.J
    res = solve_quadratic_eicp(A, B, D, J)
    assert res.status == "solved" and res.solutions[0].lam == 0.0 and res.solutions[0].residual <= 1e-10
    enumerated = meicp.analyze(scene, flutter=False)
    monkeypatch.setattr(limits, "ENUMERATE_N", 5)
    proportional = meicp.analyze(scene, flutter=False)
    assert "proportional" in proportional.evidence
    assert enumerated.divergence is True is proportional.divergence
    assert abs(enumerated.modes[0].growth_rate) <= 1e-10 and abs(proportional.modes[0].growth_rate) <= 1e-10
    # a real λ below 0 by more than rounding is no solution, nor a doubt: Q'(λ) = Q(λ + c) has
    # the same solutions (x, y) at λ − c, so the slide's at −c
    c = 1e-3
    shifted = solve_quadratic_eicp(A - c * c * B - c * D, B, D + 2 * c * B, J)
    assert shifted.status == "no_solution", shifted.message


def test_heavy_damping_leaves_no_flutter():
    r = meicp.analyze(damped(TWO_LAYERS, eta=(5.0, 5.0), mass=3.0))
    assert r.flutter is False and r.flutter_growth.upper == 0.0


# ------------------------------------------------------------------------------- refused paths


def test_paths_not_built_for_damping_refuse_a_damped_scene():
    s = damped(TWO_LAYERS, eta=(0.02, 0.02))
    with pytest.raises(ProblemError, match="method 'active-set' is not supported with damping yet"):
        meicp.analyze(s, method="active-set")
    free = damped(two_layer_scene(4, (2, 2), bottom="fixed"), eta=(0.1, 0.1))
    with pytest.raises(ProblemError, match="the modal analysis of a scene without contact is not supported"):
        meicp.analyze(free)


def test_a_damped_scene_past_the_enumeration_limits_is_decided_not_refused(monkeypatch):
    """Past the enumeration: the damped Rayleigh bound fails here, and the undamped mode,
    followed to the damped problem, is certified (tests/test_damped_modes.py)."""
    monkeypatch.setattr(limits, "ENUMERATE_N", 10)
    r = meicp.analyze(damped(TWO_LAYERS, eta=(0.02, 0.02)), flutter=False)
    assert r.divergence is True and r.stable is False and r.modes
    assert "damped Rayleigh bound" in r.evidence and "residual inverse iteration" in r.evidence


def test_damping_is_written_to_results_h5_and_the_lattice_xdmf(tmp_path):
    """A damped analysis writes what it used: results.h5 ``/damping`` (read back by
    load_results) and each layer's viscosity; the lattice file each bond's viscosity — the
    mean of its two materials' across them, as C is assembled — and ParaView's XDMF names it
    ``bond_viscosity``.  An undamped scene's files have none of it."""
    import h5py

    from meicp.io.results import write_results

    scene = damped(TWO_LAYERS, eta=(0.02, 0.1))
    result = meicp.analyze(scene)
    paths = write_results(tmp_path / "damped", scene, result, plots=False)
    back = meicp.load_results(paths["results"])
    assert back.damping == result.damping and back.damping.viscosity == {"A": 0.02, "B": 0.1}
    with h5py.File(paths["results"]) as f:
        assert list(f["scene_summary/layers/viscosity"][()]) == [0.02, 0.1]
    with h5py.File(paths["lattice"]) as f:
        ends, eta = f["bonds/connectivity"][()], f["bonds/viscosity"][()]
        material = f["nodes/material"][()]
    expected = 0.5 * (np.array([0.02, 0.1])[material[ends[:, 0]]] + np.array([0.02, 0.1])[material[ends[:, 1]]])
    assert np.array_equal(eta, expected) and set(np.round(eta, 12)) == {0.02, 0.06, 0.1}
    assert 'Attribute Name="bond_viscosity"' in paths["xdmf"].read_text()
    plain = write_results(tmp_path / "plain", TWO_LAYERS, meicp.analyze(TWO_LAYERS), plots=False)
    assert meicp.load_results(plain["results"]).damping is None and "viscosity" not in plain["xdmf"].read_text()
    with h5py.File(plain["results"]) as f, h5py.File(plain["lattice"]) as g:
        assert "damping" not in f and "bonds/viscosity" not in g
