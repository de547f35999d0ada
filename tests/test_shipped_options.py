"""A scene's ``[solver]`` options never make a decided divergence verdict undecided or much
slower (issue 33, deliverable 4): ``nev`` > 1 only widens the last search of the window
procedure, which follows one eigenpair per solve before (src/meicp/contact/divergence/search.py)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

import meicp
from meicp.contact.divergence import Procedures, divergence_of
from meicp.contact.divergence import search as search_module
from meicp.contact.divergence.condensed import CondensedProof
from meicp.contact.problem import pencil
from meicp.examples import two_layer_scene
from meicp.scene import Solver

ROOT = Path(__file__).resolve().parents[1]


def _coarsened(name: str, nx: int, rows: int):
    """A shipped scene with fewer columns and rows, every other key as shipped."""
    scene = meicp.load_scene(ROOT / "data" / "scenes" / name)
    layers = tuple(dataclasses.replace(layer, rows=rows) for layer in scene.layers)
    return dataclasses.replace(scene, lattice=dataclasses.replace(scene.lattice, nx=nx), layers=layers)


def _restarts(result) -> int:
    return sum(int(e.coverage.get("eps_iterations", 0)) for e in result.eicp if e is not None)


def test_the_shipped_solver_table_costs_no_more_than_the_defaults():
    """extensive_contact.toml (method = "active-set", nev = 4) at 100 × 50 nodes: before, its
    nev = 4 made the whole search converge three more eigenpairs in the cluster of slow
    vibrations (37 Krylov–Schur restarts against 9 for the same mode); the 10⁶-DOF scene ran
    15 minutes without a verdict.  Now the same mode for the same work."""
    shipped = _coarsened("extensive_contact.toml", 100, 25)
    assert shipped.solver.nev == 4 and shipped.solver.method == "active-set"  # the shipped table is tested
    plain = dataclasses.replace(shipped, solver=Solver())
    with_table, without = meicp.analyze(shipped, flutter=False), meicp.analyze(plain, flutter=False)
    assert with_table.divergence is without.divergence is True
    assert np.isclose(with_table.modes[0].sigma, without.modes[0].sigma, rtol=1e-8)
    assert _restarts(with_table) <= _restarts(without)


@pytest.mark.parametrize("nev, expected", [(None, [1] * 5), (3, [1] * 5 + [3])])
def test_nev_widens_only_the_last_search(monkeypatch, nev, expected):
    """On a pencil whose proofs stop (the condensed proof reported stopped at σ = 1e-3), the
    first and whole searches, and the three from lower shifts after them, follow one eigenpair
    per solve; a caller's nev > 1 adds a last
    search with nev eigenpairs per solve, and the undecided evidence says so."""
    asked = []
    real = search_module.solve_eicp

    def recording(*args, **kw):
        asked.append(kw["nev"])
        return real(*args, **kw)

    def stopped(comm, pen, sigma_max, **kw):
        return CondensedProof(False, "", "stopped for the test", -1.0, 1, (0.0, 1e-3))

    monkeypatch.setattr(search_module, "solve_eicp", recording)
    # no proxy estimate: the first search from the top (this scene's proxy has no real σ above
    # 0, which would skip it)
    monkeypatch.setattr(search_module, "rightmost_real", lambda scene, lines: None)
    scene = two_layer_scene(60, (2, 2), mu=1.2, states="slip-", shear=0.5)
    with pencil(scene) as pen:
        options = {} if nev is None else {"nev": nev}
        v = divergence_of(pen, scene, None, "active-set", 0.0, 1e-10, options, procedures=Procedures(prove=stopped))
    assert v.stable is None and asked == expected
    assert (f"the last with nev = {nev}" in v.evidence) is (nev is not None)


def test_the_scene_nev_reaches_the_last_search_too(monkeypatch):
    """``[solver] nev`` is read like the keyword: the widened search's, never the first's."""
    scene = two_layer_scene(60, (2, 2), mu=1.2, states="slip-", shear=0.5)
    scene = dataclasses.replace(scene, solver=Solver(nev=5))
    with pencil(scene) as pen:
        settings = search_module.search_settings(pen, scene, None, 0.0, 1e-10, {}, 1.0, 0.0)
        assert settings.keywords["nev"] == 1 and settings.widened_nev == 5
        settings = search_module.search_settings(pen, scene, None, 0.0, 1e-10, {"nev": 1}, 1.0, 0.0)
        assert settings.keywords["nev"] == 1 and settings.widened_nev is None


def test_the_first_search_goes_on_while_a_mode_converges_fast():
    """The shipped 10⁶-DOF scene coarsened to 100 × 50 nodes: its mode needs 9 Krylov–Schur
    restarts from the top of the window.  Cut at the first search's 6 it was found only by
    the whole search, after a condensed proof and a σ-window (at 10⁶ DOFs 49 of 77 s); its
    error estimate falls ≥ 10× a restart, so the first search now goes on and finds it."""
    from meicp.contact.divergence import sigma_window

    scene = _coarsened("extensive_contact.toml", 100, 25)
    with pencil(scene) as pen:
        kw = dict(J=pen.maps.J, method="active-set", lam_min=0.0, target=sigma_window.probe_top(pen.A, pen.B).shift,
                  nev=1, max_iter=1, give_up_after=search_module.FIRST_GIVE_UP)
        capped = meicp.solve_eicp(pen.A, pen.B, options={"eps_max_it": search_module.FIRST_EPS_MAX_IT}, **kw)
        going_on = meicp.solve_eicp(pen.A, pen.B, options={"eps_max_it": search_module.FIRST_EPS_MAX_IT_CONVERGING},
                                    converging_after=search_module.FIRST_EPS_MAX_IT, **kw)
    assert not capped.solutions and going_on.solutions and going_on.coverage["gave_up"] == 0
    assert search_module.FIRST_EPS_MAX_IT < going_on.coverage["eps_iterations"] <= \
        search_module.FIRST_EPS_MAX_IT_CONVERGING
    r = meicp.analyze(scene, flutter=False)
    assert r.divergence is True and r.proofs[0].sigma_window is None  # no proof, no window spent
    assert np.isclose(r.modes[0].sigma, going_on.solutions[0].lam, rtol=1e-8)


def test_an_option_that_leaves_the_verdict_undecided_is_named(caplog, monkeypatch):
    """A budget of one support update decides nothing where the mode is two supports away,
    and a method by name that runs no proof decides no stable scene: the undecided evidence
    (and a warning) names the option, where the defaults decide."""
    unstable = two_layer_scene(200, (10, 10), mu=2.0, states="slip+", shear=0.0)
    assert meicp.analyze(unstable, flutter=False).divergence is True
    # the searches from lower shifts find this mode within one update: without them the budget
    # is what ends the search, and that is what the evidence must name
    monkeypatch.setattr(search_module, "LOWER_SHIFTS", ())
    # ... nor does the first search from the proxy's estimate, which finds a mode at once here:
    # from the window's top it is two supports away
    monkeypatch.setattr(search_module, "rightmost_real", lambda scene, lines: None)
    with caplog.at_level("WARNING", logger="meicp"):
        r = meicp.analyze(unstable, flutter=False, max_iter=1)
    assert r.divergence is None and "max_iterations = 1 (the [solver] table or the caller) ended" in r.evidence
    assert any("max_iterations = 1" in m for m in caplog.messages)
    stable = two_layer_scene(60, (2, 2), mu=1.0, states="slip+", shear=0.5)
    assert meicp.analyze(stable, flutter=False).divergence is False
    r = meicp.analyze(dataclasses.replace(stable, solver=Solver(method="semismooth")), flutter=False)
    assert r.divergence is None and "method 'semismooth' (the [solver] table or the caller) runs no proof" in r.evidence
