"""One assembly of the lattice per analysis (issue 32): every step of ``analyze`` (the static
equilibrium, each contact state's pencil, the condensed proof, the friction range, flutter)
and of ``critical_friction`` (the static equilibrium, the enumeration, its bisection check, the
bracket's condensation) reads the K and M assembled once (``LatticeMatrices``).

Counted where K's entries are computed: ``stiffness_block``, whose first chunk (node row 0)
starts every assembly, serial or PETSc."""

import pytest

import meicp
import meicp.lattice.assembly as lattice_assembly
import meicp.petsc.assembly as petsc_assembly
from meicp.core import limits
from meicp.examples import two_layer_scene

from .conftest import ROOT
from .helpers import interface_chain_scene

SCENES = ROOT / "data" / "scenes"


@pytest.fixture
def assemblies(monkeypatch):
    """The lattices assembled, as (nx, ny) per assembly."""
    seen = []
    real = lattice_assembly.stiffness_block

    def counting(model, a, b, *args, **kwargs):
        if a == 0:
            seen.append((model.nx, model.ny))
        return real(model, a, b, *args, **kwargs)

    monkeypatch.setattr(lattice_assembly, "stiffness_block", counting)
    monkeypatch.setattr(petsc_assembly, "stiffness_block", counting)
    return seen


def test_the_undecided_path_of_analyze_assembles_once(assemblies):
    """80 pairs on each side of a one-row layer between two frictional interfaces at μ = 3 (B
    not diagonal there): the Rayleigh bound fails, the condensed proof is tried, the verdict is
    undecided and the friction range is proved; flutter decided too."""
    scene = interface_chain_scene(80, 3.0)
    r = meicp.analyze(scene)
    assert r.divergence is None and r.proofs[0].stable_friction
    assert assemblies == [(scene.nx, scene.ny)]


def test_analyze_with_static_states_assembles_once(assemblies):
    scene = meicp.load_scene(SCENES / "interface_shear_compression.toml")
    r = meicp.analyze(scene)
    assert r.static is not None and r.static.success
    assert assemblies == [(scene.nx, scene.ny)]


@pytest.mark.parametrize("bracket", [False, True])
def test_critical_friction_assembles_once(assemblies, monkeypatch, bracket):
    """Enumerated with its bisection check, or (limits.CRITICAL_J = 0) the bracket with its
    condensation; the states from the static equilibrium."""
    if bracket:
        monkeypatch.setattr(limits, "CRITICAL_J", 0)
    scene = two_layer_scene(9, (2, 2), mu=0.6, states="solve", load=(0.05, -0.1))
    mu = meicp.critical_friction(scene)
    assert mu.lower <= mu.upper
    assert assemblies == [(scene.nx, scene.ny)]
