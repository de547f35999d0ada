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
from ..core.progress import duration
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


# --------------------------------------------------------------------------- what a run costs

#: ``analyze`` of the two-layer lattice at 10⁶ DOFs with every base contact sliding, by ranks:
#: (seconds, bytes per rank) measured on this machine (docs/benchmarks.md, "scaling": 36.5 s
#: and 4.1 GB on 1 rank, 22.9 s and 2.9 GB per rank on 2), with time ∝ n^1.15 and memory ∝
#: n^1.05 measured from 10⁴ to 10⁶ DOFs
MEASURED_ANALYSIS = {1: (36.5, 4.1e9), 2: (22.9, 2.9e9)}
#: the static frictional equilibrium (``states = "solve"``, the Schur formulation) at 10⁶ DOFs on
#: 2 ranks, added to the analysis: 13–16 s, 2.2 GB per rank (docs/benchmarks.md,
#: "The shipped scenes": extensive_solve.toml and extensive_interface.toml; the sparse mixed
#: LCP took 161 s and 6.9 GB); assumed to grow like the analysis
MEASURED_STATIC = (16.0, 2.2e9)
TIME_EXPONENT, MEMORY_EXPONENT = 1.15, 1.05
#: at or below this many DOFs a run takes about a second and the estimate is not worth a line
SMALL_DOFS = 10_000


@dataclass(frozen=True)
class CostEstimate:
    """A run's typical cost from :func:`typical_cost`: ``seconds`` of wall time and ``bytes``
    per rank on ``ranks`` ranks; ``low_bytes`` the per-rank share of the certain lower bound
    :func:`check_size` refuses by; ``static`` whether the static equilibrium is included."""

    dofs: int
    ranks: int
    seconds: float
    bytes: float
    low_bytes: float
    static: bool

    def describe(self) -> str:
        """One line for the progress output."""
        what = "analysis" + (" with the static equilibrium" if self.static else "")
        if self.dofs <= SMALL_DOFS:
            return f"size: {self.dofs:,} DOFs, a small {what}: about a second, well under 1 GB"
        more = " (more ranks extrapolated from 2)" if self.ranks > 2 else ""
        return (f"size: {self.dofs:,} DOFs; {what} on {self.ranks} rank(s) typically takes about "
                f"{duration(self.seconds)} and {_bytes(self.bytes)} per rank (at least {_bytes(self.low_bytes)}), "
                f"scaled from runs measured at 10⁶ DOFs{more}; a long search or proof can take several times longer")


def typical_cost(scene: Scene, ranks: int = 1, *, static: bool = False) -> CostEstimate:
    """What an analysis of ``scene`` typically costs on ``ranks`` ranks: the measurements of
    :data:`MEASURED_ANALYSIS` (and :data:`MEASURED_STATIC` when ``static``: the contact states
    come from the static equilibrium) scaled to the scene's DOFs.  A typical figure, not a
    bound: the divergence verdict of an undecided search or a condensed proof can take several
    times longer, and a 2-rank run is assumed to split further in proportion."""
    ranks = max(int(ranks), 1)
    dofs = estimate_size(scene).dofs
    seconds, per_rank = MEASURED_ANALYSIS[min(ranks, 2)]
    if static:
        seconds, per_rank = seconds + MEASURED_STATIC[0], max(per_rank, MEASURED_STATIC[1])
    spread = 2 / ranks if ranks > 2 else 1.0
    size = dofs / 1e6
    return CostEstimate(dofs, ranks, seconds * spread * size ** TIME_EXPONENT,
                        per_rank * spread * size ** MEMORY_EXPONENT,
                        estimate_size(scene).bytes / ranks, static)



