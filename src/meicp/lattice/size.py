"""What a scene costs, known before anything is built: DOFs, nonzeros of K and a low
estimate of the memory, checked against what the machine and PETSc's index type can hold.

A scene with ``nx = 10⁹`` used to grow until the machine ran out of memory without a message; now
it is refused at once with a :class:`~meicp.core.errors.ProblemError` that names the keys
(``lattice.nx``, ``layers[k].rows``).  The estimates are deliberately low (below every
measurement of docs/benchmarks.md), so a refusal is certain: the run could not fit.  A
scene that passes may still need more than it says.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..core.errors import ProblemError
from ..scene import Scene

#: nonzeros per DOF row of K, at most: a node and its 8 neighbours, 2 DOFs each
NONZEROS_PER_DOF = 18
#: bytes per DOF, at least, of each use of a scene: below every measurement, so that a
#: refusal is certain (the measurements: docs/benchmarks-notes.md, lattice)
BYTES_PER_DOF = {"analysis": 3000, "lattice": 400, "geometry": 150}
_USES = {"analysis": "an analysis", "lattice": "the lattice with K and M", "geometry": "the lattice geometry"}


@dataclass(frozen=True)
class SizeEstimate:
    """DOFs, nonzeros of K (an upper bound) and bytes (a low estimate) of one use of a scene."""

    dofs: int
    nonzeros: int
    bytes: int


def estimate_size(scene: Scene, use: str = "analysis") -> SizeEstimate:
    """The :class:`SizeEstimate` of ``use`` (``"analysis"``: ``analyze`` or
    ``critical_friction``; ``"lattice"``: assembling K and M and writing them with the
    geometry; ``"geometry"``: the geometry alone)."""
    dofs = 2 * scene.nx * scene.ny
    return SizeEstimate(dofs, NONZEROS_PER_DOF * dofs, BYTES_PER_DOF[use] * dofs)


def check_size(scene: Scene, *, memory: int | None, index_max: int | None = None, ranks: int = 1,
               use: str = "analysis", where: str = "this machine") -> SizeEstimate:
    """Raise :class:`ProblemError` naming the scene's size keys when ``use`` of the scene
    cannot fit: more DOFs than ``index_max`` (PETSc's largest index; None: no PETSc), more
    nonzeros per rank than that, or more bytes than ``memory`` (None: unknown, not checked)
    on ``ranks`` ranks.  ``where`` says where ``memory`` was measured."""
    est = estimate_size(scene, use)
    size = _size_keys(scene, est)
    if index_max is not None:
        bits = index_max.bit_length() + 1
        if est.dofs > index_max:
            raise ProblemError(f"{size}: more than the {index_max:,} that this PETSc build's {bits}-bit "
                               "indices can number; reduce lattice.nx or the layers' rows")
        if est.nonzeros > index_max * ranks:
            need = -(-est.nonzeros // index_max)
            raise ProblemError(f"{size}: K would have up to {est.nonzeros:,} nonzeros, more than "
                               f"{ranks} rank(s) can hold with {bits}-bit PETSc indices; use at least "
                               f"{need} ranks or reduce lattice.nx or the layers' rows")
    if memory is not None and est.bytes > memory:
        raise ProblemError(f"{size}: {_USES[use]} needs at least about {_bytes(est.bytes)} "
                           f"({BYTES_PER_DOF[use]:,} bytes per DOF, measured), but {where} has "
                           f"{_bytes(memory)} available; reduce lattice.nx or the layers' rows")
    return est


def _size_keys(scene: Scene, est: SizeEstimate) -> str:
    rows = ", ".join(f"layers[{k}].rows = {layer.rows:,}" for k, layer in enumerate(scene.layers[:4]))
    if len(scene.layers) > 4:
        rows += ", ..."
    where = f"{scene.source}: " if scene.source else ""
    return (f"{where}lattice.nx = {scene.nx:,} columns × {scene.ny:,} rows ({rows}) = "
            f"{est.dofs:,} DOFs")


def _bytes(n: float) -> str:
    units = ("B", "kB", "MB", "GB", "TB", "PB", "EB")
    k = 0
    while n >= 1000 and k < len(units) - 1:
        n, k = n / 1000, k + 1
    return f"{n:.3g} {units[k]}"
