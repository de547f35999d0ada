"""Condensed λ-windows carried over μ (issue 31; docs/critical-friction.md, "With damping"): no
damped divergence mode at any μ of an interval, the damped divergence onset's lower end past
the enumeration.  Against the enumeration of the quadratic MEiCP on lattices small enough."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

import meicp
from meicp.contact.damped_mu_windows import prove_up_to
from meicp.contact.problem import pencil
from meicp.examples import two_layer_scene

from .test_damped_windows import enumerated, random_lattice
from .test_damping import damped

#: the 6 × 4 frictional interface with η 0.1 / 0.01 (tests/test_damped_onset.py): the λ = 0
#: onset is 6.7082039, damped divergence modes exist from below it
SIX = damped(two_layer_scene(6, (2, 2), bottom="fixed", stiffness=(2.0, 1.0), density=(1.0, 1.0),
                             interface={"kind": "frictional", "friction": 1.0, "states": "slip+"}), eta=(0.1, 0.01))


def reach_of(scene, start: float, top: float):
    with pencil(scene.with_friction(1.0)) as unit:
        return prove_up_to(unit, start, top)


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2 ** 32 - 1), top=st.floats(0.2, 4.0), where=st.lists(st.floats(0, 1), min_size=3,
                                                                                  max_size=3))
def test_no_mode_inside_a_proved_interval(seed, top, where):
    """Wherever the cover reaches, the enumeration of every support finds no damped divergence
    mode: at the reach itself and at three μ below it."""
    scene = random_lattice(seed)
    cover = reach_of(scene, 0.0, top)
    assert 0.0 <= cover.reach <= top
    if cover.reach > 0:
        for mu in [cover.reach, *(max(f * cover.reach, 1e-3) for f in where)]:
            assert enumerated(scene.with_friction(float(mu))).status == "no_solution", (mu, cover.statement)


def test_the_cover_stops_just_below_the_first_damped_mode():
    """From the damped Rayleigh bound's 2.357 the cover reaches past 6.69, within 0.3 % of the
    first μ where the enumeration finds a damped divergence mode (between 6.7053 and 6.7063)."""
    cover = reach_of(SIX, 2.357, 6.7082039)
    assert 6.69 < cover.reach < 6.7053, cover.statement
    assert enumerated(SIX.with_friction(cover.reach)).status == "no_solution"
    assert enumerated(SIX.with_friction(6.7063)).status != "no_solution"
    assert "concave in μ" in cover.statement and cover.intervals >= 1


def test_nothing_proved_says_so():
    cover = reach_of(SIX, 6.7063, 6.7082039)  # a damped mode at the start
    assert cover.reach == 6.7063 and cover.intervals == 0 and "not proved" in cover.statement


def test_the_seeds_scene_past_the_enumeration_gets_a_tight_floor():
    """22 pairs, η 0.1 / 0.01 (tests/test_damped_onset.py): the damped Rayleigh bound proves
    [0, 2.358]; the windows over μ carry it to within 0.5 % of the λ = 0 onset."""
    scene = damped(two_layer_scene(22, (2, 2), bottom="fixed", stiffness=(2.0, 1.0), density=(1.0, 1.0),
                                   interface={"kind": "frictional", "friction": 1.0, "states": "slip+"}),
                   eta=(0.1, 0.01))
    d = meicp.critical_friction(scene, flutter=False).divergence
    assert 6.67 < d.lower < d.upper == pytest.approx(6.7082039, rel=1e-7) and not d.exact
    assert "carried over μ" in d.evidence and "damped Rayleigh bound" in d.evidence
    for m in np.linspace(0.5, d.lower, 3):  # no mode where it is proved that none exists
        assert meicp.analyze(scene.with_friction(float(m)), flutter=False).divergence is not True
