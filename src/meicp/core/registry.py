"""Solvers dispatched by name, as qpsolvers does: a problem family keeps a
:class:`SolverRegistry`, fills it with the methods that need nothing but NumPy/SciPy, and
``meicp.petsc`` adds the ones that need PETSc with :meth:`SolverRegistry.register`."""

from __future__ import annotations

import inspect


class SolverRegistry(dict):
    """method name → solver function ``solver(problem, *, keyword options)``."""

    def register(self, name: str):
        """Decorator: the function becomes method ``name``."""
        def add(solver):
            self[name] = solver
            return solver
        return add

    def available(self) -> list[str]:
        """The method names a caller may pass, ``"auto"`` included."""
        return sorted(self) + ["auto"]

    def keywords(self) -> set[str]:
        """Every keyword option some registered method names (its ``**_ignored`` aside): what
        the entry point may hand on, so that a name none of them knows is a misspelling."""
        kinds = (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)
        names = set()
        for solver in self.values():
            params = list(inspect.signature(solver).parameters.values())[1:]  # the problem first
            names.update(p.name for p in params if p.kind in kinds)
        return names
