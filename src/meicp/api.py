"""The public entry points that take a scene: :func:`analyze`, :func:`critical_friction`,
:func:`assemble`, :func:`assemble_damping`; and :func:`load_results`, which reads a results.h5 back.

A scene is taken in any of its forms (:func:`meicp.io.scene.as_scene`): a
:class:`~meicp.scene.Scene`, the path of a scene file, a dict (the parsed table) or TOML text.
It is read here, above the packages that do the work, so that the lattice and the contact
analysis depend on the scene's dataclasses only, never on the file format.  Every keyword is
explicit (a misspelt one is a TypeError naming the nearest) and checked before any work
(a ProblemError naming it).

``comm=None`` means ``MPI.COMM_WORLD`` for :func:`analyze` and :func:`critical_friction`, as
in petsc4py and DOLFINx: under ``mpirun`` every rank calls them and shares the work (pass
``MPI.COMM_SELF`` for one independent serial run per rank); without ``mpirun`` it is one
process.  :func:`assemble` keeps its contract instead: None gives SciPy matrices on this
process, a communicator PETSc Mats on it — the kind of matrix it returns does not change with
how the program was started.
"""

from __future__ import annotations

from .contact.critical_friction import CriticalFriction
from .contact.critical_friction import critical_friction as _critical_friction
from .contact.critical_friction.solve import check_arguments
from .contact.instability import REFUSED_OPTIONS
from .contact.instability import analyze as _analyze
from .contact.result import InstabilityResult
from .contact.stored import result_from_record
from .core.comm import check_comm, world_if_none
from .core.validation import checked_keywords
from .io.results_read import read_results
from .io.scene import as_scene
from .lattice.model import LatticeModel
from .petsc.assembly import assemble as _assemble
from .petsc.assembly import assemble_damping as _assemble_damping


@checked_keywords(refused=REFUSED_OPTIONS)
def analyze(scene, comm=None, *, method: str | None = None, lam_min: float | None = None,
            tol: float | None = None, flutter: bool | None = None, nev: int | None = None,
            target: float | None = None, max_iter: int | None = None, max_j: int | None = None,
            options: dict | None = None, flutter_dense_max: int | None = None) -> InstabilityResult:
    """Decide whether a scene is stable: its contact states, divergence modes (real σ ≥ 0 of
    the MEiCP), flutter of steady sliding (complex σ), each verdict with its evidence.

    A scene without contact has no frictional instability to decide: it gets a modal
    analysis instead (its lowest vibration modes, ``result.analysis == "modal"``).

    Parameters
    ----------
    scene : Scene, str, os.PathLike, dict or str
        A :class:`~meicp.scene.Scene`; the path of a scene file; the scene's table as a dict
        (as ``tomllib`` would parse the file); or the TOML text itself (a ``str`` with a line
        break; a ``str`` without one is a path).
    comm : None, mpi4py or PETSc communicator
        The ranks that share the work (collective: every rank of it calls ``analyze``).
        None: ``MPI.COMM_WORLD`` — all the ranks of an ``mpirun`` job, one process without
        it.  ``MPI.COMM_SELF``: this process alone, whatever the job.
    method : {"auto", "enumerate", "active-set", "rayleigh", "semismooth"} or None
        The MEiCP method; None: the scene's ``[solver] method`` (``auto``: enumeration when
        small, else the proofs that scale in the order of :mod:`meicp.contact.divergence.driver`:
        Rayleigh bound at 0, a first short search, condensed proof, σ-window where that proof
        stops, the whole active-set search).
    lam_min : float or None
        List only the modes with σ ≥ lam_min (finite, ≥ 0); None: the scene's, else 0.  The
        verdict is about every σ ≥ 0 regardless (the evidence counts the modes left out).
    tol : float or None
        Certificate tolerance in (0, 1e-2]; None: the scene's, else 1e-10.
    flutter : bool or None
        Also decide flutter of steady sliding; None: the scene's ``[solver] flutter``
        (true).  False leaves ``result.flutter`` None, so ``stable`` cannot be True.
    nev : int or None
        Eigenpairs per eigen-solve (the vibration modes of a scene without contact).
    target : float or None
        Shift of the active-set search's SLEPc solves (default: the top of the σ-window, and for
        the first, short search 1.25× the contact-strip proxy's rightmost real σ when lower).
    max_iter : int or None
        The active-set search's budget of support updates (default: the scene's
        ``[solver] max_iterations``).
    max_j : int or None
        Raise the enumeration's limit of complementarity pairs (≤ 26), accepting its cost.
    options : dict or None
        PETSc options of the eigen-solves, without the leading dash and the prefix
        (default: the scene's ``[petsc]`` table).
    flutter_dense_max : int or None
        Retained DOFs up to which flutter takes the dense path (every eigenvalue: the
        growth bracket exact, flutter absence provable); None: ``FLUTTER_DENSE_MAX`` (2,500).
        Larger values buy exactness with O(n³) time: about 60 s at 3,300 retained DOFs,
        144 s at 5,000 on this machine.

    Returns
    -------
    InstabilityResult
        ``stable`` (True / False / None), ``divergence``, ``flutter``, ``modes`` (each
        ``sigma``, ``growth_rate``, ``x`` in natural numbering, ``support``),
        ``flutter_modes``, ``evidence``, ``flutter_evidence``, ``proofs``, ``states``,
        ``interface_states``, ``static``, ``sizes``, ``timings``; ``to_dict()`` is what
        ``meicp solve --json`` prints, ``summary()`` a readable report.

    Raises
    ------
    ProblemError
        A bad scene (naming its key), or a bad argument (naming it): ``comm`` that is not a
        communicator, ``lam_min < 0``, ``tol`` out of range, an unknown method, ``nev = 0``...
    TypeError
        An unknown keyword, with the nearest known one (``flutterr`` → ``flutter``).

    Examples
    --------
    >>> result = meicp.analyze("data/scenes/two_layers.toml")              # doctest: +SKIP
    >>> result.stable, result.modes[0].sigma                               # doctest: +SKIP
    (False, 0.3290...)
    >>> scene = meicp.load_scene("data/scenes/two_layers.toml")            # doctest: +SKIP
    >>> meicp.analyze(scene.with_friction(0.3)).stable                     # doctest: +SKIP
    True
    """
    scene = as_scene(scene)
    comm = world_if_none(comm)
    given = {name: value for name, value in (("nev", nev), ("target", target), ("max_iter", max_iter),
                                             ("max_j", max_j), ("options", options),
                                             ("flutter_dense_max", flutter_dense_max)) if value is not None}
    return _analyze(scene, comm, method=method, lam_min=lam_min, tol=tol, flutter=flutter, **given)


@checked_keywords()
def critical_friction(scene, *, mu_max: float = 1e3, bisection: bool | None = None, tol: float = 1e-8,
                      comm=None, flutter: bool | None = None) -> CriticalFriction:
    """The friction at which the first instability starts, for the scene's contact states
    (one μ for every frictional contact), as certified brackets of both onsets
    (docs/critical-friction.md): ``divergence`` — μ_c, the smallest μ ≥ 0 with a σ = 0
    divergence mode — and ``flutter`` — μ_f, the smallest μ with a non-real σ of the sliding
    pencil; the float's value is the smaller, ``first`` says which.

    μ_c: up to 20 complementarity pairs the EiCP in μ is enumerated (exact); beyond, a
    bracket: the lower end proved, the upper end a certified mode.  μ_f: an interval cover
    from μ = 0 proves the lower end (dense pencils, up to ``FLUTTER_DENSE_MAX`` retained
    DOFs), a certified flutter mode gives the upper end; past the dense limit the lower end
    is 0.  Prescribed states are taken as they are; ``"solve"`` takes the states of the
    static equilibrium at the scene's μ.

    Parameters
    ----------
    scene : Scene, str, os.PathLike, dict or str
        As for :func:`analyze`: a Scene, a file's path, the table as a dict, or TOML text.
    mu_max : float
        The largest μ searched (finite, > 0); no mode up to it gives ``inf``.
    bisection : bool or None
        Cross-check an enumerated μ_c on the σ-problem with the mass: None runs it when
        that enumeration is cheap, True always, False never.
    tol : float
        The bisection's relative width in μ, in (0, 0.01].
    comm : None, mpi4py or PETSc communicator
        The ranks that share the condensations of a bracket (collective).  None:
        ``MPI.COMM_WORLD``, as for :func:`analyze`.
    flutter : bool or None
        Bracket the flutter onset too: None takes the scene's ``[solver] flutter`` (default
        True); False gives the divergence onset alone (faster).

    Returns
    -------
    CriticalFriction
        A float (the upper end of the overall bracket: a μ with a certified mode; ``inf``
        when none up to ``mu_max``) carrying ``lower``, ``upper``, ``exact``, ``evidence``,
        ``divergence`` and ``flutter`` (each an ``Onset``: ``lower``, ``upper``, ``exact``,
        ``evidence``; ``flutter`` None when not analysed), ``first`` and ``describe()``.

    Raises
    ------
    ProblemError
        A bad scene or argument, naming it (``mu_max`` not a finite number > 0...), or a
        scene whose μ_c is undefined (a motion of zero stiffness compatible with the slip).
    ConvergenceError
        The bisection check contradicts the enumeration.
    TypeError
        An unknown keyword, with the nearest known one.
    """
    mu_max, tol, bisection = check_arguments(mu_max, tol, bisection)
    scene = as_scene(scene)
    return _critical_friction(scene, mu_max=mu_max, bisection=bisection, tol=tol, comm=world_if_none(comm),
                              flutter=flutter)


@checked_keywords()
def assemble(scene, comm=None):
    """The lattice's stiffness K and lumped mass M in natural numbering (DOF 2n: x, 2n + 1: y
    of node n = j·nx + i), without the contacts or boundary conditions.

    Parameters
    ----------
    scene : Scene, LatticeModel, str, os.PathLike, dict or str
        A Scene or a :class:`~meicp.lattice.model.LatticeModel` built from one, or a scene in
        any form :func:`analyze` takes.
    comm : None, mpi4py or PETSc communicator
        None: SciPy sparse matrices on this process (also under ``mpirun``: this is the
        serial contract tests and scripts rely on).  A communicator: PETSc Mats distributed
        on it (collective).

    Returns
    -------
    (K, M)
        Two SciPy CSR matrices, or two PETSc Mats.

    Raises
    ------
    ProblemError
        A bad scene (naming its key) or a ``comm`` that is not a communicator.
    """
    check_comm(comm)
    return _assemble(scene if isinstance(scene, LatticeModel) else as_scene(scene), comm)


@checked_keywords()
def assemble_damping(scene, comm=None):
    """The lattice's damping matrix C in natural numbering (docs/damping.md): assembled
    exactly like K with each bond's viscosity η in place of its stiffness (a bond joining
    two materials gets the mean, or its bonded interface's own ``viscosity``), plus
    ``[damping] mass`` · M.  Without damping keys it is zero (K's pattern, explicit zeros).

    Parameters
    ----------
    scene : Scene, LatticeModel, str, os.PathLike, dict or str
        As for :func:`assemble`.
    comm : None, mpi4py or PETSc communicator
        None: a SciPy CSR matrix on this process; a communicator: a PETSc Mat distributed
        on it as K is (collective; the caller destroys it).

    Returns
    -------
    C
        A SciPy CSR matrix or a PETSc Mat, symmetric positive semidefinite.

    Raises
    ------
    ProblemError
        A bad scene (naming its key) or a ``comm`` that is not a communicator.
    """
    check_comm(comm)
    return _assemble_damping(scene if isinstance(scene, LatticeModel) else as_scene(scene), comm)


@checked_keywords()
def load_results(path) -> InstabilityResult:
    """The result that ``meicp solve`` (or :func:`meicp.io.results.write_results`) wrote to a
    results.h5, read back.

    Parameters
    ----------
    path : str or os.PathLike
        The results.h5 file (the output directory's ``results.h5``).

    Returns
    -------
    InstabilityResult
        With everything the file holds: verdicts, evidence, modes and flutter modes (shapes
        ``x`` included), proofs, contact states, sizes, timings, the static equilibrium's
        status, reactions and displacement, and ``critical_friction`` when it was computed.
        ``eicp`` holds each MEiCP's method, status and message only (no solutions), and
        ``static`` no LCP or matrix classes.  The scene is the file's ``/scene`` text
        (:func:`meicp.io.scene.loads_scene` reads it).

    Raises
    ------
    ProblemError
        No such file, not an HDF5 file, not a meicp results file, or a newer format.
    """
    return result_from_record(read_results(path))
