"""``static_equilibrium``: the contact states of a scene under its load, by the condensed or
the mixed formulation (docs/static-equilibrium.md)."""

from __future__ import annotations

import time

from ...core import limits
from ...core.errors import ProblemError
from ...lattice.model import LatticeModel
from ...lcp.problem import DEFAULT_TOL as LCP_TOL
from ...scene import Scene
from .condensed import solve_condensed
from .data import static_data
from .mixed import solve_mixed
from .result import StaticResult
from .schur import solve_schur

#: default relative tolerance of the state classification (docs/static-equilibrium.md)
TOL = 1e-9
FORMULATIONS = ("auto", "condensed", "schur", "mixed")


def static_equilibrium(scene, *, model=None, tol: float = TOL, method: str = "auto",
                       classify_limit: int = 12, lcp_tol: float = LCP_TOL,
                       allow_floating: bool = True, formulation: str = "auto", comm=None,
                       petsc_options: dict | None = None, lines=None, stiffness=None, **lcp_options) -> StaticResult:
    """Static frictional equilibrium of ``scene`` under its ``[load]``; every contact's state.

    scene: a :class:`~meicp.scene.Scene`; model: its
    :class:`~meicp.lattice.model.LatticeModel` if already built.  Every contact set of the
    scene (rigid base, frictional interfaces) is solved together, whatever its ``states``
    key says (the sets interact; the caller picks the sets it asked to solve).

    tol: relative classification tolerance; method: passed to :func:`meicp.solve_lcp`
    (``auto`` = dense Lemke here, with fallbacks); lcp_tol: its certificate tolerance;
    classify_limit: ``exact_limit`` of :func:`meicp.classify` on the LCP matrix;
    allow_floating: condense rigid components held by contact instead of raising.

    formulation: ``"condensed"`` (dense compliance, Lemke; classifies the LCP matrix),
    ``"schur"`` (one MUMPS factorisation of the bordered stiffness, distributed over ``comm``,
    its Schur complement G; the frictional problem of order 2 per contact on G by NSGS and an
    exact active-set polish, certified on the sparse problem; options under
    ``-meicp_static_schur_``; needs K_ff invertible), ``"mixed"`` (sparse, displacements kept, PETSc SNES VI + certified polish; no matrix
    classes; options ``petsc_options`` under ``-meicp_static_``) or ``"auto"`` (condensed up
    to :data:`limits.STATIC_AUTO_CONDENSED_LIMIT` contacts, then schur up to
    :data:`limits.STATIC_SCHUR_MAX_CONTACTS`, else mixed; mixed too, with a note saying why, when a rigid
    component floats on its contacts).  comm: with several ranks the schur and
    mixed formulations' PETSc solves are distributed over it (collective then: every rank
    calls with the same scene); the condensed formulation ignores it.

    lines: the scene's contact lines (:func:`~meicp.contact.lines.contact_lines`) when the
    caller has them already; stiffness: a function giving the scene's SciPy K (``analyze``
    assembles once per run), called when K is needed and not held after its pieces are taken
    (the static solve itself keeps only K_ff); None: assembled here.

    Deterministic: under MPI every rank may call it with the same scene and gets the same
    answer.  Raises :class:`ProblemError` before any solve for a scene with no contact set
    ("a load with no contact"), a bad load, more than :data:`limits.STATIC_MAX_CONTACTS` contacts for the
    condensed formulation, or a singular stiffness.  A failed LCP is not an exception:
    ``status`` comes from the LCP and no states are reported.  The formulations, tolerances
    and what each error means: docs/static-equilibrium.md.
    """
    t_start = time.perf_counter()
    timings = {}
    if not isinstance(scene, Scene):
        raise ProblemError(f"scene must be a Scene, got {type(scene).__name__} "
                           "(read a scene file with meicp.load_scene)")
    if not (tol > 0 and tol < 1):
        raise ProblemError(f"tol must be in (0, 1), got {tol!r}")
    has_base = scene.boundary.bottom == "contact"
    if not has_base and not scene.frictional_interfaces():
        what = "a load with no contact" if scene.load is not None else "no contact"
        raise ProblemError(f"static equilibrium: {what}: the scene has no contact set (boundary.bottom "
                           f"is {scene.boundary.bottom!r}, not \"contact\", and no interface is "
                           "frictional), so there are no contact states to solve for")
    if has_base and scene.contact is None:
        raise ProblemError("contact: required when boundary.bottom = \"contact\"")
    nsets = int(has_base) + len(scene.frictional_interfaces())
    nc_total = nsets * scene.nx
    if formulation not in FORMULATIONS:
        raise ProblemError(f"formulation must be 'auto', 'condensed', 'schur' or 'mixed', got {formulation!r}")
    auto = formulation == "auto"
    if auto:
        formulation = ("condensed" if nc_total <= limits.STATIC_AUTO_CONDENSED_LIMIT else
                       "schur" if nc_total <= limits.STATIC_SCHUR_MAX_CONTACTS else "mixed")
    if formulation == "schur" and nc_total > limits.STATIC_SCHUR_MAX_CONTACTS:
        raise ProblemError(f"static equilibrium: {nc_total} contacts exceed the Schur formulation's limit of "
                           f"{limits.STATIC_SCHUR_MAX_CONTACTS} (its dense compliance has (2·contacts)² "
                           "entries); use formulation=\"mixed\" (the sparse mixed formulation)")
    if formulation == "condensed" and nc_total > limits.STATIC_MAX_CONTACTS:
        raise ProblemError(f"static equilibrium: {nc_total} contacts exceed the condensed dense "
                           f"formulation's limit of {limits.STATIC_MAX_CONTACTS}; use formulation=\"mixed\" (the "
                           "sparse mixed formulation)")
    model = model if model is not None else LatticeModel(scene)
    if not isinstance(model, LatticeModel) or (model.scene is not scene and model.scene != scene):
        raise ProblemError("model must be the LatticeModel of this scene")
    data = static_data(scene, model, tol=tol, allow_floating=allow_floating, timings=timings, lines=lines,
                       stiffness=stiffness)
    if formulation == "schur" and data.rigid_modes:
        why = (f"{data.rigid_modes} rigid-body mode(s) not held by the Dirichlet boundary (K_ff singular): the "
               "Schur formulation needs K_ff invertible")
        if not auto:
            raise ProblemError(f"static equilibrium: formulation=\"schur\": {why}; use formulation=\"mixed\" "
                               "or \"condensed\"")
        formulation = "mixed"
        data.notes.append(f"formulation auto: mixed, not schur — {why}")
    if formulation == "schur":
        return solve_schur(data, comm=comm, timings=timings, t_start=t_start, petsc_options=petsc_options)
    if formulation == "mixed":
        return solve_mixed(data, comm=comm, petsc_options=petsc_options, timings=timings, t_start=t_start)
    result = solve_condensed(data, method=method, lcp_tol=lcp_tol, classify_limit=classify_limit,
                             lcp_options=lcp_options, timings=timings, t_start=t_start)
    if (auto and not result.success and result.status != "infeasible" and not data.rigid_modes
            and nc_total <= limits.STATIC_SCHUR_MAX_CONTACTS):
        # the dense LCP of the friction cone's facets defeats Lemke on some scenes that the Schur
        # formulation solves (extensive_interface.toml coarsened to 200 columns: 39,499 pivots,
        # then PETSc's VI diverged); its answer is certified on the sparse problem as well
        why = f"formulation auto: condensed failed ({result.message}), schur next"
        result = solve_schur(data, comm=comm, timings=timings, t_start=t_start, petsc_options=petsc_options)
        result.notes.insert(0, why)
    return result
