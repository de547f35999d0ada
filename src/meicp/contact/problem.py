"""The MEiCP of a scene in its contact states (seed 000 §III, docs/design.md §7.2):
:func:`pencil` gives ``A = −P̃ K Q̃``, ``B = P̃ M Q̃``, the complementarity set J and the maps,
for the instability analysis, the critical friction, tests and benchmark scripts alike.

States come from the scene (prescribed), from the static frictional equilibrium when a
contact set says ``"solve"`` (:func:`contact_states`), or from the caller.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from ..core.comm import mpi_comm
from ..core.errors import ConvergenceError
from ..core.matrix import is_petsc_mat
from ..lattice.model import LatticeModel
from ..petsc.assembly import assemble
from ..petsc.mat import destroying
from ..petsc.pencil import reduced_pencil
from ..scene import SOLVE, Scene
from .maps import ContactSet, ReducedSystem, contact_sets, reduced_system
from .static import StaticResult, static_equilibrium

log = logging.getLogger("meicp")


@dataclass
class Pencil:
    """One MEiCP ``(σB − A)x = w`` of a scene: ``A = −P̃ K Q̃``, ``B = P̃ M Q̃`` (SciPy CSR, or
    PETSc Mats distributed by the lattice's row bands), ``J`` the complementarity positions,
    ``maps`` the :class:`~meicp.contact.maps.ReducedSystem` (Q̃, P̃, retained DOFs, which
    contact each J position belongs to), ``sets`` the contact lines with their states,
    ``model`` the lattice and ``static`` the static equilibrium the states came from (None
    when prescribed).  A context manager: PETSc matrices are destroyed on leaving it."""

    A: object
    B: object
    maps: ReducedSystem
    sets: list
    model: LatticeModel
    static: StaticResult | None = None

    @property
    def J(self) -> np.ndarray:
        return self.maps.J

    @property
    def distributed(self) -> bool:
        return is_petsc_mat(self.A)

    def __enter__(self) -> "Pencil":
        return self

    def __exit__(self, *exc) -> None:
        self.destroy()

    def destroy(self) -> None:
        """Free PETSc matrices (collective); nothing to do for SciPy ones."""
        with destroying(self.A, self.B):
            self.A = self.B = None


def needs_static(scene: Scene) -> bool:
    """Whether some contact set's states come from the static equilibrium."""
    if scene.contact is not None and scene.contact.states == SOLVE:
        return True
    return any(i.kind == "frictional" and i.states in (SOLVE, None) for i in scene.interfaces)


def contact_states(scene: Scene, model: LatticeModel, comm=None) -> tuple[list[ContactSet] | None,
                                                                          StaticResult | None]:
    """The scene's contact lines with their states resolved, and the static equilibrium
    result when it was needed (else None).  When it failed the lines are None: the caller
    decides whether that is an error.  Collective on ``comm`` (the static equilibrium)."""
    if not needs_static(scene):
        return contact_sets(scene, model), None
    log.info("static equilibrium: frictional contact LCP")
    static = static_equilibrium(scene, model=model, comm=mpi_comm(comm))
    if not static.success:
        return None, static
    return contact_sets(scene, model, {"base": static.states, **static.interface_states}), static


def pencil_of(K, M, model: LatticeModel, sets: list[ContactSet], grazing_case: tuple = (),
              static: StaticResult | None = None) -> Pencil:
    """The pencil of already assembled K, M (SciPy, or PETSc when distributed) for the states
    of ``sets`` and one grazing case (:func:`~meicp.contact.maps.grazing_cases`)."""
    maps = reduced_system(model, sets, grazing_case)
    A = B = None
    if maps.retained.size:
        A, B = reduced_pencil(K, M, maps.P, maps.Q, maps.retained)
    return Pencil(A, B, maps, sets, model, static)


def pencil(scene: Scene, states=None, comm=None, *, grazing_case: tuple = ()) -> Pencil:
    """The MEiCP pencil of ``scene``: ``A = −P̃ K Q̃``, ``B = P̃ M Q̃``, J and the maps.

    states: None (the scene's own; the static equilibrium's when a set says ``"solve"``,
    ConvergenceError if it fails), or the states of the base (one state or a list, left to
    right), or a dict naming contact lines (``"base"``, each frictional interface by its
    lower layer) → states.  comm: None or a one-rank communicator for SciPy matrices, several
    ranks for distributed PETSc ones (collective; destroy them with ``Pencil.destroy`` or a
    ``with`` block).  grazing_case: the tangential case of each grazing contact, one of
    :func:`~meicp.contact.maps.grazing_cases` (required when a contact is grazing)."""
    comm = mpi_comm(comm)
    model = LatticeModel(scene)
    static = None
    if states is None:
        sets, static = contact_states(scene, model, comm)
        if sets is None:
            raise ConvergenceError(f"static equilibrium failed: {static.message}", static)
    else:
        sets = contact_sets(scene, model, states if isinstance(states, dict) else {"base": states})
    with destroying(*assemble(model, comm)) as (K, M):
        return pencil_of(K, M, model, sets, grazing_case, static)
