"""Solvers dispatched by name, as qpsolvers does: a problem family keeps a
:class:`SolverRegistry`, fills it with the methods that need nothing but NumPy/SciPy, and
``meicp.petsc`` adds the ones that need PETSc with :meth:`SolverRegistry.register`."""

from __future__ import annotations


class SolverRegistry(dict):
    """method name → solver function."""

    def register(self, name: str):
        """Decorator: the function becomes method ``name``."""
        def add(solver):
            self[name] = solver
            return solver
        return add

    def available(self) -> list[str]:
        """The method names a caller may pass, ``"auto"`` included."""
        return sorted(self) + ["auto"]
