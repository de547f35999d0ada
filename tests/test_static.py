"""Static frictional equilibrium (meicp.contact.static): contact states from the LCP.

Every check recomputes what it verifies independently of the module where it can:
reactions from ``K u − f`` of a fresh assembly, the LCP certificate from (M, q), the contact
laws from the returned arrays, the condensed LCP against Siconos.
"""

import dataclasses

import numpy as np
import pytest

from meicp.core.errors import ProblemError
from meicp.contact.static import TOL, StaticResult, static_equilibrium
from meicp.io.scene import scene_from_dict
from meicp.petsc.assembly import assemble
from meicp.scene import Load
from meicp.lattice.model import LatticeModel

LAYERS = [{"name": "A", "rows": 2, "stiffness": 1.0, "density": 1.0},
          {"name": "B", "rows": 2, "stiffness": 5.0, "density": 2.0}]


def scene(nx=5, *, top="fixed", bottom="contact", left="free", right="free", mu=0.5, load=None,
          interfaces=None, layers=None):
    d = {"lattice": {"nx": nx}, "layers": layers or LAYERS,
         "boundary": {"top": top, "bottom": bottom, "left": left, "right": right}}
    if bottom == "contact":
        d["contact"] = {"friction": mu, "states": "solve"}
    if load is not None:
        d["load"] = load
    if interfaces:
        d["interfaces"] = interfaces
    return scene_from_dict(d)


def frictional(mu=0.4, below="A"):
    return [{"below": below, "kind": "frictional", "friction": mu}]


def residual_forces(s, r: StaticResult):
    """``K u − f_ext`` from a fresh assembly: the forces the contacts and the Dirichlet
    boundary exert on the lattice, per DOF."""
    model = LatticeModel(s)
    K, _ = assemble(model)
    f = np.zeros(model.n_dofs)
    if s.load is not None and s.load.gravity:
        f[1::2] = -s.load.gravity * model.mass()
    return K @ r.u - f, model


def contact_force_vector(s, r: StaticResult, model):
    """The nodal forces of the returned reactions, built by hand from the conventions:
    base reaction on the bottom node; interface reaction +r on the upper, −r on the lower."""
    F = np.zeros(model.n_dofs)
    if r.r_n is not None:
        nodes = np.arange(s.nx)
        F[2 * nodes] += r.r_t
        F[2 * nodes + 1] += r.r_n
    for itf in s.frictional_interfaces():
        lower, upper = model.interface_node_pairs(itf.index)
        rn, rt = r.interface_r_n[itf.below], r.interface_r_t[itf.below]
        F[2 * upper] += rt
        F[2 * upper + 1] += rn
        F[2 * lower] -= rt
        F[2 * lower + 1] -= rn
    return F


def check_equilibrium(s, r: StaticResult):
    """On every free DOF, K u − f equals the contact forces (to rounding)."""
    res, model = residual_forces(s, r)
    F = contact_force_vector(s, r, model)
    free = model.free_dofs()
    scale = max(np.abs(res).max(), np.abs(F).max(), 1e-300)
    assert np.abs(res[free] - F[free]).max() <= 1e-10 * scale
    return res, model


def check_laws(r: StaticResult, mu, rn, rt, gap, slip, held=None):
    """Signorini and Coulomb on the returned arrays, and the states' meaning."""
    F, D = r.tolerances["force_scale"], r.tolerances["displacement_scale"]
    held = np.zeros(rn.size, bool) if held is None else held
    assert np.all(rn >= -1e-12 * F)
    assert np.all(gap[~held] >= -1e-10 * max(D, 1e-300))
    assert np.all(np.abs(rn * gap) <= 1e-10 * max(F * D, 1e-300))
    assert np.all(np.abs(rt) <= mu * rn * (1 + 1e-9) + 1e-12 * F)
    return F, D


def states_consistent(states, mu, rn, rt, slip, F, D):
    for st, n, t, u in zip(states, rn, rt, slip):
        if st in ("slip+", "slip-"):
            s = 1.0 if st == "slip+" else -1.0
            assert n > 0
            assert t == pytest.approx(-s * mu * n, abs=1e-9 * F)   # r_t = −s μ r_n
            assert s * u >= -1e-9 * D                               # it slides in direction s
        elif st == "stick":
            assert n > 0 and abs(t) < mu * n and abs(u) <= 1e-9 * D
        elif st == "separated":
            assert abs(n) <= 1e-9 * F
        else:
            assert st == "grazing"


def lcp_certificate(r: StaticResult, tol=1e-9):
    M, q, x = r.lcp_matrix, r.lcp_q, r.lcp.x
    w = M @ x + q
    sx = max(np.abs(x).max(), 1e-300)
    sw = max(np.abs(q).max(), np.abs(M).max() * sx)
    assert x.min() >= -tol * sx
    assert w.min() >= -tol * sw
    assert np.abs(x * w).max() <= tol * sx * sw


# ------------------------------------------------------------------------ base contact

def test_vertical_compression_all_stick_and_global_equilibrium():
    s = scene(7, mu=1.0, load={"top_displacement": [0.0, -0.1]})
    r = static_equilibrium(s)
    assert r.success and r.lcp.success
    lcp_certificate(r)
    assert r.states == ["stick"] * 7
    assert np.all(r.r_n > 0)
    # symmetric geometry: r_n symmetric, r_t antisymmetric, the middle column has r_t = 0
    assert np.allclose(r.r_n, r.r_n[::-1], rtol=1e-10)
    assert np.allclose(r.r_t, -r.r_t[::-1], atol=1e-12)
    check_laws(r, 1.0, r.r_n, r.r_t, r.gap, r.slip)
    res, model = check_equilibrium(s, r)
    top = model.side_nodes("top")
    # Σ r_n equals the total vertical reaction at the top (K u − f there), independently
    assert r.r_n.sum() == pytest.approx(-res[2 * top + 1].sum(), rel=1e-10)
    assert r.r_t.sum() == pytest.approx(-res[2 * top].sum(), abs=1e-12)
    assert r.equilibrium_residual < 1e-10
    assert r.u.shape == (s.n_dofs,)
    assert np.allclose(r.u[2 * top + 1], -0.1) and np.allclose(r.u[2 * top], 0.0)


def test_compression_small_friction_bottom_slides_outward():
    s = scene(7, mu=0.05, load={"top_displacement": [0.0, -0.1]})
    r = static_equilibrium(s)
    assert r.success
    F, D = check_laws(r, 0.05, r.r_n, r.r_t, r.gap, r.slip)
    states_consistent(r.states, 0.05, r.r_n, r.r_t, r.slip, F, D)
    # the squeezed lattice spreads: left half slides left, right half right, middle sticks
    assert r.states[:3] == ["slip-"] * 3 and r.states[4:] == ["slip+"] * 3
    assert r.states[3] == "stick"
    assert np.all(r.slip[:3] < 0) and np.all(r.slip[4:] > 0)
    check_equilibrium(s, r)


def test_shear_and_compression_slip_follows_the_shear():
    s = scene(7, mu=0.05, load={"top_displacement": [0.05, -0.1]})
    r = static_equilibrium(s)
    assert r.success
    lcp_certificate(r)
    F, D = check_laws(r, 0.05, r.r_n, r.r_t, r.gap, r.slip)
    states_consistent(r.states, 0.05, r.r_n, r.r_t, r.slip, F, D)
    # the top moves +x: most of the base slides +x, friction on it points −x
    assert r.states.count("slip+") >= 5
    assert r.r_t.sum() < 0
    for st, u, t in zip(r.states, r.slip, r.r_t):
        if st == "slip+":
            assert u > 0 and t < 0
    res, model = check_equilibrium(s, r)
    top = model.side_nodes("top")
    assert r.r_t.sum() == pytest.approx(-res[2 * top].sum(), rel=1e-10)
    # mirror the shear: the states mirror with slip+ ↔ slip-
    m = static_equilibrium(scene(7, mu=0.05, load={"top_displacement": [-0.05, -0.1]}))
    flip = {"slip+": "slip-", "slip-": "slip+"}
    assert m.states == [flip.get(x, x) for x in r.states[::-1]]


def test_large_friction_shear_sticks():
    r = static_equilibrium(scene(5, mu=2.0, load={"top_displacement": [0.02, -0.1]}))
    assert r.states == ["stick"] * 5
    assert np.all(np.abs(r.slip) <= 1e-9 * r.tolerances["displacement_scale"])


def test_uplift_without_gravity_separates():
    r = static_equilibrium(scene(5, mu=0.5, load={"top_displacement": [0.0, 0.1]}))
    assert r.success
    assert r.states == ["separated"] * 5
    assert np.all(r.r_n == 0) and np.all(r.r_t == 0)
    assert np.all(r.gap > 0.05)


def test_gravity_on_a_free_top_weight_carried_by_the_base():
    # top and sides free: the lattice rests on the base; its rigid-body modes are held by contact
    s = scene(5, top="free", mu=0.5, load={"gravity": 2.0})
    r = static_equilibrium(s)
    assert r.success and r.rigid_modes == 3
    lcp_certificate(r)
    weight = 2.0 * LatticeModel(s).total_mass()
    assert r.r_n.sum() == pytest.approx(weight, rel=1e-10)
    assert r.r_t.sum() == pytest.approx(0.0, abs=1e-10 * weight)
    assert all(st in ("stick", "slip+", "slip-") for st in r.states)
    check_laws(r, 0.5, r.r_n, r.r_t, r.gap, r.slip)
    check_equilibrium(s, r)


def test_frictionless_base():
    s = scene(7, mu=0.0, load={"top_displacement": [0.0, -0.1]})
    r = static_equilibrium(s)
    assert r.success
    assert np.all(r.r_t == 0) and np.all(r.r_n > 0)
    assert r.lcp_matrix.shape == (7, 7)             # no friction unknowns
    assert r.classes.p_matrix is True and r.classes.spd is True
    assert any("Uniqueness" in g for g in r.guarantees)
    # every contact slips (the cone |r_t| ≤ 0 is saturated): outward by the sign of u_t; the
    # middle column has not moved and the load pushes it nowhere → slip+ by convention
    assert r.states == ["slip-"] * 3 + ["slip+"] * 4
    check_equilibrium(s, r)
    sh = static_equilibrium(scene(7, mu=0.0, load={"top_displacement": [0.05, -0.1]}))
    assert sh.states.count("slip+") >= 6 and np.all(sh.r_t == 0)


def test_siconos_agrees_on_the_condensed_lcp():
    pytest.importorskip("siconos.numerics")
    from meicp.lcp.siconos import siconos_solve

    for mu, load in ((1.0, [0.0, -0.1]), (0.0, [0.05, -0.1]), (0.05, [0.05, -0.1])):
        r = static_equilibrium(scene(6, mu=mu, load={"top_displacement": load}))
        peer = siconos_solve(r.lcp_matrix, r.lcp_q, "lemke")
        assert peer.success, peer.message
        a, b = r.split_lcp(r.lcp.x), r.split_lcp(peer.x)
        # the reactions (not λ, β± individually) are what must be unique
        assert np.allclose(a["r_n"], b["r_n"], rtol=1e-8, atol=1e-12)
        assert np.allclose(a["r_t"], b["r_t"], rtol=1e-8, atol=1e-12)
        assert np.allclose(a["r_n"], r.r_n[a["normal"]])


def test_classes_and_guarantees_reported():
    r = static_equilibrium(scene(3, mu=0.5, load={"top_displacement": [0.0, -0.1]}))
    n = r.lcp_matrix.shape[0]
    assert n == 3 * 4 and r.classes.n == n and r.classes.exact_limit == 12
    # the friction split: zero λ diagonal → not P; λ alone solves LCP(0, M) → not R0
    assert r.classes.p_matrix is False and r.classes.r0 is False
    assert r.guarantees and all(isinstance(g, str) for g in r.guarantees)
    assert any("friction split" in g for g in r.guarantees)
    assert any("G_nn is SPD" in g for g in r.guarantees)
    assert set(r.tolerances) >= {"tol", "force_scale", "displacement_scale", "gap", "cone"}
    assert r.tolerances["tol"] == TOL
    assert r.timings["total"] > 0 and "lcp" in r.timings and "classify" in r.timings


# ------------------------------------------------------------------------ interfaces

def test_frictional_interface_under_compression_equal_and_opposite():
    s = scene(5, bottom="fixed", load={"top_displacement": [0.0, -0.1]}, interfaces=frictional(0.4))
    r = static_equilibrium(s)
    assert r.success and r.states == [] and r.r_n is None
    st, rn, rt = r.interface_states["A"], r.interface_r_n["A"], r.interface_r_t["A"]
    assert all(x in ("stick", "slip+", "slip-") for x in st)
    assert np.all(rn > 0)
    check_laws(r, 0.4, rn, rt, r.interface_gap["A"], r.interface_slip["A"])
    res, model = check_equilibrium(s, r)
    lower, upper = model.interface_node_pairs(0)
    # the contact puts +r on the upper node and −r on the lower, seen in K u independently
    assert np.allclose(res[2 * upper + 1], rn, rtol=1e-10)
    assert np.allclose(res[2 * lower + 1], -rn, rtol=1e-10)
    assert np.allclose(res[2 * upper], rt, atol=1e-12)
    assert np.allclose(res[2 * lower], -rt, atol=1e-12)
    top = model.side_nodes("top")
    assert rn.sum() == pytest.approx(-res[2 * top + 1].sum(), rel=1e-10)


def test_frictional_interface_shear_slip_sign():
    s = scene(5, bottom="fixed", load={"top_displacement": [0.1, -0.1]}, interfaces=frictional(0.4))
    r = static_equilibrium(s)
    st, rn, rt, d = (r.interface_states["A"], r.interface_r_n["A"], r.interface_r_t["A"],
                     r.interface_slip["A"])
    F, D = r.tolerances["force_scale"], r.tolerances["displacement_scale"]
    states_consistent(st, 0.4, rn, rt, d, F, D)
    # the upper layer is dragged +x over the lower one: slip+ (relative), friction −x on it
    assert st.count("slip+") >= 3 and "slip-" not in st


def test_base_and_interface_together_lower_layer_held_by_contacts():
    s = scene(5, mu=0.5, load={"top_displacement": [0.02, -0.1]}, interfaces=frictional(0.4))
    r = static_equilibrium(s)
    assert r.success and r.rigid_modes == 3   # the lower layer floats between two contacts
    assert len(r.states) == 5 and len(r.interface_states["A"]) == 5
    assert np.all(r.r_n > 0) and np.all(r.interface_r_n["A"] > 0)
    check_equilibrium(s, r)
    # vertical equilibrium of the lower layer alone: base pushes up what the interface pushes down
    assert r.r_n.sum() == pytest.approx(r.interface_r_n["A"].sum(), rel=1e-9)


# ------------------------------------------------------------------------ side loads, held

def test_side_shortening_forces_corner_slip():
    s = scene(7, top="free", left="fixed_x", right="fixed_x", mu=0.1,
              load={"side_displacement": [0.05, -0.05], "gravity": 0.2})
    assert s.load.side_displacement == (0.05, -0.05)
    r = static_equilibrium(s)
    assert r.success
    # the corners are pushed inward by the side pistons: forced slip toward the middle
    assert r.states[0] == "slip+" and r.states[-1] == "slip-"
    assert r.slip[0] == pytest.approx(0.05) and r.slip[-1] == pytest.approx(-0.05)
    assert r.r_t[0] == pytest.approx(-0.1 * r.r_n[0]) and r.r_t[-1] == pytest.approx(0.1 * r.r_n[-1])
    weight = 0.2 * LatticeModel(s).total_mass()
    assert r.r_n.sum() == pytest.approx(weight, rel=1e-10)   # sides fixed in x only
    check_equilibrium(s, r)


def test_fixed_sides_hold_the_bottom_corners():
    s = scene(5, top="fixed", left="fixed", right="fixed", mu=0.5,
              load={"top_displacement": [0.0, -0.1]})
    r = static_equilibrium(s)
    assert r.success
    assert r.held.tolist() == [True, False, False, False, True]
    assert r.states[0] == r.states[-1] == "stick" and r.r_n[0] == 0 and r.r_n[-1] == 0
    assert np.all(r.r_n[1:-1] > 0)
    check_equilibrium(s, r)


# ------------------------------------------------------------------------ bad input, failures

def test_load_with_no_contact_is_an_error():
    s = scene(5, bottom="fixed", load={"top_displacement": [0.0, -0.1]})
    with pytest.raises(ProblemError, match="a load with no contact"):
        static_equilibrium(s)


def test_side_displacement_on_a_free_side_is_an_error():
    with pytest.raises(ProblemError, match=r"load\.side_displacement"):
        scene(5, load={"side_displacement": [0.05, 0.0]})
    with pytest.raises(ProblemError, match=r"load\.side_displacement"):
        scene(5, left="fixed_y", load={"side_displacement": [0.05, 0.0]})
    with pytest.raises(ProblemError, match=r"load\.side_displacement"):
        scene(5, load={"side_displacement": [0.05]})
    # a scene built in code bypasses the parser: the solver checks again
    s = dataclasses.replace(scene(5, load={"top_displacement": [0.0, -0.1]}),
                            load=Load(top_displacement=(0.0, -0.1), side_displacement=(0.0, -0.02)))
    with pytest.raises(ProblemError, match=r"load\.side_displacement.*right"):
        static_equilibrium(s)


def test_singular_stiffness_is_reported():
    # a block on a frictionless base: nothing holds its x translation
    with pytest.raises(ProblemError, match="held neither by the Dirichlet boundary"):
        static_equilibrium(scene(5, top="free", mu=0.0, load={"gravity": 1.0}))
    with pytest.raises(ProblemError, match="Dirichlet boundary"):
        static_equilibrium(scene(5, top="free", mu=0.5, load={"gravity": 1.0}), allow_floating=False)
    # a one-row layer between two frictional interfaces is a mechanism
    layers = LAYERS[:1] + [{"name": "M", "rows": 1, "stiffness": 1.0, "density": 1.0}] + [
        {"name": "C", "rows": 2, "stiffness": 1.0, "density": 1.0}]
    with pytest.raises(ProblemError, match="'M'.*mechanism"):
        static_equilibrium(scene(5, bottom="fixed", layers=layers, load={"top_displacement": [0, -0.1]},
                                 interfaces=frictional(0.4, "A") + frictional(0.4, "M")))


def test_failed_lcp_reports_no_states():
    # gravity pointing up on a free block: no equilibrium exists
    r = static_equilibrium(scene(4, top="free", mu=0.5, load={"gravity": -1.0}))
    assert not r.success and r.status == r.lcp.status
    assert r.states == [] and r.u is None
    assert "no contact states" in r.message


def test_too_many_contacts_is_honest():
    s = scene(1001, mu=0.5, load={"top_displacement": [0.0, -0.1]}, interfaces=frictional(0.4))
    with pytest.raises(ProblemError, match="condensed dense formulation's limit.*mixed"):
        static_equilibrium(s, formulation="condensed")


# ------------------------------------------------------------------------ mixed formulation

MIXED_SCENES = {
    "compression_large_mu_stick": lambda: scene(7, mu=1.0, load={"top_displacement": [0.0, -0.1]}),
    "shear_small_mu_slip": lambda: scene(7, mu=0.05, load={"top_displacement": [0.05, -0.1]}),
    "uplift_separated": lambda: scene(5, mu=0.5, load={"top_displacement": [0.0, 0.1]}),
    "frictional_interface": lambda: scene(5, bottom="fixed", load={"top_displacement": [0.1, -0.1]},
                                          interfaces=frictional(0.4)),
    "frictionless": lambda: scene(7, mu=0.0, load={"top_displacement": [0.0, -0.1]}),
    "base_and_interface_floating": lambda: scene(5, mu=0.5, load={"top_displacement": [0.02, -0.1]},
                                                 interfaces=frictional(0.4)),
    "gravity_free_top": lambda: scene(5, top="free", mu=0.5, load={"gravity": 2.0}),
    "side_shortening": lambda: scene(7, top="free", left="fixed_x", right="fixed_x", mu=0.1,
                                     load={"side_displacement": [0.05, -0.05], "gravity": 0.2}),
    "medium_shear_slip": lambda: scene(100, mu=0.3, load={"top_displacement": [0.05, -0.05]}),
    "medium_stick": lambda: scene(100, mu=2.0, load={"top_displacement": [0.01, -0.05]}),
    "medium_interface": lambda: scene(50, bottom="fixed", load={"top_displacement": [0.05, -0.1]},
                                      interfaces=frictional(0.2)),
}


def assert_same_equilibrium(a: StaticResult, b: StaticResult, rtol=1e-7):
    assert a.states == b.states and a.interface_states == b.interface_states
    pairs = [(a.r_n, b.r_n), (a.r_t, b.r_t)] if a.r_n is not None else []
    for k in a.interface_r_n:
        pairs += [(a.interface_r_n[k], b.interface_r_n[k]), (a.interface_r_t[k], b.interface_r_t[k])]
    scale = max([np.abs(x).max() for x, _ in pairs] + [1e-300])
    for x, y in pairs:
        assert np.abs(x - y).max() <= rtol * scale
    assert np.abs(a.u - b.u).max() <= rtol * max(np.abs(a.u).max(), 1e-300)


@pytest.mark.parametrize("name", sorted(MIXED_SCENES))
def test_mixed_formulation_matches_condensed(name):
    s = MIXED_SCENES[name]()
    c = static_equilibrium(s, formulation="condensed")
    m = static_equilibrium(s, formulation="mixed")
    assert c.success and m.success, m.message
    assert_same_equilibrium(c, m)
    # independent checks of the mixed result: equilibrium from a fresh assembly, the laws
    if name == "uplift_separated":   # no force at all: K u vanishes on the free DOFs
        res, model = residual_forces(s, m)
        assert np.abs(res[model.free_dofs()]).max() <= 1e-12 * np.abs(m.u).max()
    else:
        check_equilibrium(s, m)
    for rn, rt, g, u, mu, st in [(m.r_n, m.r_t, m.gap, m.slip, s.contact.friction if s.contact else 0, m.states)] * (
            m.r_n is not None) + [(m.interface_r_n[k], m.interface_r_t[k], m.interface_gap[k],
                                   m.interface_slip[k], 0.4 if name == "frictional_interface" else None,
                                   m.interface_states[k]) for k in m.interface_r_n]:
        if mu is None:
            continue
        F, D = check_laws(m, mu, rn, rt, g, u)
        states_consistent(st, mu, rn, rt, u, F, D)
    assert m.equilibrium_residual <= 1e-9
    assert m.residual <= 1e-9
    # the mixed path does not classify, and says why
    assert m.classes is None and m.lcp_matrix is None
    assert any("not classified" in n and "not the contact operator" in n for n in m.notes)
    assert m.layout["formulation"] == "mixed"


def test_mixed_formulation_semismooth_variant_is_certified():
    s = MIXED_SCENES["medium_shear_slip"]()
    c = static_equilibrium(s, formulation="condensed")
    m = static_equilibrium(s, formulation="mixed", petsc_options={"snes_type": "vinewtonssls"})
    assert m.success and m.layout["attempts"][0]["snes_type"] == "vinewtonssls"
    assert_same_equilibrium(c, m)


def test_mixed_formulation_failure_reports_no_states():
    # gravity pointing up on a free block: no equilibrium exists
    r = static_equilibrium(scene(4, top="free", mu=0.5, load={"gravity": -1.0}), formulation="mixed")
    assert not r.success and r.states == [] and r.u is None
    assert "SNES VI" in r.message and "vinewtonrsls" in r.message and "no contact states" in r.message


def test_formulation_auto_and_bad_value():
    small = static_equilibrium(scene(5, mu=0.5, load={"top_displacement": [0.0, -0.1]}))
    assert small.lcp_matrix is not None and small.classes is not None       # condensed
    large = static_equilibrium(scene(201, mu=0.5, load={"top_displacement": [0.0, -0.1]}))
    assert large.success and large.layout["formulation"] == "schur"      # above the dense limit, nothing floats
    with pytest.raises(ProblemError, match="formulation"):
        static_equilibrium(scene(5, load={"top_displacement": [0.0, -0.1]}), formulation="sparse")


def test_mixed_formulation_above_the_condensed_limit():
    s = scene(1001, mu=0.5, load={"top_displacement": [0.02, -0.1]}, interfaces=frictional(0.4))
    r = static_equilibrium(s)   # auto → mixed: 2002 contacts
    assert r.success, r.message
    assert len(r.states) == 1001 and len(r.interface_states["A"]) == 1001
    check_equilibrium(s, r)


def test_where_the_condensed_lcp_fails_auto_goes_on_to_the_schur_formulation():
    """extensive_interface.toml coarsened to 200 columns of 50 + 50 rows (200 contacts, the
    largest the condensed formulation takes): Lemke and PETSc's VI both failed on its dense LCP
    of 800 unknowns and ``analyze`` reported no contact states (not converged); auto now goes on
    to the Schur formulation, certified on the sparse problem, and says so."""
    import tomllib
    from pathlib import Path

    d = tomllib.loads((Path(__file__).parents[1] / "data" / "scenes" / "extensive_interface.toml").read_text())
    d["lattice"]["nx"] = 200
    for layer in d["layers"]:
        layer["rows"] = 50
    st = static_equilibrium(scene_from_dict(d))
    assert st.success and st.notes[0].startswith("formulation auto: condensed failed (")
    assert "schur next" in st.notes[0] and st.interface_states["lower"]
