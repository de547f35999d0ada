"""The MEiCP of a scene in its contact states (seed 000 §III, docs/design.md §7.2):
:func:`pencil` gives ``A = −P̃ K Q̃``, ``B = P̃ M Q̃``, the complementarity set J and the maps,
for the instability analysis, the critical friction, tests and benchmark scripts alike.

States come from the scene (prescribed), from the static frictional equilibrium when a
contact line says ``"solve"`` (:func:`contact_states`), or from the caller.  The lattice's K
and M are assembled once per analysis (:class:`~meicp.petsc.assembly.LatticeMatrices`) and every
pencil reduced from them keeps them (``Pencil.lattice``), with the communicator.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

from ..core.comm import mpi_comm
from ..core.errors import ConvergenceError
from ..core.matrix import is_petsc_mat
from ..lattice.model import LatticeModel
from ..petsc.assembly import LatticeMatrices
from ..petsc.mat import destroying
from ..petsc.pencil import reduced_matrix, reduced_pencil
from ..scene import SOLVE, Scene
from .lines import BASE, ContactLine, contact_lines, with_states
from .maps import ReducedSystem, reduced_system
from .static import StaticResult, static_equilibrium

log = logging.getLogger("meicp")


@dataclass
class Pencil:
    """One MEiCP ``(σB − A)x = w`` of a scene: ``A = −P̃ K Q̃``, ``B = P̃ M Q̃`` (SciPy CSR, or
    PETSc Mats distributed by the lattice's row bands), ``J`` the complementarity positions,
    ``maps`` the :class:`~meicp.contact.maps.ReducedSystem` (Q̃, P̃₀, P̃₁, μ, retained DOFs,
    which contact each J position belongs to), ``lines`` the contact lines with their states,
    ``lattice`` the :class:`~meicp.petsc.assembly.LatticeMatrices` (K, M, the communicator and
    the model) the pencil was reduced from, and ``static`` the static equilibrium the states
    came from (None when prescribed).  A context manager: A and B are destroyed on leaving it,
    and the lattice's K and M too when the pencil owns them (``owns_lattice``: made by
    :func:`pencil`; an analysis that reduces several pencils from one lattice destroys it itself)."""

    A: object
    B: object
    maps: ReducedSystem
    lines: tuple
    lattice: LatticeMatrices
    static: StaticResult | None = None
    owns_lattice: bool = False
    _damping: object = field(default=None, init=False, repr=False)

    @property
    def J(self) -> np.ndarray:
        return self.maps.J

    @property
    def K(self):
        return self.lattice.K

    @property
    def M(self):
        return self.lattice.M

    @property
    def comm(self):
        """The mpi4py communicator the pencil is distributed over (None: serial)."""
        return self.lattice.comm

    @property
    def model(self) -> LatticeModel:
        return self.lattice.model

    @property
    def distributed(self) -> bool:
        return is_petsc_mat(self.A)

    @property
    def damped(self) -> bool:
        """Whether the lattice has damping: the pencil is then quadratic, λ²B + λD − A with
        D = P̃CQ̃ (:mod:`meicp.contact.damped`)."""
        return self.lattice.model.damped

    def damping(self):
        """``D = P̃CQ̃`` in the pencil's layout (a PETSc Mat on the row bands when the pencil is
        distributed, else SciPy CSR), made once from the lattice's C and kept until
        :meth:`destroy` — the damped searches of one run share it.  Collective."""
        if self._damping is None:
            maps = self.maps
            C = self.lattice.damping_in_layout() if self.distributed else self.lattice.damping()
            with destroying(C):
                self._damping = reduced_matrix(C, maps.P, maps.Q, maps.retained)
        return self._damping

    def __enter__(self) -> "Pencil":
        return self

    def __exit__(self, *exc) -> None:
        self.destroy()

    def destroy(self) -> None:
        """Free PETSc matrices (collective): A and B, and K and M when owned; nothing to do for
        SciPy ones."""
        with destroying(self.A, self.B, self._damping):
            self.A = self.B = self._damping = None
        if self.owns_lattice:
            self.lattice.destroy()


def needs_static(scene: Scene) -> bool:
    """Whether some contact line's states come from the static equilibrium."""
    if scene.contact is not None and scene.contact.states == SOLVE:
        return True
    return any(i.kind == "frictional" and i.states in (SOLVE, None) for i in scene.interfaces)


def contact_states(scene: Scene, lattice: LatticeMatrices) -> tuple[tuple[ContactLine, ...] | None,
                                                                    StaticResult | None]:
    """The scene's contact lines with their states resolved, and the static equilibrium
    result when it was needed (else None).  When it failed the lines are None: the caller
    decides whether that is an error.  The static equilibrium reads the lattice's K (whole, on
    every rank: on several ranks a serial copy, dropped once its blocks are taken) and is
    collective on its communicator."""
    model = lattice.model
    lines = contact_lines(scene, model)
    if not needs_static(scene):
        return with_states(lines, None), None
    log.info("static equilibrium: frictional contact LCP")
    static = static_equilibrium(scene, model=model, comm=lattice.comm, lines=lines,
                                stiffness=lambda: lattice.whole()[0])
    if not static.success:
        return None, static
    return with_states(lines, {BASE: static.states, **static.interface_states}), static


def pencil_of(lattice: LatticeMatrices, lines, grazing_case: tuple = (),
              static: StaticResult | None = None, *, maps: ReducedSystem | None = None) -> Pencil:
    """The pencil of the assembled ``lattice`` for the states of ``lines`` and one grazing
    case (:func:`~meicp.contact.maps.grazing_cases`); ``maps``: the reduced system when the
    caller has it already (e.g. with another μ: :meth:`ReducedSystem.with_friction`)."""
    maps = reduced_system(lattice.model, lines, grazing_case) if maps is None else maps
    A = B = None
    if maps.retained.size:
        A, B = reduced_pencil(lattice.K, lattice.M, maps.P, maps.Q, maps.retained)
    return Pencil(A, B, maps, tuple(lines), lattice, static)


def pencil(scene: Scene, states=None, comm=None, *, grazing_case: tuple = ()) -> Pencil:
    """The MEiCP pencil of ``scene``: ``A = −P̃ K Q̃``, ``B = P̃ M Q̃``, J and the maps.

    states: None (the scene's own; the static equilibrium's when a line says ``"solve"``,
    ConvergenceError if it fails), or the states of the base (one state or a list, left to
    right), or a dict naming contact lines (``"base"``, each frictional interface by its
    lower layer) → states.  comm: None or a one-rank communicator for SciPy matrices, several
    ranks for distributed PETSc ones (collective; destroy them with ``Pencil.destroy`` or a
    ``with`` block: the pencil owns its lattice).  grazing_case: the tangential case of each
    grazing contact, one of :func:`~meicp.contact.maps.grazing_cases` (required when a contact
    is grazing)."""
    lattice = LatticeMatrices(LatticeModel(scene), mpi_comm(comm))
    try:
        static = None
        if states is None:
            lines, static = contact_states(scene, lattice)
            if lines is None:
                raise ConvergenceError(f"static equilibrium failed: {static.message}", static)
        else:
            lines = with_states(contact_lines(scene, lattice.model),
                                states if isinstance(states, dict) else {BASE: states})
        pen = pencil_of(lattice, lines, grazing_case, static)
    except BaseException:
        lattice.destroy()
        raise
    pen.owns_lattice = True
    return pen
