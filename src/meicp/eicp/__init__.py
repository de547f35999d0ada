"""Eigenvalue complementarity problems, EiCP and mixed MEiCP (docs/design.md §4)."""

from .problem import EiCPProblem, EiCPResult, EiCPSolution
from .solve import available_methods, solve_eicp

__all__ = ["EiCPProblem", "EiCPResult", "EiCPSolution", "available_methods", "solve_eicp"]
