"""Linear complementarity problems: solvers, matrix classes and game value (docs/design.md §2–§3)."""

from .problem import LCPProblem, LCPResult
from .solve import available_methods, solve_lcp

__all__ = ["LCPProblem", "LCPResult", "available_methods", "solve_lcp"]
