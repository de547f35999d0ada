"""The divergence verdict past the enumeration budget (issue 14, :mod:`meicp.contact.divergence`):
the issue's table rows decided, and the large-problem path never contradicting enumeration.
The tests read the verdict's fields (:class:`~meicp.contact.divergence.DivergenceProof`); each
evidence sentence is checked once, by the test of the step that makes it."""

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import meicp
from meicp.contact.divergence import DivergenceProof, Procedures, divergence_of, search, sigma_window
from meicp.contact.divergence.condensed import CondensedProof, prove_no_divergence
from meicp.contact.problem import pencil
from meicp.contact import proxy
from meicp.contact.lines import contact_lines
from meicp.contact.result import InstabilityResult
from meicp.core import limits
from meicp.examples import two_layer_scene
from meicp.io.scene import scene_from_dict
from meicp.lattice.model import LatticeModel

from .helpers import interface_chain_scene

ROOT = Path(__file__).resolve().parents[1]


def _scene(nx, rows, state, mu, shear=0.5):
    return two_layer_scene(nx, rows, mu=mu, states=state, shear=shear)


def _verdict(scene, method="active-set", **procedures):
    """The divergence verdict of the scene's one pencil, as ``analyze`` computes it (serial,
    its default tol and options), with some procedures replaced to reach a branch."""
    with pencil(scene) as pen:
        return divergence_of(pen, scene, None, method, 0.0, 1e-10, {}, procedures=Procedures(**procedures))


def _stalled(A, B, *, max_it):
    """Lanczos as in the cluster of slow vibrations: an unconverged Ritz value below 0."""
    return -1.0, False, 60


def test_stable_by_the_rayleigh_bound_past_16_contacts():
    """nx = 60, 2 + 2 rows, slip+, μ = 1: sym(−A) ≻ 0 (before: inconclusive).  The Rayleigh
    proof's sentence is checked here."""
    r = meicp.analyze(_scene(60, (2, 2), "slip+", 1.0), flutter=False)
    assert r.divergence is False and r.modes == []
    proof = r.proofs[0]
    assert proof.test == "rayleigh-inertia" and proof.sigma_window == (0.0, math.inf)
    assert proof.supports_visited == proof.eigen_solves == 0 and r.eicp == [None]
    assert r.evidence == proof.statement
    assert r.evidence.startswith("Rayleigh bound (LDLᵀ inertia): sym(A) + η·diag|·| is negative definite")
    assert r.evidence.endswith("every MEiCP solution has σ = xᵀsym(A)x / xᵀsym(B)x < 0 (a proof)")


def test_the_full_support_mode_is_found_by_the_first_search():
    """nx = 60, 2 + 2 rows, slip−, μ = 3: the full support carries σ = 0.8188 (before:
    cycling among the slow vibrations nearest 0), found by the first search from 1.25× the
    contact-strip proxy's rightmost real σ (below the short Lanczos run's estimate of the
    top): no σ-window is certified for a mode.  The certified mode's sentence is checked
    here."""
    scene = _scene(60, (2, 2), "slip-", 3.0)
    r = meicp.analyze(scene, flutter=False)
    assert r.divergence is True and np.isclose(r.modes[0].sigma, 0.818755, rtol=1e-5)
    proof = r.proofs[0]
    assert r.modes[0].residual < 1e-10 and proof.test == "certified-mode"
    assert proof.sigma_window is None and 1 <= proof.eigen_solves <= search.FIRST_SEARCH
    assert proof.supports_visited >= 1 and proof.margin is None and proof.stable_friction is None
    with pencil(scene) as pen:
        top = sigma_window.probe_top(pen.A, pen.B).shift
        estimate = proxy.rightmost_real(scene, pen.lines)
    shift = search.PROXY_SHIFT * estimate
    assert r.modes[0].sigma < shift < top
    assert r.evidence == proof.statement == (
        f"search from σ = {shift:.6g}: a certified divergence mode after {proof.eigen_solves} eigen-solve(s), "
        f"{proof.supports_visited} support(s)")


def test_the_first_search_starts_from_the_proxy_where_the_top_misses_the_mode():
    """nx = 400, 10 + 10 rows, slip+, shear −0.5, μ = 2.303: the window's top (θ ≈ 1.11) lies
    far above the lattice's modes, and the first search from it converged to none
    (docs/benchmarks-notes.md, "first search from the proxy"); from 1.25× the contact-strip
    proxy's rightmost real σ (0.0674) it certifies a mode (σ ≈ 0.0414) with no proof or window."""
    scene = two_layer_scene(400, (10, 10), mu=2.303, states="slip+", shear=-0.5)
    r = meicp.analyze(scene, flutter=False)
    proof = r.proofs[0]
    assert r.divergence is True and proof.test == "certified-mode" and proof.sigma_window is None
    assert 0.0413 < r.modes[0].sigma < 0.0415 and r.modes[0].residual < 1e-10  # one of several modes there
    with pencil(scene) as pen:
        estimate = proxy.rightmost_real(scene, pen.lines)
    assert np.isclose(estimate, 0.0674, rtol=1e-3)
    assert r.evidence.startswith(f"search from σ = {search.PROXY_SHIFT * estimate:.6g}: a certified divergence mode")
    # a search finds some modes: the summary does not call the first the fastest
    table = "\n".join(text for _, text in r.summary_rows(scene))
    assert "fastest found first, not proved the fastest" in table


def test_the_first_search_starts_at_the_top_when_the_proxy_estimate_is_not_below_it():
    """The proxy's estimate only lowers the first shift: with a top below 1.25σ_p, or no proxy
    (an embedded band), the search starts at the top."""
    scene = _scene(60, (2, 2), "slip-", 3.0)
    with pencil(scene) as pen:
        estimate = proxy.rightmost_real(scene, pen.lines)
        low = search.search_settings(pen, scene, None, 0.0, 1e-10, {}, estimate, 0.0)
        assert search.first_shift(low, scene) == (estimate, "the window's top")
        high = low.from_shift(10 * estimate)
        shift, why = search.first_shift(high, scene)
        assert shift == search.PROXY_SHIFT * estimate and "proxy" in why
    banded = meicp.load_scene(ROOT / "data" / "scenes" / "embedded_on_base.toml")
    with pencil(banded) as pen:
        assert proxy.rightmost_real(banded, pen.lines) is None


def test_the_proxy_estimate_is_skipped_where_it_would_mislead_or_fail():
    """No estimate from a proxy with a grazing contact (its pencil needs a tangential case: it
    used to raise); a rigid motion at rounding level (a free top: σ ≈ 1e-14 would start the
    search among the slow vibrations) counts as no real σ above 0 (0.0: no first search); a
    caller's own target is kept."""
    grazing = two_layer_scene(60, (2, 2), mu=3.0, states=["slip-"] * 29 + ["grazing"] + ["slip-"] * 30)
    assert proxy.rightmost_real(grazing, contact_lines(grazing, LatticeModel(grazing))) is None
    assert meicp.analyze(grazing, flutter=False).divergence is True
    free_top = two_layer_scene(60, (2, 2), mu=1.0, states="slip+", top="free")
    with pencil(free_top) as pen:
        assert proxy.rightmost_real(free_top, pen.lines) == 0.0  # no real σ above 0: no first search
    scene = _scene(60, (2, 2), "slip-", 3.0)
    with pencil(scene) as pen:
        given = search.search_settings(pen, scene, None, 0.0, 1e-10, {"target": 5.0}, 1.0, 0.0)
        assert search.first_shift(given, scene) == (5.0, "the caller's target")


def test_no_first_search_where_the_proxy_has_no_real_sigma_above_0(caplog):
    """nx = 400, 10 + 10 rows, slip+, shear 0.5, μ = 0.8841: the window's top is above 0 but
    the contact-strip proxy has no real σ above 0; from the top the short search found nothing
    (docs/benchmarks-notes.md, "no first search without a proxy mode"), so none is made and
    the condensed proof decides, with no eigen-solve."""
    scene = two_layer_scene(400, (10, 10), mu=0.8841, states="slip+", shear=0.5)
    with pencil(scene) as pen:
        assert sigma_window.probe_top(pen.A, pen.B).positive
        assert proxy.rightmost_real(scene, pen.lines) == 0.0
        settings = search.search_settings(pen, scene, None, 0.0, 1e-10, {}, 1.0, 0.0)
        assert search.first_shift(settings, scene)[0] is None and search.first_search(settings, scene) is None
    with caplog.at_level("INFO", logger="meicp"):
        r = meicp.analyze(scene, flutter=False)
    assert r.divergence is False and r.proofs[0].test == "condensed-windows" and r.proofs[0].eigen_solves == 0
    assert any("no first search (the contact-strip proxy has no real σ above 0)" in m for m in caplog.messages)


def test_stable_by_the_condensed_windows_where_the_rayleigh_bound_fails():
    """nx = 60, slip−, μ = 1.2 (below μ_c ≈ 1.46): sym(−A) is indefinite; the condensed
    tests prove every σ ≥ 0 free of modes, with no σ-window certified."""
    r = meicp.analyze(_scene(60, (2, 2), "slip-", 1.2), flutter=False)
    proof = r.proofs[0]
    assert r.divergence is False and proof.test == "condensed-windows"
    assert proof.sigma_window == (0.0, math.inf) and proof.margin > 0
    assert r.evidence == proof.statement and r.evidence.endswith("(a proof)")


@pytest.mark.parametrize("reach, stable", [(50.0, True), (1e-3, None)])
def test_a_proof_stopped_short_of_infinity_is_completed_by_the_sigma_window(reach, stable):
    """Where the condensed proof covers only [0, c] (here: the real proof on [0, c], reported
    as stopped there), the certified σ_max of (sym A, sym B) completes it when σ_max ≤ c —
    and only then: with c below σ_max the verdict stays undecided, saying what was proved.
    The sentence of the σ-window's proof is checked here."""

    def stopped_at_reach(comm, pen, sigma_max, **kw):
        p = prove_no_divergence(comm, pen, reach, **kw)
        assert p.proved and p.window == (0.0, reach)
        return CondensedProof(False, "", f"window [{reach}, inf] not certified", -1.0, p.samples, p.window)

    v = _verdict(_scene(60, (2, 2), "slip-", 1.2), prove=stopped_at_reach)
    assert v.stable is stable
    if stable:
        assert v.proof.test == "rayleigh-window+condensed-windows" and v.proof.margin == -1.0
        sigma_max = v.proof.sigma_window[1]
        assert v.proof.sigma_window[0] == 0.0 and 0 < sigma_max <= reach
        assert v.evidence == v.proof.statement == (
            f"no solution above σ_max = {sigma_max:.6g} (Rayleigh bound, LDLᵀ inertia) and none in "
            f"[0, {reach:.6g}] by the condensed windows (window [{reach}, inf] not certified) (a proof)")
    else:
        assert v.proof.test == "" and v.proof.sigma_window == (0.0, reach) and v.modes == []
        assert v.proof.stable_friction_scale is not None and v.proof.margin is None


def test_without_a_certified_window_the_condensed_proof_covers_every_sigma():
    """When the top of (sym A, sym B) sits in the cluster of slow vibrations (a tall lattice:
    Lanczos returns an unconverged Ritz value below it) no σ_max is certified; the condensed
    proof then covers [0, ∞) — and proves nothing where a mode exists (the search from 0
    misses the mode without the window's top: undecided, never stable).  The condensed
    windows' sentence (:mod:`meicp.contact.divergence.condensed`) is checked here."""
    v = _verdict(_scene(60, (2, 2), "slip-", 1.2), estimate_top=_stalled)
    assert v.stable is True and v.proof.test == "condensed-windows"
    assert v.proof.sigma_window == (0.0, math.inf) and v.evidence == v.proof.statement
    assert v.evidence.startswith("G(σ) ∈ R₀ on every window of [0, inf] (")
    # JSON (and results.h5): was [0.0, null] (unknown), then [0.0, "inf"]; now flagged (issue 30)
    proof = InstabilityResult(proofs=[v.proof]).to_dict()["proofs"][0]
    assert proof["sigma_window"] == [0.0, None] and proof["sigma_window_infinite"] == [0, 1]
    v = _verdict(_scene(60, (2, 2), "slip-", 3.0), estimate_top=_stalled)
    assert v.stable is not True


def test_below_a_positive_top_the_proof_comes_before_any_search(monkeypatch):
    """With no Ritz value above 0 in the short Lanczos run the first search would start in the
    cluster of slow vibrations and give up: it is not made.  The condensed proof decides a
    stable lattice with no eigen-solve; on an unstable one the whole search after the proof
    still runs (here, from the faked top, it misses the mode: undecided, never stable)."""
    from meicp.contact.divergence import driver

    def no_first_search(settings, *where):
        raise AssertionError("the first search was made below a positive top")

    monkeypatch.setattr(driver, "first_search", no_first_search)
    v = _verdict(_scene(60, (2, 2), "slip-", 1.2), estimate_top=_stalled)
    assert v.stable is True and v.proof.test == "condensed-windows"
    assert v.proof.eigen_solves == 0 and v.proof.supports_visited == 0 and v.eicp is None
    v = _verdict(_scene(60, (2, 2), "slip-", 3.0), estimate_top=_stalled)
    assert v.stable is None and v.proof.eigen_solves >= 1 and v.eicp is not None


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(nx=st.integers(4, 9), lower=st.integers(1, 3), upper=st.integers(1, 3),
       state=st.sampled_from(["slip+", "slip-"]), shear=st.sampled_from([-0.5, 0.5]),
       mu=st.floats(0.05, 6.0))
def test_the_large_problem_path_never_contradicts_enumeration(nx, lower, upper, state, shear, mu):
    """Forced on small scenes, the window path (Rayleigh bound, σ-window, search from its top,
    condensed proof) agrees with the enumeration of every support whenever it decides, and
    its mode is the enumeration's fastest."""
    scene = _scene(nx, (lower, upper), state, mu, shear)
    truth = meicp.analyze(scene, method="enumerate", flutter=False)
    window = meicp.analyze(scene, method="active-set", flutter=False)
    assert truth.divergence is not None
    if window.divergence is True:
        assert truth.divergence is True
        assert np.isclose(window.modes[0].sigma, truth.modes[0].sigma, rtol=1e-8, atol=1e-12) or any(
            np.isclose(window.modes[0].sigma, m.sigma, rtol=1e-8) for m in truth.modes)
    elif window.divergence is False:
        assert truth.divergence is False, window.evidence
    else:
        assert window.proofs[0].test == "" and window.proofs[0].stable_friction_scale is not None


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(nx=st.integers(4, 9), lower=st.integers(1, 3), upper=st.integers(1, 3),
       state=st.sampled_from(["slip+", "slip-"]), shear=st.sampled_from([-0.5, 0.5]),
       mu=st.floats(0.05, 6.0))
def test_without_a_window_the_proof_on_every_sigma_never_contradicts_enumeration(nx, lower, upper, state, shear,
                                                                                 mu):
    """Lanczos made to stall (no σ_max certified): the condensed proof on [0, ∞) and the
    search from 0 never claim what enumeration contradicts."""
    scene = _scene(nx, (lower, upper), state, mu, shear)
    truth = _verdict(scene, method="enumerate")
    window = _verdict(scene, estimate_top=_stalled)
    assert truth.stable is not None
    if window.stable is not None:
        assert window.stable == truth.stable, window.evidence


@pytest.mark.parametrize("mu, test", [(0.5, "rayleigh-inertia"), (3.0, "condensed-windows"),
                                      (20.0, "certified-mode")])
def test_a_frictional_interface_past_16_contacts_is_decided(mu, test):
    """80 sliding interface pairs: at μ = 0.5 the Rayleigh bound proves stability; at μ = 3
    (sym B was indefinite in the old coordinates: undecided) the condensed windows do, and at
    μ = 20 the search certifies σ = 0.30265 (B diagonal in centre-of-mass coordinates)."""
    from meicp.io.scene import loads_scene

    text = (ROOT / "data" / "scenes" / "frictional_interface.toml").read_text()
    text = text.replace("nx = 10", "nx = 80").replace("friction = 0.5", f"friction = {mu}")
    r = meicp.analyze(loads_scene(text), flutter=False)
    assert r.divergence is (mu == 20.0) and r.proofs[0].test == test, r.evidence
    if mu == 20.0:
        assert abs(r.modes[0].sigma - 0.30265) < 1e-5


def test_a_non_diagonal_b_past_16_contacts_gets_a_verdict_not_an_error():
    """80 pairs on each side of a one-row layer between two interfaces (B not diagonal there)
    at μ = 3: sym(B) is indefinite (no Rayleigh quotient, and Lanczos on (sym A, sym B) breaks
    down — it used to end in a PETSc error): undecided, with that reason.  The undecided
    sentence is checked here."""
    r = meicp.analyze(interface_chain_scene(80, 3.0), flutter=False)
    proof = r.proofs[0]
    assert r.divergence is None and proof.test == "" and r.evidence == proof.statement
    assert proof.stable_friction_scale is not None and proof.eigen_solves >= 1
    assert r.evidence.startswith("undecided: Rayleigh bound at 0: B is not proved positive definite")
    assert "; no σ-window (λ_max(sym A, sym B) not estimated); condensed test: " in r.evidence
    assert f"over {proof.supports_visited} support(s) found no mode ({r.eicp[0].status})" in r.evidence


@pytest.mark.parametrize("top", ["fixed", "free"])
def test_a_rigid_motion_is_never_proved_away(top):
    """Every contact separated: with the top free the lattice floats (σ = 0 rigid motions,
    within rounding of the Rayleigh bound) — never "no divergence"; held at the top it is
    proved stable."""
    scene = two_layer_scene(8, (2, 2), mu=1.0, states="separated", top=top)
    r = meicp.analyze(scene, method="active-set", flutter=False)
    assert r.divergence is (False if top == "fixed" else r.divergence)
    if top == "free":
        assert r.divergence is not False


def test_an_undecided_verdict_states_the_friction_up_to_which_stability_is_proved():
    """Issue 14, item 3: 80 pairs at μ = 3 on each side of a one-row layer between two
    interfaces are undecided; the evidence gives the μ up to which these states are proved
    stable (Rayleigh bound along μ).  Checked independently: just below it the verdict at that
    μ is a Rayleigh proof, and 20 % above it the bound fails (the proved set of μ is an
    interval from 0, and the search stops within 10 %)."""

    def at(mu):
        return meicp.analyze(interface_chain_scene(80, mu), flutter=False)

    r = at(3.0)
    assert r.divergence is None
    proof = r.proofs[0]
    mu_r = proof.stable_friction["lower"]
    assert 0.5 <= mu_r < 3.0 and proof.stable_friction_scale == pytest.approx(mu_r / 3.0)
    assert f"μ ≤ {mu_r:.4g} (lower)" in r.evidence  # the friction range's own sentence, in the verdict's
    below, above = at(0.999 * mu_r), at(1.2 * mu_r)
    assert below.divergence is False and below.proofs[0].test == "rayleigh-inertia"
    assert above.proofs[0].test != "rayleigh-inertia"


def test_a_floating_lattice_has_no_friction_range():
    """Without friction the Rayleigh bound cannot hold on a lattice free to move as a whole."""
    from meicp.contact.friction_range import proved_friction_range

    with pencil(two_layer_scene(20, (2, 2), mu=1.0, states="slip+", top="free")) as pen:
        reach = proved_friction_range(pen)
    assert reach.scale == 0.0 and reach.factorisations == 1 and "no friction range proved" in reach.statement


def test_the_friction_range_on_300_sliding_base_contacts():
    """The friction range of 300 sliding base contacts at μ = 3, checked on the pencils of the
    μ it names: the Rayleigh bound proves stability just below it, not 20 % above."""
    from meicp.contact.friction_range import proved_friction_range
    from meicp.contact.problem import pencil
    from meicp.contact.rayleigh import rayleigh_bound

    with pencil(_scene(300, (4, 4), "slip+", 3.0)) as pen:
        reach = proved_friction_range(pen)
    mu_r = reach.friction["base"]
    assert 0 < mu_r < 3.0 and reach.failed <= 1.1 * reach.scale and reach.factorisations <= 8
    for mu, proved in ((0.999 * mu_r, True), (1.2 * mu_r, False)):
        with pencil(_scene(300, (4, 4), "slip+", mu)) as pen:
            assert (rayleigh_bound(pen.A, pen.B).proved is True) is proved


@pytest.mark.parametrize("state, mu, mode", [("slip+", 1.0, False), ("slip-", 3.0, True)])
def test_the_first_search_gives_up_only_where_no_ritz_value_shows_above_zero(state, mu, mode):
    """The first search's stopping test (search.FIRST_GIVE_UP): on a stable lattice every
    Ritz value sits in the slow vibrations below 0 and the eigen-solve stops after the first
    restart (the stopping test reads that restart's Ritz values) instead of its six; where a
    mode exists it shows above 0 at once and is found."""
    with pencil(_scene(200, (20, 20), state, mu)) as pen:  # tall enough for a cluster of slow vibrations
        theta = sigma_window.ritz_estimate(pen.A, pen.B, max_it=sigma_window.PROBE_RESTARTS)[0]
        kw = dict(J=pen.maps.J, method="active-set", lam_min=0.0, target=1.001 * theta, nev=1, max_iter=1,
                  options={"eps_max_it": search.FIRST_EPS_MAX_IT})
        eager = meicp.solve_eicp(pen.A, pen.B, give_up_after=search.FIRST_GIVE_UP, **kw)
        patient = meicp.solve_eicp(pen.A, pen.B, **kw)
    assert bool(eager.solutions) is mode and bool(patient.solutions) is mode
    if mode:
        assert eager.coverage["gave_up"] == 0 and np.isclose(eager.solutions[0].lam, patient.solutions[0].lam)
    else:
        assert eager.coverage["gave_up"] == 1 and eager.coverage["eps_iterations"] == search.FIRST_GIVE_UP
        assert patient.coverage["eps_iterations"] == search.FIRST_EPS_MAX_IT


def test_a_proof_is_written_with_the_keys_results_files_have_always_had():
    """results.json / results.h5 keep their keys (and their order) for each kind of proof."""
    window = DivergenceProof("condensed-windows", "s", 7, (0.0, math.inf), 3, margin=0.5)
    assert list(window.to_dict()) == ["test", "statement", "sigma_window", "supports_visited", "eigen_solves",
                                      "margin"]
    undecided = DivergenceProof("", "s", 7, None, 3, stable_friction_scale=0.5, stable_friction={"base": 1.0})
    assert undecided.to_dict() == {"test": "", "statement": "s", "sigma_window": None, "supports_visited": 7,
                                   "eigen_solves": 3, "stable_friction_scale": 0.5, "stable_friction": {"base": 1.0}}
    assert list(DivergenceProof("enumerate", "s", 16).to_dict()) == ["test", "supports_visited", "statement"]
    assert DivergenceProof("all-held", "s").to_dict() == {"test": "all-held", "statement": "s"}


def test_why_no_sigma_max_was_certified():
    """The reasons an undecided verdict gives for having no σ_max, where they are made."""
    top = sigma_window.TopEstimate(False, math.nan, False, 1.0, False)
    assert sigma_window.no_sigma_max(top) == "no σ-window (λ_max(sym A, sym B) not estimated)"
    stalled = sigma_window.TopEstimate(True, -1e-5, False, 1.0, False)
    assert sigma_window.no_sigma_max(stalled) == (
        f"no σ_max: no Ritz value of (sym A, sym B) above 0 in {sigma_window.PROBE_RESTARTS} Lanczos restarts "
        "(largest -1e-05; the top lies among the slow vibrations, where Lanczos stalls)")
    missed = sigma_window.TopEstimate(True, 2.5, True, 1.0, True)
    assert sigma_window.no_sigma_max(missed) == "no σ_max certified above the estimate 2.5 of λ_max(sym A, sym B)"


def test_a_pencil_with_no_stiffness_past_the_enumeration_is_undecided_not_a_crash(monkeypatch):
    """Every retained DOF a mechanism (A = 0): MUMPS factors no zero matrix, so its inertia is
    read without one (PETSc error 73 before)."""
    scene = scene_from_dict({
        "lattice": {"nx": 3}, "layers": [{"name": "L0", "rows": 1, "stiffness": 5.8, "density": 1.2},
                                         {"name": "L1", "rows": 1, "stiffness": 1.24, "density": 1.8}],
        "boundary": {"top": "fixed_x", "bottom": "fixed", "left": "free", "right": "free"},
        "interfaces": [{"below": "L0", "kind": "frictional", "friction": 1.0,
                        "states": ["slip+", "separated", "separated"]}]})
    with pencil(scene) as pen:
        assert not pen.A.toarray().any()
    assert meicp.analyze(scene, flutter=False).divergence is True  # σ = 0, enumerated
    monkeypatch.setattr(limits, "ENUMERATE_N", 0)
    assert meicp.analyze(scene, flutter=False).divergence is not False


def test_a_slow_mode_missed_at_the_first_shift_is_searched_for_below_it(monkeypatch):
    """Where the first search finds nothing at its shift and the condensed proof cannot exclude
    σ = 0 itself, short searches from shifts below the first one come before the whole search
    from the window's top, which reaches a mode just above 0 last: on the scaling family at
    10⁶ DOFs (σ = 4.1e-5, the proxy's shift 0.0092) that whole search ran past 10 minutes where
    the first shift below found the mode in 5 restarts.  Here the first shift is pushed 40×
    too high to miss the mode of a 10⁴-DOF lattice the same way."""
    scene = two_layer_scene(100, (25, 25), mu=2.0, states="slip+")
    expected = meicp.analyze(scene, None, method="active-set", flutter=False)
    monkeypatch.setattr(search, "PROXY_SHIFT", 40 * search.PROXY_SHIFT)
    r = meicp.analyze(scene, None, method="active-set", flutter=False)
    first = search.PROXY_SHIFT * proxy.rightmost_real(scene, contact_lines(scene, LatticeModel(scene)))
    assert r.divergence is True and [m.sigma for m in r.modes][:1] == pytest.approx([expected.modes[0].sigma])
    shift = float(r.evidence.split("search from σ = ")[1].split(":")[0])
    assert shift == pytest.approx(search.LOWER_SHIFTS[0] * first, rel=1e-5)
