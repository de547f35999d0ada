"""The damped flutter search past the dense limit (issue 31, docs/damping.md "damped flutter at
scale"): complex shift-and-invert on the companion form of λ²B + λD − A.  Against the dense
companion QZ of the same pencil (every certified mode one of its eigenvalues, the fastest found
the dense fastest), its pairs re-checked on Q built independently, and what it never claims."""

import numpy as np
import pytest

import meicp
from meicp.contact.damped import damping_matrix
from meicp.contact.flutter import pencil_flutter
from meicp.contact.problem import pencil
from meicp.core import limits
from meicp.eicp.quadratic import quadratic_spectrum
from meicp.examples import two_layer_scene

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
    assert search.flutter_growth.upper is None and not search.flutter_growth.exact
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
    """Past the enumeration's limits the damped divergence is undecided (its scalable path is
    not built), and the search's certified flutter mode still decides the verdict."""
    monkeypatch.setattr(limits, "ENUMERATE_N", 10)
    r = meicp.analyze(SCENES["base"], flutter_dense_max=10)
    assert r.divergence is None and "not built yet" in r.evidence
    assert r.flutter is True and r.stable is False and r.status == "solved"
