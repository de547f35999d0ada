"""The result of :func:`~meicp.lcp.classes.classify`: :class:`MatrixClasses`, the class names
and labels of its report, the bookkeeping that sets each class once (:class:`_State`), and the
sentences on what the classes guarantee for LCP(q, M) (seed 002 §7).

Plain data and text: the tests that decide the classes are in :mod:`meicp.lcp.classes_exact`
and :mod:`meicp.lcp.classes_sufficient`, the entry point in :mod:`meicp.lcp.classes`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .game import GameValue

#: the class attributes, in report order
CLASS_NAMES = (
    "symmetric", "spd", "psd", "positive_definite", "p_matrix", "p0", "z_matrix", "m_matrix",
    "q_matrix", "r0", "copositive", "strictly_copositive", "semimonotone",
)

#: short human names for the report
LABELS = {
    "symmetric": "symmetric",
    "spd": "SPD",
    "psd": "PSD (xᵀMx ≥ 0)",
    "positive_definite": "PD (xᵀMx > 0)",
    "p_matrix": "P",
    "p0": "P0",
    "z_matrix": "Z",
    "m_matrix": "M-matrix",
    "q_matrix": "Q",
    "r0": "R0",
    "copositive": "copositive",
    "strictly_copositive": "strictly copositive",
    "semimonotone": "semimonotone (E0)",
}


@dataclass
class MatrixClasses:
    """Class membership of a square matrix M: each attribute is True, False or None.

    symmetric: M = Mᵀ (to ``tol``).
    spd: symmetric and positive definite.
    psd: xᵀMx ≥ 0 for all x — M need *not* be symmetric (the monotone LCP); the
        symmetric part ``(M + Mᵀ)/2`` is positive semidefinite.
    positive_definite: xᵀMx > 0 for all x ≠ 0, M not necessarily symmetric.
    p_matrix / p0: every principal minor > 0 / ≥ 0.
    z_matrix: off-diagonal entries ≤ 0.   m_matrix: Z and P (nonsingular M-matrix).
    q_matrix: LCP(q, M) has a solution for every q.
    r0: LCP(0, M) has only the solution x = 0.
    copositive / strictly_copositive: xᵀMx ≥ 0 / > 0 for all x ≥ 0, x ≠ 0.
    semimonotone: E0 — every x ≥ 0, x ≠ 0 has some i with x_i > 0 and (Mx)_i ≥ 0.

    tests: for each class, the test (or implication) that decided it, or why not.
    witnesses: vectors that refute a class (JSON-friendly lists), e.g. ``r0`` → a
        nonzero solution of LCP(0, M); ``copositive`` → x ≥ 0 with xᵀMx < 0.
    game_value: :class:`~meicp.lcp.game.GameValue` (None if n > ``game_limit``).
    guarantees: sentences on what the classes guarantee for LCP(q, M), and what they
        do not (seed 002 §7).
    """

    n: int
    symmetric: bool | None = None
    spd: bool | None = None
    psd: bool | None = None
    positive_definite: bool | None = None
    p_matrix: bool | None = None
    p0: bool | None = None
    z_matrix: bool | None = None
    m_matrix: bool | None = None
    q_matrix: bool | None = None
    r0: bool | None = None
    copositive: bool | None = None
    strictly_copositive: bool | None = None
    semimonotone: bool | None = None
    tests: dict = field(default_factory=dict)
    witnesses: dict = field(default_factory=dict)
    game_value: GameValue | None = None
    guarantees: list = field(default_factory=list)
    exact_limit: int = 12
    tol: float = 1e-10
    scale: float = 1.0
    notes: list = field(default_factory=list)
    timings: dict = field(default_factory=dict)

    def __repr__(self) -> str:
        held = {True: [], False: [], None: []}
        for name, value in self.classes().items():
            held[value].append(name)
        parts = [f"{label}: {', '.join(held[value])}" for label, value in (("yes", True), ("no", False),
                                                                          ("undecided", None)) if held[value]]
        if self.game_value is not None:
            parts.append(f"game value {self.game_value.value:.4g}")
        return f"MatrixClasses(n={self.n}; {'; '.join(parts)})"

    def classes(self) -> dict:
        """``{name: True/False/None}`` for every class."""
        return {name: getattr(self, name) for name in CLASS_NAMES}

    def report(self) -> str:
        """A readable multi-line report: one line per class, the game value, the guarantees."""
        exact = "exact tests" if self.n <= self.exact_limit else "sufficient tests only"
        lines = [f"Matrix classes of a {self.n}×{self.n} matrix "
                 f"({exact}; exact_limit = {self.exact_limit}, tol = {self.tol:g})"]
        word = {True: "yes", False: "no", None: "undecided"}
        for name in CLASS_NAMES:
            lines.append(f"  {LABELS[name]:<22} {word[getattr(self, name)]:<10} "
                         f"{self.tests.get(name, '')}")
        gv = self.game_value
        if gv is None:
            lines.append("  game value v(M)       not computed (n above game_limit)")
        elif gv.success:
            lines.append(f"  game value v(M)        {gv.value:.6g}  (duality gap {gv.residual:.1e}·max|M|)")
            if self.n <= 8:
                lines.append(f"    x* (min player) = {_fmt_vec(gv.x)}, y* (max player) = {_fmt_vec(gv.y)}")
        else:
            lines.append(f"  game value v(M)        not certified: {gv.message}")
        lines.append("Guarantees for LCP(q, M) (seed 002 §7):")
        lines.extend(f"  - {g}" for g in self.guarantees)
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """A JSON-serialisable dictionary (classes, tests, witnesses, game value, guarantees)."""
        return {
            "n": self.n,
            "classes": self.classes(),
            "tests": dict(self.tests),
            "witnesses": {k: list(v) for k, v in self.witnesses.items()},
            "game_value": None if self.game_value is None else self.game_value.to_dict(),
            "guarantees": list(self.guarantees),
            "exact_limit": self.exact_limit,
            "tol": self.tol,
            "scale": self.scale,
            "notes": list(self.notes),
            "timings": dict(self.timings),
        }

    def __str__(self) -> str:
        return self.report()


def _fmt_vec(v) -> str:
    return "(" + ", ".join(f"{t:.4g}" for t in v) + ")"


def _fmt_set(idx) -> str:
    return "{" + ",".join(str(int(i)) for i in idx) + "}"


class _State:
    """The classification being built: a class is set once, by the first test that decides it."""

    def __init__(self, out: MatrixClasses):
        self.out = out
        self.notes: list[str] = []

    def get(self, name):
        return getattr(self.out, name)

    def decide(self, name: str, value: bool, test: str, witness=None) -> bool:
        current = getattr(self.out, name)
        if current is None:
            setattr(self.out, name, bool(value))
            self.out.tests[name] = test
            if witness is not None:
                self.out.witnesses[name] = [float(t) for t in np.asarray(witness).ravel()]
            return True
        if current != bool(value):  # only at numerical class boundaries
            self.notes.append(f"{name}: kept {current} ({self.out.tests[name]}); "
                              f"a second test said {bool(value)} ({test})")
        return False


# ----------------------------------------------------------------------------------------
# Guarantees (seed 002 §7)
# ----------------------------------------------------------------------------------------

def _guarantees(c: MatrixClasses) -> list[str]:
    g = []
    gv = c.game_value
    tol = c.tol
    if c.q_matrix:
        g.append(f"Existence: LCP(q, M) has a solution for every load q (Q-matrix: {c.tests['q_matrix']}).")
    elif c.q_matrix is False:
        g.append(f"NOT guaranteed: existence fails for some load q — M is not a Q-matrix "
                 f"({c.tests['q_matrix']}).")
    else:
        g.append("NOT guaranteed: existence for every q (Q undecided); check each solve's certificate.")
    if c.p_matrix:
        g.append("Uniqueness: for every q the solution is unique (P-matrix), and x(q) depends "
                 "Lipschitz-continuously on q.")
    elif c.p_matrix is False:
        g.append("NOT guaranteed: uniqueness — M is not P, and P is necessary for a unique solution "
                 "for every q, so some q has no solution or several.")
    else:
        g.append("NOT guaranteed: uniqueness for every q (P undecided).")
    if c.r0:
        g.append("No spurious unloaded equilibria: with q = 0 the only solution is x = 0 (R0).")
    elif c.r0 is False:
        g.append("Spurious unloaded equilibria exist: LCP(0, M) has a nonzero solution (not R0), "
                 "and every positive multiple of it is one too.")
    else:
        g.append("NOT guaranteed: absence of nonzero unloaded equilibria (R0 undecided).")
    if gv is not None and gv.success:
        if gv.lower > tol * c.scale:
            g.append(f"Game value v(M) = {gv.value:.6g} > 0: y* gives My* > 0, so LCP(q, M) is "
                     "feasible for every q and the energetic margin of seed 002 §4 holds.")
        elif gv.upper <= tol * c.scale:
            g.append(f"Game value v(M) = {gv.value:.6g} ≤ 0 (to tolerance): no y ≥ 0 has My > 0, so "
                     "for every q < 0 (e.g. q = −1) LCP(q, M) has no feasible point; no energetic margin.")
        else:
            g.append(f"Game value v(M) = {gv.value:.6g} is zero to tolerance: no certified "
                     "energetic margin (seed 002 (19)).")
    elif gv is not None:
        g.append("Game value not certified: the energetic margin v(M) > 0 is not established.")
    else:
        g.append("Game value not computed (n above game_limit): the energetic margin is not established.")
    if c.spd:
        g.append("SPD: LCP(q, M) is the optimality condition of the strictly convex energy "
                 "min ½xᵀMx + qᵀx over x ≥ 0, whose minimiser is the unique solution.")
    elif c.psd and not c.p_matrix:
        g.append("PSD (monotone LCP): the solution set is convex and LCP(q, M) is solvable "
                 "whenever it is feasible (Lemke's method finds a solution or proves infeasibility).")
    if c.m_matrix:
        g.append("M-matrix: the solution is the least element of the feasible set "
                 "{x ≥ 0 : Mx + q ≥ 0}, and contact couplings are purely compressive (Z).")
    if c.semimonotone:
        g.append("E0: for every q > 0 (all contacts pushed open) the only solution is x = 0.")
    elif c.semimonotone is False:
        g.append("Not E0: some q > 0 (all contacts pushed open) still has a nonzero solution.")
    if c.strictly_copositive:
        g.append("Strictly copositive: xᵀMx > 0 for every nonzero x ≥ 0 — this alone implies "
                 "Q, R0 and v(M) > 0 (seed 002 (20)).")
    return g

