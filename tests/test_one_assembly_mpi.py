"""Assemblies of one analysis on 2 ranks (issue 32): the distributed K and M once; the
lattice read whole on every rank (the condensation's pieces, the static equilibrium's data)
built once by each consumer that needs it, at its own time — cheaper in time and memory than
gathering the PETSc rows or keeping a whole copy through the factorisations
(docs/benchmarks-notes.md, "LatticeMatrices.whole")."""

import pytest

import meicp
import meicp.petsc.assembly as petsc_assembly

from .conftest import ROOT
from .helpers import interface_chain_scene

pytestmark = pytest.mark.mpi(min_size=2)
SCENES = ROOT / "data" / "scenes"


@pytest.fixture
def counted(monkeypatch):
    """(kind, nx, ny) of every assembly this rank takes part in: ``petsc`` (its rows of the
    distributed K, M) or ``whole`` (the serial assembly, on this rank)."""
    seen = []
    petsc, whole = petsc_assembly.assemble_petsc, petsc_assembly.assemble_scipy

    def counting_petsc(model, comm, *args, **kwargs):
        seen.append(("petsc", model.nx, model.ny))
        return petsc(model, comm, *args, **kwargs)

    def counting_whole(model, *args, **kwargs):
        seen.append(("whole", model.nx, model.ny))
        return whole(model, *args, **kwargs)

    monkeypatch.setattr(petsc_assembly, "assemble_petsc", counting_petsc)
    monkeypatch.setattr(petsc_assembly, "assemble_scipy", counting_whole)
    return seen


def test_the_undecided_path_on_two_ranks_assembles_the_lattice_once(comm, counted):
    """80 pairs on each side of a one-row layer between two frictional interfaces at μ = 3
    (undecided: the Rayleigh bound, the condensed proof and the friction range all run): one
    distributed assembly, one whole copy (the condenser's); flutter's contact-strip proxy is a
    lattice of its own."""
    scene = interface_chain_scene(80, 3.0)
    r = meicp.analyze(scene, comm=comm)
    assert r.divergence is None
    mine = [c[0] for c in counted if c[1:] == (scene.nx, scene.ny)]
    assert mine == ["petsc", "whole"]
