"""The instability analysis: maps, oracles, enumeration against active-set, critical friction."""

import numpy as np
import pytest
import scipy.linalg

import meicp
from meicp import analyze, critical_friction
from meicp.contact.critical_friction.enumerated import friction_pencil
from meicp.contact.lines import contact_lines
from meicp.contact.maps import grazing_cases, reduced_system
from meicp.contact.problem import contact_states
from meicp.core.errors import ProblemError
from meicp.io.scene import loads_scene
from meicp.core import limits
from meicp.eicp.solve import solve_eicp
from meicp.petsc.assembly import LatticeMatrices, assemble
from meicp.lattice.model import LatticeModel

from .conftest import ROOT

SCENES = ROOT / "data" / "scenes"


def cell_scene(states, shear=0.4, mu=1.0, rows=2):
    return loads_scene(f"""
[lattice]
nx = 2
shear = {shear}
[[layers]]
name = "A"
rows = {rows}
stiffness = 1.0
density = 1.0
[boundary]
top = "fixed"
bottom = "contact"
[contact]
friction = {mu}
states = {states!r}
""".replace("'", '"'))


@pytest.mark.parametrize("shear", [0.4, -0.7, 1.5])
def test_single_node_oracle(shear):
    """One slipping node, everything else held: μ_c = k_tt / |k_tn| from K's 2×2 block of
    that node, for slip against the sign of k_tn; no μ_c for the other direction."""
    K, _ = assemble(LatticeModel(cell_scene(["stick", "slip+"], shear)))
    K = K.toarray()
    k_tt, k_tn = K[2, 2], K[2, 3]  # node 1 = (i=1, j=0): DOFs 2 (x), 3 (y)
    assert abs(k_tn) > 1e-3
    good = "slip+" if k_tn < 0 else "slip-"   # s = −sign(k_tn)
    bad = "slip-" if good == "slip+" else "slip+"
    assert critical_friction(cell_scene(["stick", good], shear), flutter=False) == pytest.approx(k_tt / abs(k_tn),
                                                                                                 rel=1e-10)
    assert critical_friction(cell_scene(["stick", bad], shear), flutter=False) == np.inf


def test_single_spring_is_cot_theta():
    """The k_tt/|k_tn| ratio of one bond at angle θ is cot θ: check on the element matrix."""
    from .helpers import bond_stiffness

    for theta in (0.3, 0.9, 1.2):
        K = bond_stiffness([[0, 0], [np.cos(theta), np.sin(theta)]], [[0, 1]], 2.0).toarray()
        assert K[0, 0] / abs(K[0, 1]) == pytest.approx(1 / np.tan(theta))


def test_maps_by_hand_on_the_cell():
    """A = −PKQ, B = PMQ for states [slip-, separated] built independently in dense form."""
    scene = cell_scene(["slip-", "separated"], 0.2, mu=0.7)
    model = LatticeModel(scene)
    K, M = (m.toarray() for m in assemble(model))
    red = reduced_system(model, contact_lines(scene, model))
    # retained: node 0 x (slip-, column −e_0), node 1 x and y (free); top row fixed
    Q = np.zeros((8, 3))
    Q[0, 0], Q[2, 1], Q[3, 2] = -1.0, 1.0, 1.0
    P = np.zeros((3, 8))
    P[0, 0], P[0, 1] = -1.0, 0.7      # s·e_t + μ·e_n
    P[1, 2] = P[2, 3] = 1.0
    assert np.allclose(red.Q.toarray(), Q) and np.allclose(red.P.toarray(), P)
    assert red.J.tolist() == [0]


def test_two_layers_unstable_above_and_stable_below_critical_friction():
    mu_c = critical_friction(SCENES / "two_layers.toml", flutter=False)
    assert 1.0 < mu_c < 3.0
    unstable = analyze(SCENES / "two_layers.toml")
    assert unstable.stable is False and unstable.modes and unstable.modes[0].sigma > 0
    assert unstable.modes[0].growth_rate == pytest.approx(np.sqrt(unstable.modes[0].sigma))
    stable = analyze(SCENES / "two_layers_below_mu_c.toml")
    assert stable.divergence is False and "a proof" in stable.evidence
    assert stable.states == ["slip+"] * 5


def test_slip_direction_matters_on_a_sheared_lattice():
    plus = critical_friction(SCENES / "sheared_slip_plus.toml", flutter=False)
    minus = critical_friction(SCENES / "sheared_slip_minus.toml", flutter=False)
    assert abs(plus - minus) > 0.5
    assert analyze(SCENES / "sheared_slip_minus.toml").stable is False
    assert analyze(SCENES / "sheared_slip_plus.toml").divergence is False


def test_modes_are_certified_and_in_natural_numbering():
    r = analyze(SCENES / "two_layers.toml")
    model = LatticeModel(meicp.load_scene(SCENES / "two_layers.toml"))
    for m in r.modes:
        assert m.x.shape == (model.n_dofs,) and abs(np.linalg.norm(m.x) - 1) < 1e-12
        assert np.all(m.x[model.constrained_dofs()] == 0)
        assert m.residual <= 1e-10
        # slipping nodes: v_n = 0 and v_t ≥ 0 in the slip direction (slip+)
        bottom = np.arange(model.nx)
        assert np.all(m.x[2 * bottom + 1] == 0) and np.all(m.x[2 * bottom] >= -1e-12)


def test_active_set_mode_is_among_the_enumerated_ones():
    scene = meicp.load_scene(SCENES / "sheared_slip_minus.toml")
    every = analyze(scene, method="enumerate")
    one = analyze(scene, method="active-set")
    assert one.stable is False
    assert any(abs(m.sigma - one.modes[0].sigma) <= 1e-9 * m.sigma for m in every.modes)


def test_stick_everywhere_is_a_plain_eigenproblem():
    """All nodes sticking: no complementarity; the modes are the generalized eigenpairs of the
    lattice with the bottom row fixed, none with σ ≥ 0 (K SPD): stable by enumeration."""
    r = analyze(cell_scene("stick", rows=4))
    assert r.stable is True and r.sizes["complementarity"] == 0 and r.sizes["retained"] == 8
    held = analyze(cell_scene("stick"))  # nothing left to move
    assert held.stable is True and "every DOF is held" in held.evidence


def test_frictional_interface_all_stick_equals_tied_lattice():
    """Sticking pairs tie u_upper = u_lower: the pencil's eigenvalues equal the limit of the
    same lattice with stiff penalty springs between the pairs (an independent construction)."""
    text = (SCENES / "frictional_interface.toml").read_text().replace('states = "slip+"', 'states = "stick"')
    scene = loads_scene(text)
    model = LatticeModel(scene)
    K, M = assemble(model)
    red = reduced_system(model, contact_lines(scene, model))
    A, B = -(red.P @ K @ red.Q).toarray(), (red.P @ M @ red.Q).toarray()
    tied = np.sort(scipy.linalg.eigvals(A, B).real)[::-1][:4]
    lower, upper = model.interface_node_pairs(0)
    free = model.free_dofs()
    Kd, Md = K.toarray(), M.toarray()
    for kp in (1e6,):
        Kp = Kd.copy()
        for a, b in zip(lower, upper):
            for c in (0, 1):
                i, j = 2 * a + c, 2 * b + c
                Kp[i, i] += kp
                Kp[j, j] += kp
                Kp[i, j] -= kp
                Kp[j, i] -= kp
        pen = np.sort(-scipy.linalg.eigh(Kp[np.ix_(free, free)], Md[np.ix_(free, free)], eigvals_only=True))[::-1][:4]
        assert np.allclose(pen, tied, rtol=1e-4)
    # tied pairs keep their centre of mass (diagonal B); sliding pairs add d, which the mass
    # does not couple to it: B stays diagonal
    sliding = meicp.load_scene(SCENES / "frictional_interface.toml")
    red = reduced_system(LatticeModel(sliding), contact_lines(sliding, LatticeModel(sliding)))
    Bs = (red.P @ M @ red.Q).toarray()
    assert np.count_nonzero(Bs - np.diag(np.diag(Bs))) == 0 and np.diag(Bs).min() > 0


def _free_pencil(scene):
    """K and M on the DOFs no boundary holds (dense), for SciPy's eigh."""
    K, M = assemble(scene)
    free = np.setdiff1d(np.arange(scene.n_dofs), LatticeModel(scene).constrained_dofs())
    return K.toarray()[np.ix_(free, free)], M.toarray()[np.ix_(free, free)], free


def test_a_scene_without_contact_gets_its_lowest_vibration_modes():
    """`solve` refused sheared.toml ("no contact"): a modal analysis instead, σ = −ω² of
    K v = ω² M v on the free DOFs, certified, and a proof (inertia) that nothing has σ ≥ 0."""
    scene = meicp.load_scene(SCENES / "sheared.toml")
    r = analyze(scene)
    assert r.analysis == "modal" and r.success and r.stable is True and r.verdict.startswith("NO CONTACT")
    assert "positive definite" in r.evidence and "no frictional instability" in r.evidence
    Kf, Mf, free = _free_pencil(scene)
    omega2 = scipy.linalg.eigh(Kf, Mf, eigvals_only=True)[:6]
    assert [m.sigma for m in r.modes] == pytest.approx(-omega2, rel=1e-9)
    for m in r.modes:
        assert m.frequency == pytest.approx(np.sqrt(-m.sigma)) and m.growth_rate == 0.0 and m.support.size == 0
        assert m.residual <= 1e-10 and np.linalg.norm(m.x) == pytest.approx(1.0)
        held = np.setdiff1d(np.arange(scene.n_dofs), free)
        assert np.all(m.x[held] == 0.0)
        v = m.x[free]
        assert np.linalg.norm(Kf @ v + m.sigma * (Mf @ v)) <= 1e-8 * np.linalg.norm(Kf @ v)
    assert len(analyze(scene, nev=2).modes) == 2


def test_a_lattice_nothing_holds_has_zero_frequency_motions_and_no_verdict():
    """The free 4-node cell: 3 rigid-body motions (σ = 0) are neither a frictional
    instability nor oscillations; stable is None and the evidence counts them."""
    scene = meicp.load_scene(SCENES / "four_node_cell.toml")
    r = analyze(scene)
    assert r.analysis == "modal" and r.success and r.stable is None
    assert "3 eigenvalue(s) σ ≥ 0" in r.evidence and "rigid-body" in r.evidence
    Kf, Mf, _ = _free_pencil(scene)
    omega2 = scipy.linalg.eigh(Kf, Mf, eigvals_only=True)[:6]
    sigma = np.array([m.sigma for m in r.modes])
    assert np.abs(sigma[:3]).max() <= 1e-12 and sigma[3:] == pytest.approx(-omega2[3:], rel=1e-9)


def test_bad_scenes():
    with pytest.raises(ProblemError, match="one state per column"):
        analyze(cell_scene(["stick", "slip+", "slip+"]))
    with pytest.raises(ProblemError, match="slide"):
        analyze(cell_scene(["stick", "slide"]))


# ----------------------------------------------------------------- critical_friction condensed
TWO_LAYERS = (SCENES / "two_layers.toml").read_text().replace("top_displacement = [0.06, -0.1]", "")


def _two_layers(base=None, interface=None, top="fixed"):
    text = TWO_LAYERS.replace('top = "fixed"', f'top = "{top}"')
    if base is not None:
        text = text.replace('states = "slip+"', f"states = {base}")
    if interface is not None:
        text = text.replace('kind = "bonded"', f'kind = "frictional"\nfriction = 0.5\nstates = {interface}')
    return loads_scene(text)


@pytest.mark.parametrize("name, value", [("two_layers", 1.90603249044423),
                                         ("sheared_slip_plus", 4.2510780089706754),
                                         ("sheared_slip_minus", 1.4736958249387473)])
def test_condensed_critical_friction_equals_the_stored_values(name, value):
    """Values of the former uncondensed enumeration (whole reduced lattice per support)."""
    assert critical_friction(SCENES / f"{name}.toml", flutter=False) == pytest.approx(value, rel=1e-10)


def _uncondensed_critical_friction(scene, mu_max=1e3):
    """The reference: the EiCP in μ, ``(μB′ − A′)x = y``, enumerated on the whole reduced
    lattice (no condensation; order r per support), the smallest μ over the grazing cases."""
    lattice = LatticeMatrices(LatticeModel(scene))
    lines, _ = contact_states(scene, lattice)
    mus = [np.inf]
    for case in grazing_cases(lines):
        red = reduced_system(lattice.model, lines, case)
        if red.J.size:
            A1, B1 = friction_pencil(lattice.K, red)
            r = solve_eicp(A1.toarray(), B1.toarray(), J=red.J, method="enumerate", lam_min=0.0, tol=1e-9,
                           max_j=limits.EICP_MAX_J)
            mus += [s.lam for s in r.solutions if 0.0 <= s.lam <= mu_max]
    return min(mus)


@pytest.mark.parametrize("scene", [
    pytest.param(lambda: meicp.load_scene(SCENES / "frictional_interface.toml"), id="frictional-interface"),
    pytest.param(lambda: meicp.load_scene(SCENES / "interface_shear_compression.toml"), id="interface-static-states"),
    pytest.param(lambda: _two_layers('["grazing", "slip+", "slip+", "grazing", "slip+"]'), id="two-grazing"),
    pytest.param(lambda: _two_layers('["separated", "grazing", "slip-", "slip-", "stick"]'), id="grazing-separated"),
    pytest.param(lambda: _two_layers('["slip+", "stick", "slip+", "slip+", "separated"]',
                                     '["stick", "slip-", "separated", "slip+", "grazing"]'), id="base-and-interface"),
])
def test_condensed_critical_friction_equals_the_uncondensed_one(scene):
    sc = scene()
    old = _uncondensed_critical_friction(sc)
    new = critical_friction(sc, flutter=False)  # with its bisection check (small: it runs)
    assert np.isfinite(old) and new == pytest.approx(old, rel=1e-10)


def test_zero_stiffness_motion_against_the_slip_directions_still_works():
    """A free top: the block can slide as a whole.  With mixed slip directions that motion
    is not sign-feasible, −Ac is singular, the enumeration meets singular pencils and the
    bisection check (required then) confirms the value of the uncondensed path; the same
    for the lower layer between a sliding base and a sliding interface."""
    for sc in (_two_layers('["slip+", "slip+", "slip-", "slip-", "slip-"]', top="free"),
               _two_layers(interface='"slip+"')):
        old = _uncondensed_critical_friction(sc)
        assert critical_friction(sc, bisection=True, flutter=False) == pytest.approx(old, rel=1e-10)


def test_zero_stiffness_motion_along_the_slip_directions_is_refused():
    """The old path returned a number here (6.46; 0.64), but a σ = 0 motion exists at every
    μ: the whole block sliding to the right, or a floating upper layer."""
    with pytest.raises(ProblemError, match="μ_c is undefined"):
        critical_friction(_two_layers(top="free"), bisection=False)
    with pytest.raises(ProblemError, match="μ_c is undefined"):
        critical_friction(_two_layers(interface='"separated"', top="free"), bisection=False)


def test_critical_friction_beyond_the_enumeration_limit_is_a_bracket():

    wide = TWO_LAYERS.replace("nx = 5", f"nx = {limits.CRITICAL_J + 1}")
    mu = critical_friction(loads_scene(wide), flutter=False)
    assert mu.lower <= mu == mu.upper < np.inf and "lower end" in mu.evidence


def test_condensed_critical_friction_beyond_the_former_limit():
    """|J| = 17 > 16 (the former limit), r = 255: enumerated in seconds; the σ-problem is too
    large for the bisection check, which is skipped by default; μ_c lies between the values
    of the narrower lattices' trend (two_layers: nx = 5 gives 1.906)."""
    sc = loads_scene(TWO_LAYERS.replace("nx = 5", "nx = 17"))
    mu = critical_friction(sc, flutter=False)
    assert 1.0 < mu < 3.0
    # the smallest certified σ = 0 solution: just above it analyze finds a mode
    above, below = sc.with_friction(mu * (1 + 1e-4)), sc.with_friction(mu * (1 - 1e-4))
    assert analyze(above, method="active-set").stable is False
    assert analyze(below, method="active-set").divergence is not True


def test_exact_zero_sigma_slide_is_a_mode_whatever_the_rounding_sign():
    """A free top with every base node slip+: the whole block slides right at zero stiffness,
    an exact σ = 0 solution at every μ.  Its σ comes out ±1e-15; the λ ≥ lam_min filter must
    allow rounding (eicp.problem.lam_floor), else the enumeration "proves" stability at the
    μ where the sign is negative (0.5 and 3 here)."""
    for mu in (0.5, 1.0, 3.0):
        sc = loads_scene(TWO_LAYERS.replace('top = "fixed"', 'top = "free"').replace("friction = 3.0",
                                                                                   f"friction = {mu}"))
        r = analyze(sc)
        assert r.stable is False and abs(r.modes[0].sigma) < 1e-12, mu


def test_critical_friction_without_slip_skips_a_large_bisection_and_handles_no_dofs():
    """No slip or grazing contact: μ_c = inf.  The σ-problem of a large lattice is not
    enumerated by the default check (it used to raise "|F| = 2200 is too large"), and a
    lattice with every DOF held gives inf (it used to raise "A is empty")."""
    stick = TWO_LAYERS.replace('states = "slip+"', 'states = "stick"')
    big = stick.replace("nx = 5", "nx = 50").replace("rows = 2", "rows = 12")
    assert critical_friction(loads_scene(big)) == np.inf
    assert critical_friction(loads_scene(stick.replace("rows = 2", "rows = 1"))) == np.inf


def test_scene_petsc_options_apply_on_every_solve(capfd, caplog):
    """A scene's [petsc] table reaches the active-set's eigen-solves as the command line does:
    an option read at solve time (eps_view) takes effect, and one that nothing reads is
    reported, once (it used to be the other way round for eps_view: dropped after set-up)."""
    text = (SCENES / "two_layers.toml").read_text().replace(
        "eps_tol = 1e-10", "eps_tol = 1e-10\neps_view = true\neps_no_such_option = 3")
    r = analyze(loads_scene(text), method="active-set")
    assert r.stable is False
    out = capfd.readouterr().out
    solves = r.eicp[0].coverage["eigen_solves"]
    assert out.count("EPS Object: (meicp_as_)") == solves >= 1
    assert r.eicp[0].coverage["unused_options"] == ["meicp_as_eps_no_such_option"]
    warned = [rec.getMessage() for rec in caplog.records if "not used" in rec.getMessage()]
    assert warned == ["PETSc options not used by any solver: -meicp_as_eps_no_such_option"]
