"""The cheap numbers the README and docs quote, re-computed by today's code: each claim is read
from the text (so the test follows an edit of it) and checked to the digits printed.  The
README's Python example is run by tests/test_examples.py; the 10⁶-DOF figures are
benchmarks (docs/benchmarks.md), not tests."""

import dataclasses
import re

import numpy as np
import pytest

import meicp
from meicp.core import limits
from meicp.io.scene import loads_scene

from .conftest import ROOT
from .helpers import interface_chain_scene

README = (ROOT / "README.md").read_text()
SCENES_README = (ROOT / "data" / "scenes" / "README.md").read_text()
FLUTTER = (ROOT / "docs" / "flutter.md").read_text()
BENCHMARKS = (ROOT / "docs" / "benchmarks.md").read_text()
SCENES = ROOT / "data" / "scenes"


def quoted(pattern: str, text: str) -> str:
    """The one number ``pattern``'s group captures in ``text`` (the claim must be there)."""
    found = re.findall(pattern, text, re.S)
    assert len(found) >= 1, f"no claim matches {pattern!r}"
    assert len(set(found)) == 1, f"the text quotes different values: {found}"
    return found[0]


def close(value: float, printed: str) -> bool:
    """``value`` rounds to ``printed`` (half a unit of its last digit)."""
    digits = len(printed.split(".")[1]) if "." in printed else 0
    return abs(value - float(printed)) <= 0.5 * 10.0 ** -digits * (1 + 1e-9)


def two_layers(mu: float | None = None):
    scene = meicp.load_scene(SCENES / "two_layers.toml")
    return scene if mu is None else dataclasses.replace(scene, contact=dataclasses.replace(scene.contact, friction=mu))


def test_mu_c_of_two_layers():
    printed = quoted(r"divergence\s+at μ_c ≈ ([\d.]+)", README)
    assert close(meicp.critical_friction(two_layers(), bisection=False, flutter=False), printed)


def test_the_flutter_onset_of_two_layers():
    """flutter.md's bisection bracket, verdict by verdict, and the README's rounding of it."""
    below, above = map(float, re.search(r"False \(a proof\) at ([\d.]+)\s+and True at ([\d.]+)", FLUTTER).groups())
    at_below, at_above = meicp.analyze(two_layers(below)), meicp.analyze(two_layers(above))
    assert at_below.flutter is False and "proof" in at_below.flutter_evidence
    assert at_above.flutter is True
    assert close(below, quoted(r"flutter starts at μ ≈ ([\d.]+)", README))
    assert close(below, quoted(r"flutter from μ ≈ ([\d.]+)", SCENES_README))
    lower, upper = map(float, re.search(r"flutter starts at \*\*μ_f ∈ \[([\d.]+), ([\d.]+)\]\*\*", FLUTTER).groups())
    assert lower <= below < above <= upper
    onset = meicp.critical_friction(two_layers()).flutter
    assert onset.exact and close(onset.lower, repr(lower)) and close(onset.upper, repr(upper))
    benchmark = quoted(r"flutter from \*\*μ = ([\d.]+)\*\*", BENCHMARKS)
    assert close(below, benchmark) and close(above, benchmark)


def test_the_fastest_flutter_mode_of_two_layers():
    """flutter.md's example: σ, growth rate and frequency of the fastest flutter mode at μ = 3."""
    sig, growth, freq = re.search(r"# \(([-\d.]+[+-][\d.]+j)\), ([\d.]+), ([\d.]+)", FLUTTER).groups()
    r = meicp.analyze(two_layers())
    fast = r.flutter_modes[0]
    re_s, im_s = re.fullmatch(r"([-\d.]+)([+-][\d.]+)j", sig).groups()
    assert close(fast.sigma.real, re_s) and close(fast.sigma.imag, im_s)
    assert close(fast.growth_rate, growth) and close(fast.frequency, freq)


def _growth_list(what: str) -> dict:
    """μ → growth rate, from the stability map's "(0.083 at μ = 2, 0.174 at 3, …)" after ``what``."""
    text = re.search(r"\*\*Stability map.*?(?=\n\n)", BENCHMARKS, re.S).group(0)
    items = re.search(rf"{what} \(([^)]*)\)", text, re.S).group(1)
    return {float(mu): g for g, mu in re.findall(r"([\d.]+) at (?:μ = )?([\d.]+)", items)}


FLUTTER_GROWTH = _growth_list("its growth then about linear in μ")
DIVERGENCE_GROWTH = _growth_list("below the divergence growth rate")


@pytest.mark.parametrize("mu", sorted(FLUTTER_GROWTH))
def test_the_stability_map_growth_rates(mu):
    """docs/benchmarks.md's stability map of two_layers.toml: growth rates at μ."""
    r = meicp.analyze(two_layers(mu))
    assert close(r.flutter_modes[0].growth_rate, FLUTTER_GROWTH[mu])
    if mu in DIVERGENCE_GROWTH:
        assert close(r.modes[0].growth_rate, DIVERGENCE_GROWTH[mu])


def test_the_stability_map_quotes_growth_rates():
    assert len(FLUTTER_GROWTH) >= 3 and len(DIVERGENCE_GROWTH) >= 2


@pytest.mark.parametrize("name", ["sheared_slip_plus", "sheared_slip_minus"])
def test_mu_c_of_the_sheared_scenes(name):
    printed = quoted(rf"`{name}\.toml`[^\n]*?μ_c = ([\d.]+)", SCENES_README)
    mu_c = meicp.critical_friction(SCENES / f"{name}.toml", bisection=False, flutter=False)
    assert mu_c.exact and close(mu_c, printed)


def test_the_friction_range_of_an_undecided_verdict():
    """README: 80 pairs on each side of a one-row layer between two interfaces at μ = 3 are
    undecided, "proved for μ ≤ 0.973" (a single interface is decided since centre-of-mass
    coordinates)."""
    printed = quoted(r"one-row layer between two frictional interfaces, sides fixed, at\s+μ = 3: "
                     r"\"proved for\s+μ ≤ ([\d.]+)\"", README)
    r = meicp.analyze(interface_chain_scene(80, 3.0), flutter=False)
    assert r.divergence is None
    assert close(r.proofs[0].stable_friction["lower"], printed)


def test_the_limits_the_readme_quotes():
    assert int(quoted(r"Small pencils \(≤ ([\d,]+) retained DOFs\)", README).replace(",", "")) \
        == limits.FLUTTER_DENSE_MAX
    assert int(quoted(r"up to (\d+)\s+sliding contacts, `enumerate`", README)) == limits.ENUMERATE_J
    assert int(quoted(r"raises the limit, up to (\d+)", README)) == limits.MAX_ENUMERATED
    mantissa, exponent = re.search(r"passes (\d)·10(\S+) flops", README).groups()
    assert float(mantissa) * 10.0 ** int(exponent.translate(str.maketrans("⁰¹²³⁴⁵⁶⁷⁸⁹", "0123456789"))) \
        == limits.ENUMERATE_MAX_FLOPS
    # "16 pairs up to r ≈ 310": the order r at which 2^16·r³ reaches the budget
    r = float(quoted(r"16 pairs up to\s+r ≈ (\d+)", README))
    assert abs((limits.ENUMERATE_MAX_FLOPS / 2 ** 16) ** (1 / 3) - r) < 5


def test_the_scenes_page_example_is_stable_with_every_base_node_sticking():
    doc = (ROOT / "docs" / "scenes.md").read_text()
    assert "every base node\nsticks, STABLE" in doc or "every base node sticks, STABLE" in doc.replace("\n", " ")
    example = re.search(r"## Example\n.*?```toml\n(.*?)```", doc, re.S).group(1)
    r = meicp.analyze(loads_scene(example))
    assert r.stable is True and set(r.states) == {"stick"} and len(r.states) == loads_scene(example).nx
    assert np.isfinite(r.timings["total"])
