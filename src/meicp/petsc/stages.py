"""PETSc log stages, so that ``-log_view`` splits a run by phase instead of putting
everything in "Main Stage"::

    with stage("assemble"):
        K, M = assemble(model, comm)

The phases of ``meicp solve`` are ``static``, ``assemble``, ``reduce``, ``eigen``,
``flutter``, ``critical_friction`` and ``write`` (:data:`PHASES`).  A stage is registered once per name
and pushed on every rank that enters the block (PETSc's event log expects the ranks to
agree); pushing costs nothing measurable when no log is requested.
"""

from __future__ import annotations

from contextlib import contextmanager

from . import import_petsc

#: the stage names meicp uses, in the order a run meets them
PHASES = ("static", "assemble", "reduce", "eigen", "flutter", "critical_friction", "write")

_STAGES: dict = {}


@contextmanager
def stage(name: str):
    """Run the block in the PETSc log stage ``name`` (one of :data:`PHASES`)."""
    if name not in PHASES:
        raise ValueError(f"unknown log stage {name!r} (add it to PHASES)")
    PETSc = import_petsc()
    log_stage = _STAGES.get(name)
    if log_stage is None:
        log_stage = _STAGES[name] = PETSc.Log.Stage(name)
    log_stage.push()
    try:
        yield
    finally:
        log_stage.pop()
