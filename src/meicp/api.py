"""The public entry points that take a scene file as well as a :class:`~meicp.scene.Scene`.

The file is read here (:func:`meicp.io.scene.load_scene`), above the packages that do the
work, so that the lattice and the contact analysis depend on the scene's dataclasses only,
never on the file format.  Everything else is the function it calls.
"""

from __future__ import annotations

from .contact.critical_friction import critical_friction as _critical_friction
from .contact.instability import analyze as _analyze
from .contact.result import InstabilityResult
from .io.scene import as_scene
from .lattice.model import LatticeModel
from .petsc.assembly import assemble as _assemble


def analyze(scene, comm=None, **options) -> InstabilityResult:
    """:func:`meicp.contact.instability.analyze` of a Scene or a scene file."""
    return _analyze(as_scene(scene), comm, **options)


def critical_friction(scene, **options) -> float:
    """:func:`meicp.contact.critical_friction.critical_friction` of a Scene or a scene file."""
    return _critical_friction(as_scene(scene), **options)


def assemble(scene, comm=None):
    """:func:`meicp.petsc.assembly.assemble` (``(K, M)``: SciPy when ``comm`` is None, PETSc
    Mats on ``comm``) of a Scene, a :class:`LatticeModel` or a scene file."""
    return _assemble(scene if isinstance(scene, LatticeModel) else as_scene(scene), comm)
