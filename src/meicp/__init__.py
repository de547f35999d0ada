"""meicp: stability of layered elastic lattices in frictional contact.

Mixed eigenvalue complementarity problems (MEiCP) and linear complementarity problems
(LCP) on distributed PETSc matrices with SLEPc eigensolvers.  See ``docs/design.md`` and
the README for the public API.
"""

from ._version import __version__
from .core.blas_kernel import choose_openblas_kernel

choose_openblas_kernel()  # before NumPy or PETSc load OpenBLAS: its kernels, not Prescott's

from .core.environment import require_python_stack  # noqa: E402

require_python_stack()  # NumPy, SciPy, mpi4py from Debian: a clear message if not

from .core.errors import ConvergenceError, MeicpError, ProblemError, SolverNotFound  # noqa: E402
from .core.results import Result  # noqa: E402
from .core import validation  # noqa: E402,F401
from .lcp import LCPResult, solve_lcp  # noqa: E402
from .lcp.classes import MatrixClasses, classify  # noqa: E402
from .eicp import EiCPResult, EiCPSolution, solve_eicp  # noqa: E402
# PETSc builds on lcp and eicp: these register the PETSc Mat as a matrix kind (core.matrix)
# and the PETSc-based methods by name; petsc4py itself loads at the first PETSc operation
from .petsc import eicp_active_set as _petsc_active_set, eicp_semismooth as _petsc_semismooth  # noqa: E402,F401
from .petsc import lcp as _petsc_lcp, mat as _petsc_mat  # noqa: E402,F401
from .lcp.game import GameValue, game_value  # noqa: E402
from .scene import Scene  # noqa: E402
from .io.scene import load_scene  # noqa: E402
from .lattice.model import LatticeModel  # noqa: E402
from .contact.result import FlutterMode, InstabilityResult, Mode  # noqa: E402
from .contact.critical_friction import CriticalFriction  # noqa: E402
from .api import analyze, assemble, assemble_damping, critical_friction, load_results  # noqa: E402
from .study import SweepResult, sweep  # noqa: E402

__all__ = ["__version__", "MeicpError", "ProblemError", "ConvergenceError", "SolverNotFound", "Result", "solve_lcp", "LCPResult",
           "classify", "MatrixClasses", "game_value", "GameValue",
           "load_scene", "Scene", "assemble", "assemble_damping", "LatticeModel",
           "solve_eicp", "EiCPResult", "EiCPSolution",
           "analyze", "critical_friction", "load_results", "InstabilityResult", "Mode", "FlutterMode",
           "CriticalFriction", "sweep", "SweepResult"]
