"""Static equilibrium, Schur formulation (one MUMPS factorisation of the bordered stiffness,
NSGS + active-set polish on the compliance G): the same equilibrium as the dense condensed
formulation, certified on the sparse problem, honest about what it cannot do."""

import numpy as np
import pytest

from meicp.contact.static import static_equilibrium
from meicp.contact.static.delassus import solve_delassus, violation
from meicp.contact.static.schur import SCHUR_CERT_TOL
from meicp.core import limits
from meicp.core.errors import ProblemError

from .test_static import (MIXED_SCENES, assert_same_equilibrium, check_equilibrium, check_laws, frictional, scene,
                          states_consistent)

SCENES = {
    **{k: MIXED_SCENES[k] for k in ("compression_large_mu_stick", "shear_small_mu_slip", "uplift_separated",
                                     "frictional_interface", "frictionless", "medium_shear_slip", "medium_stick",
                                     "medium_interface")},
    # mixed stick / slip: the interface family of data/scenes/extensive_interface.toml, coarse
    "interface_family": lambda: scene(40, bottom="fixed", load={"top_displacement": [0.05, -0.05]},
                                      interfaces=frictional(0.5, below="A"),
                                      layers=[{"name": "A", "rows": 10, "stiffness": 1.0, "density": 1.0},
                                              {"name": "B", "rows": 10, "stiffness": 4.0, "density": 2.0}]),
    "base_gravity": lambda: scene(30, mu=0.05, load={"top_displacement": [0.05, -0.02], "gravity": 0.5}),
    "base_side_shortening": lambda: scene(30, left="fixed_x", right="fixed_x", mu=0.3,
                                          load={"side_displacement": [0.04, -0.04], "top_displacement": [0.0, -0.02]}),
    "interface_gravity": lambda: scene(30, bottom="fixed", load={"top_displacement": [0.03, -0.05], "gravity": 0.05},
                                       interfaces=frictional(0.5)),
}


def _laws(s, r):
    """Signorini, Coulomb and the states' meaning on every contact set, from the returned arrays."""
    sets = []
    if r.r_n is not None and s.contact is not None:
        sets.append((r.r_n, r.r_t, r.gap, r.slip, s.contact.friction, r.states, r.held))
    for itf in s.frictional_interfaces():
        k = itf.below
        sets.append((r.interface_r_n[k], r.interface_r_t[k], r.interface_gap[k], r.interface_slip[k],
                     itf.friction, r.interface_states[k], r.interface_held[k]))
    for rn, rt, gap, slip, mu, states, held in sets:
        F, D = check_laws(r, mu, rn, rt, gap, slip, held)
        if mu > 0 and not held.any():
            states_consistent(states, mu, rn, rt, slip, F, D)


@pytest.mark.parametrize("name", sorted(SCENES))
def test_schur_matches_condensed(name):
    s = SCENES[name]()
    c = static_equilibrium(s, formulation="condensed")
    r = static_equilibrium(s, formulation="schur")
    assert c.success and r.success, r.message
    assert r.layout["formulation"] == "schur"
    assert_same_equilibrium(c, r, rtol=1e-9)
    assert r.residual <= SCHUR_CERT_TOL and r.equilibrium_residual <= SCHUR_CERT_TOL
    assert max(r.layout["certificate"].values()) <= SCHUR_CERT_TOL
    if name != "uplift_separated":   # no force at all there
        check_equilibrium(s, r)
    _laws(s, r)


def test_mixed_states_in_the_family():
    """The coarse interface family really mixes sticking and slipping pairs (the benchmark's
    and the shipped scene's premise), and so do the scenes with gravity and side loads."""
    for name in ("interface_family", "interface_gravity", "base_gravity", "base_side_shortening"):
        r = static_equilibrium(SCENES[name](), formulation="schur")
        states = r.states + sum(r.interface_states.values(), [])
        assert "stick" in states and any(x.startswith("slip") for x in states), (name, states)


def test_auto_picks_schur_above_the_dense_limit_and_mixed_when_floating(monkeypatch):
    monkeypatch.setattr(limits, "STATIC_AUTO_CONDENSED_LIMIT", 20)
    held = static_equilibrium(SCENES["medium_shear_slip"]())
    assert held.success and held.layout["formulation"] == "schur"
    floating = static_equilibrium(scene(30, mu=0.5, load={"top_displacement": [0.02, -0.1]},
                                        interfaces=frictional(0.4)))
    assert floating.success and floating.layout["formulation"] == "mixed"
    assert any("not schur" in n and "rigid-body mode" in n for n in floating.notes)


def test_floating_component_is_refused_by_name():
    with pytest.raises(ProblemError, match="schur.*rigid-body mode.*mixed"):
        static_equilibrium(MIXED_SCENES["base_and_interface_floating"](), formulation="schur")


def test_too_many_contacts_for_schur(monkeypatch):
    monkeypatch.setattr(limits, "STATIC_SCHUR_MAX_CONTACTS", 10)
    with pytest.raises(ProblemError, match="Schur formulation's limit of 10.*mixed"):
        static_equilibrium(scene(11, load={"top_displacement": [0.0, -0.1]}), formulation="schur")


def test_option_meicp_owns_is_refused():
    # ICNTL(19) (the Schur complement itself) belongs to meicp: a clear error, before MUMPS runs
    with pytest.raises(ProblemError, match="ICNTL\\(19\\).*meicp_static_schur_mat_mumps_icntl_19"):
        static_equilibrium(SCENES["shear_small_mu_slip"](), formulation="schur",
                           petsc_options={"mat_mumps_icntl_19": 0})


def test_mumps_option_reaches_the_factor():
    # a larger workspace (ICNTL(14)) is accepted and changes nothing
    s = SCENES["shear_small_mu_slip"]()
    a = static_equilibrium(s, formulation="schur")
    b = static_equilibrium(s, formulation="schur", petsc_options={"mat_mumps_icntl_14": 80})
    assert_same_equilibrium(a, b, rtol=1e-12)


# ------------------------------------------------------------------------ the Delassus solver


def _random_problem(rng, n, n_fric, mu):
    X = rng.standard_normal((2 * n, 2 * n))
    m = n + n_fric
    G = (X @ X.T / (2 * n) + 0.5 * np.eye(2 * n))[:m, :m]
    c0 = rng.standard_normal(m)
    return G, c0, np.full(n_fric, mu), np.arange(n_fric)


@pytest.mark.parametrize("seed", range(6))
def test_delassus_random_problems_certified(seed):
    rng = np.random.default_rng(seed)
    n = 30
    G, c0, mu_f, pos = _random_problem(rng, n, n - 5, [0.1, 0.5, 1.0][seed % 3])
    sol = solve_delassus(G, c0, mu_f, pos, tol=1e-11)
    assert sol.success, sol.message
    w = G @ sol.r + c0
    D = max(np.abs(w).max(), np.abs(c0).max())
    assert violation(sol.r, w, mu_f, pos, n, D=D) <= 1e-11
    # every contact's state is one of the four cases: checked against its definition
    rn, rt, gap, slip = sol.r[:n], sol.r[n:], w[:n], w[n:]
    F = np.abs(sol.r).max()
    sep = rn <= 1e-9 * F
    assert np.all(gap[~sep] <= 1e-9 * D)
    sliding = np.abs(slip) > 1e-9 * D
    assert np.allclose(rt[sliding], -np.sign(slip[sliding]) * mu_f[sliding] * rn[:n - 5][sliding], atol=1e-9 * F)


def test_delassus_frictionless_matches_the_lcp():
    from meicp import solve_lcp

    rng = np.random.default_rng(7)
    G, c0, _, _ = _random_problem(rng, 25, 0, 0.0)
    sol = solve_delassus(G, c0, np.zeros(0), np.zeros(0, np.int64), tol=1e-11)
    ref = solve_lcp(G, c0, method="lemke")
    assert sol.success and ref.success
    assert np.abs(sol.r - ref.x).max() <= 1e-9 * np.abs(ref.x).max()


def test_delassus_no_solution_is_not_reported():
    # w = −r − 1 ≥ 0 with r ≥ 0 has no solution: never 'success'
    sol = solve_delassus(-np.eye(3), -np.ones(3), np.zeros(0), np.zeros(0, np.int64), tol=1e-10)
    assert not sol.success and sol.certificate > 1e-10
