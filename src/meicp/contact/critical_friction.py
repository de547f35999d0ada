"""The critical friction: the smallest μ at which a σ = 0 divergence mode exists,
``meicp.critical_friction``, as a certified bracket.  μ becomes the eigenvalue of an EiCP at
σ = 0, condensed onto the complementarity DOFs; up to ``CRITICAL_J`` pairs it is enumerated
(exact), beyond that the lower end is a proof on the condensed matrix and the upper end a
certified mode found by search (:mod:`.mu_bracket`).  The derivation, the singular cases
and the cost are in ``docs/critical-friction.md``."""

from __future__ import annotations

import dataclasses
import logging
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spl
from scipy.optimize import linprog

from ..core.comm import mpi_comm
from ..core.errors import ConvergenceError, ProblemError
from ..core.machine import available_memory
from ..eicp.enumeration import MAX_J
from ..eicp.problem import EiCPProblem, certify_pair
from ..eicp.solve import solve_eicp
from ..lattice.model import LatticeModel
from ..lattice.size import check_size
from ..petsc.assembly import assemble
from ..petsc.pencil import reduced_pencil
from ..scene import Scene
from .condensation import lift
from .condenser import Condenser, on_root
from .divergence import ENUMERATE_J, ENUMERATE_N, enumeration_is_small
from .maps import friction_part, grazing_cases, reduced_system
from .mu_bracket import extend_lower, lower_end, lower_from_mode, upper_candidates
from .problem import contact_states, pencil_of

log = logging.getLogger("meicp")

#: critical_friction enumerates the 2^|J| supports of its EiCP condensed onto the |J|
#: complementarity DOFs (order ≤ |J|) up to this many pairs: 3.3 s at |J| = 17, 15 s at
#: |J| = 19 (about ×2.2 per pair); beyond it brackets μ_c (:mod:`.mu_bracket`)
CRITICAL_J = 20
#: the μ-independent block −A′ (and its Schur complement) counts as singular beyond this
#: condition number: a motion of (near) zero stiffness, μ_c undefined
CRITICAL_COND = 1e12
#: a bracket is exact when upper − lower ≤ EXACT_WIDTH·upper (the lower end's certificate
#: is taken 10⁻⁶ below its computed value, so a tighter tolerance could never be met)
EXACT_WIDTH = 1e-5
#: certificate residual of a σ = 0 mode lifted to the whole reduced lattice
MODE_TOL = 1e-9
#: the search stops once a mode within this relative distance of the proved lower end is found
SEARCH_CLOSE = 1e-3
#: time allowed to the active-set starts of the search, and to extending the lower end by
#: segments (each; what is found or proved by then stands, and the evidence says it)
DENSE_SECONDS = 60.0
#: condensed candidates lifted (one solve each) before the upper end is given up
MAX_LIFTS = 20


class CriticalFriction(float):
    """The critical friction as a float — the upper end: a μ at which a certified σ = 0 mode
    exists (inf when none was found up to ``mu_max``) — carrying its certified bracket:
    ``lower`` (no σ = 0 mode for any μ < lower, proved), ``upper`` (= the value), ``exact``
    (μ_c is known: the ends meet within EXACT_WIDTH, or no mode exists up to ``mu_max``,
    proved) and ``evidence`` (how each end was obtained)."""

    lower: float
    upper: float
    exact: bool
    evidence: str

    def __new__(cls, upper: float, lower: float, exact: bool, evidence: str):
        obj = super().__new__(cls, upper)
        obj.upper, obj.lower, obj.exact, obj.evidence = float(upper), float(lower), bool(exact), str(evidence)
        return obj

    def __reduce__(self):
        return (CriticalFriction, (self.upper, self.lower, self.exact, self.evidence))

    @property
    def width(self) -> float:
        """(upper − lower)/upper: 0 when exact, inf without a mode."""
        if self.upper == self.lower:
            return 0.0
        return (self.upper - self.lower) / self.upper if np.isfinite(self.upper) else np.inf

    def describe(self) -> str:
        """One line: ``1.4605 (exact)``, ``in [1.08, 1.4605] (width …)`` or ``≥ 2.3 (no σ = 0 mode
        found …)``."""
        if self.exact and np.isfinite(self.upper):
            if self.lower == self.upper:
                return f"{self.upper:.10g} (exact)"
            return f"{self.upper:.10g} (exact within {self.width:.1e}: proved ≥ {self.lower:.10g})"
        if self.exact:
            return f"none up to μ = {self.lower:.6g} (proved)"
        if not np.isfinite(self.upper):
            return f"≥ {self.lower:.10g} (no σ = 0 mode found: upper end inf)"
        return f"in [{self.lower:.10g}, {self.upper:.10g}] (width {100 * self.width:.2g} %)"


def critical_friction(scene, *, mu_max: float = 1e3, bisection: bool | None = None, tol: float = 1e-8,
                      condense: bool = True, comm=None) -> CriticalFriction:
    """The smallest μ ≥ 0 at which a σ = 0 divergence mode exists for the scene's states
    (prescribed ones; with ``"solve"`` the states of the static equilibrium at the scene's μ),
    one μ for every frictional contact, as a :class:`CriticalFriction`: a float (the upper
    end, a μ with a certified mode; ``inf`` when none was found up to ``mu_max``) carrying
    ``lower``, ``upper``, ``exact`` and ``evidence``.

    scene: a :class:`~meicp.scene.Scene` (:func:`meicp.critical_friction` also reads a file).
    Solved as an EiCP in μ, condensed onto its complementarity DOFs
    (docs/critical-friction.md).  Up to ``CRITICAL_J`` (20) complementarity pairs per grazing
    case it is enumerated — all 2^|J| supports, exact — and the μ_c found is lifted back to
    the whole reduced lattice and certified there.  Beyond, a bracket: the lower end is a
    proof (diagonally scaled positive definiteness of the condensed S + μR on [0, lower]),
    the upper end a σ = 0 mode found by a search on the condensed problem, lifted and
    certified on the whole reduced lattice; condensations by MUMPS (collective on ``comm``;
    None: this process alone).  ``condense=False``: the former enumeration of the whole
    reduced pencil (order r per support, at most 16 pairs and 600 reduced DOFs; slow, kept
    for cross-checks).

    A motion of zero stiffness once the slip DOFs are eliminated — a floating body, or a
    block free to slide as a whole — makes the μ-independent block singular.  If such a
    motion is compatible with the slip directions (x_J ≥ 0) it is a σ = 0 motion at every μ
    and μ_c is undefined: ProblemError.  If it is not (e.g. a layer between two sliding
    contacts slipping in opposite directions), the enumeration meets singular pencils on
    some supports, so the bisection check is then required (ProblemError if it is too large
    for the default ``bisection=None``; a warning if ``bisection=False``); beyond CRITICAL_J
    such a lattice is refused (the bracket needs the lattice held once the contacts are).

    ``bisection``: cross-check of an enumerated μ_c on the σ-problem with the mass (a σ ≥ 0
    mode must exist just above μ_c and none just below, each decided by enumerating the
    whole reduced pencil; ConvergenceError if they disagree).  ``None`` (default): run it
    when that enumeration is within ``analyze``'s budget for enumerating (2^|J|·r³ ≤ 2e9
    flops, about ≤ 9 pairs on ~150 reduced DOFs), skip it beyond; ``True``: always;
    ``False``: never.  Never run for a bracket.
    """
    comm = mpi_comm(comm)
    scene, model, sets = _friction_states(scene)
    K, M = assemble(model)
    ends, evidence = [], []
    small, singular, enumerated = True, False, True
    for case in grazing_cases(sets):
        red = reduced_system(model, sets, case)
        # every case counts: the bisection check enumerates the σ-problem of each, with or without J
        small = small and enumeration_is_small(red.retained.size, red.J.size)
        if red.J.size == 0:
            continue
        A1, B1 = _friction_pencil(K, red, sets)
        if not condense:
            mu = _smallest_mu_full(A1, B1, red.J, mu_max)
            ends.append((mu, mu))
        elif red.J.size <= CRITICAL_J:
            mu, sing = _smallest_mu_condensed(A1, B1, red.J, mu_max)
            singular = singular or sing
            ends.append((mu, mu))
        else:
            enumerated = False
            lo, up, text = _bracket(comm, model, red, K, M, A1, B1, mu_max)
            ends.append((lo, up))
            evidence.append(text)
    lower = min((lo for lo, _ in ends), default=np.inf)
    upper = min((up for _, up in ends), default=np.inf)
    if enumerated:
        if singular and bisection is None and not small:
            raise ProblemError("critical_friction: a motion of zero stiffness is left once the slip DOFs are "
                               "eliminated (not compatible with the slip directions), so the enumeration meets "
                               "singular pencils and needs the bisection check, but the σ-problem is too large to "
                               "enumerate; pass bisection=True to run it anyway, or hold the body")
        note = ""
        if bisection or (bisection is None and small):
            note = _check_by_bisection(K, M, sets, model, upper, mu_max, tol)
        elif singular:
            log.warning("critical_friction: singular μ-independent block and bisection=False: μ_c = %.10g is "
                        "certified but its minimality is not cross-checked", upper)
        elif bisection is None:
            log.info("critical_friction: bisection check skipped (the σ-problem is too large to enumerate)")
        lower = mu_max if not np.isfinite(upper) else upper
        text = ("every support of the condensed EiCP in μ enumerated" +
                (f": no σ = 0 mode up to μ = {mu_max:g}" if not np.isfinite(upper) else
                 ", the smallest μ certified on the whole reduced lattice") + note)
        return CriticalFriction(upper, lower, True, text)
    exact = (upper - lower <= EXACT_WIDTH * upper) if np.isfinite(upper) else lower >= mu_max
    return CriticalFriction(upper, min(lower, upper), exact, "; ".join(evidence))


def _bracket(comm, model, red, K, M, A1, B1, mu_max: float) -> tuple[float, float, str]:
    """``(lower, upper, evidence)`` of one grazing case with |J| > CRITICAL_J (collective)."""
    with Condenser(comm, model, red, friction="unit", K=K, M=M) as cond:
        low, upper, mode_text = _ends(comm, cond, red, A1, B1, mu_max)
        error_text = cond.error_text()
    lower = min(low.mu, upper)
    text = f"|J| = {red.J.size}: lower end {low.evidence}; upper end {mode_text}; {error_text}"
    return lower, upper, text


def _ends(comm, cond, red, A1, B1, mu_max: float):
    """The proved lower end (a :class:`~.mu_bracket.LowerEnd`), the certified upper end and
    its sentence (collective; the dense work on rank 0)."""
    clock = time.perf_counter()

    def lap(name):
        nonlocal clock
        now = time.perf_counter()
        cond.seconds[name] = cond.seconds.get(name, 0.0) + now - clock
        clock = now

    if not cond.prepare(need_tau=False, keep_factor=True):
        raise ProblemError(_singular_message(cond.why))
    clock = time.perf_counter()  # prepare timed its own steps (held, probe)
    c0 = cond.at(0.0, xi=False)
    lap("condense")
    S, R, eS, eR = c0.S, c0.R, c0.error_S, c0.error_R

    def dense_ends():
        low = lower_end(S, R, eS, eR, mu_max=mu_max)
        lap("lower")
        candidates = upper_candidates(S, R, near=max(low.mu, low.mu_pd), mu_max=mu_max, d=low.d,
                                      good_enough=low.mu * (1 + SEARCH_CLOSE), seconds=DENSE_SECONDS)
        lap("search")
        return low, candidates

    low, candidates = on_root(comm, dense_ends)
    upper, mode_x = np.inf, None
    mode_text = f"no σ = 0 mode found up to μ = {mu_max:g} ({len(candidates)} condensed candidates)"
    problem = EiCPProblem.from_data(A1, B1, red.J)
    with cond.factor_FF(0.0) as solve:
        for mu, xJ in candidates[:MAX_LIFTS]:
            if mu >= upper:
                break
            sol = certify_pair(problem, mu, lift(cond.pieces, 0.0, xJ, solve))
            if sol.residual <= MODE_TOL:
                upper, mode_x = mu, xJ
                mode_text = (f"σ = 0 mode at μ = {mu:.10g} on {sol.support.size} of {red.J.size} contact DOFs, "
                             f"certified on the whole reduced lattice (residual {sol.residual:.1e})")
    lap("lift")
    if low.mu > upper * (1 + 1e-12):
        raise ConvergenceError(f"critical_friction: proof of no σ = 0 mode up to μ = {low.mu:.10g} above the "
                               f"certified mode at μ = {upper:.10g}: a rounding blunder, no bracket")

    def refine(low):
        if mode_x is not None and upper - low.mu > EXACT_WIDTH * upper:
            low = lower_from_mode(low, S, R, eS, eR, upper, mode_x)
        if not np.isfinite(upper) or upper - low.mu > EXACT_WIDTH * upper:
            low = extend_lower(low, S, R, eS, eR, mu_cap=min(upper, mu_max), seconds=DENSE_SECONDS)
        return low

    low = on_root(comm, lambda proved=low: refine(proved))
    lap("refine")
    log.info("critical_friction: |J| = %d, %s", red.J.size,
             ", ".join(f"{k} {v:.1f} s" for k, v in cond.seconds.items()))
    return low, upper, mode_text


def friction_pencils(scene):
    """The σ = 0 EiCPs in μ of :func:`critical_friction`, condensed onto the
    complementarity DOFs: one ``(Ac, Bc, J)`` per grazing case with a complementarity pair,
    for ``(μ Bc − Ac) x = y`` (dense, order |J|).  Raises ProblemError if the μ-independent
    block is singular.  Serial."""
    scene, model, sets = _friction_states(scene)
    K, _ = assemble(model)
    out = []
    for case in grazing_cases(sets):
        red = reduced_system(model, sets, case)
        if red.J.size == 0:
            continue
        Ac, Bc, Jc, _, null = _condense(*_friction_pencil(K, red, sets), red.J)
        if null.shape[1]:
            raise ProblemError(_singular_message(f"the condensed block −Ac (order {Ac.shape[0]}) is singular"))
        out.append((Ac, Bc, Jc))
    return out


def _friction_states(scene):
    """(scene, model, contact sets) with the states resolved (static equilibrium if asked)."""
    if not isinstance(scene, Scene):
        raise ProblemError(f"scene must be a Scene, got {type(scene).__name__} "
                           "(meicp.critical_friction also reads a scene file)")
    check_size(scene, memory=available_memory())  # serial SciPy: this process, no PETSc indices
    model = LatticeModel(scene)
    sets, static = contact_states(scene, model)
    if sets is None:
        raise ConvergenceError(f"static equilibrium failed: {static.message}", static)
    return scene, model, sets




def _friction_pencil(K, red, sets):
    """``A′ = −P̃₀ K Q̃``, ``B′ = P̃₁ K Q̃`` (sparse CSR) of the σ = 0 EiCP in μ."""
    P0 = (red.P - friction_part(red, sets)).tocsr()
    return reduced_pencil(K, K, P0, red.Q, red.retained, P_B=red.P_friction)


def _smallest_mu_full(A1, B1, J, mu_max):
    """The former path: enumerate the EiCP in μ on the whole reduced lattice."""
    if A1.shape[0] > ENUMERATE_N or J.size > ENUMERATE_J:
        raise ProblemError(f"critical_friction(condense=False) enumerates the whole reduced lattice: reduced size "
                           f"{A1.shape[0]} (limit {ENUMERATE_N}) / |J| = {J.size} (limit {ENUMERATE_J}) too large")
    r = solve_eicp(A1.toarray(), B1.toarray(), J=J, method="enumerate", lam_min=0.0, tol=1e-9,
                   max_j=MAX_J)  # sized by the check above, not by the by-name work budget
    mus = [s.lam for s in r.solutions if 0.0 <= s.lam <= mu_max]
    return min(mus) if mus else np.inf


def _condense(A1, B1, J):
    """Eliminate the rows/columns E where w = 0 and B′ = 0 (no μ in the equation):
    ``x_E = −A′_EE⁻¹ A′_EC x_C``.  Returns ``(Ac, Bc, Jc, lift, null)``: Jc the positions of
    J in C, ``lift(x_C)`` the whole reduced x, ``null`` an orthonormal basis (columns) of the
    null space of −Ac (usually empty).  ProblemError if ``−A′_EE`` is singular: then a
    motion with x_C = 0 costs no energy, a σ = 0 motion at every μ."""
    r = A1.shape[0]
    in_j = np.zeros(r, dtype=bool)
    in_j[J] = True
    with_mu = np.diff(B1.indptr) > 0           # rows of B′ with a stored entry
    keep = in_j | with_mu                       # C: J and any free row that carries μ
    C, E = np.flatnonzero(keep), np.flatnonzero(~keep)
    Jc = np.flatnonzero(in_j[C])
    A_CC, B_CC = A1[C][:, C].toarray(), B1[C][:, C].toarray()
    if E.size:
        A_EE = A1[E][:, E].tocsc()
        singular = f"the μ-independent block −A′_EE ({E.size} DOFs) is singular"
        try:
            lu = spl.splu(A_EE)
        except RuntimeError as exc:  # "Factor is exactly singular"
            raise ProblemError(_singular_message(singular)) from exc
        inv = spl.LinearOperator(A_EE.shape, matvec=lu.solve, rmatvec=lambda v: lu.solve(v, trans="T"),
                                 dtype=float)
        cond = spl.norm(A_EE, 1) * spl.onenormest(inv)
        if not np.isfinite(cond) or cond > CRITICAL_COND:
            raise ProblemError(_singular_message(f"{singular} (condition ≈ {cond:.1e})"))
        X_EC = lu.solve(A1[E][:, C].toarray())  # A′_EE⁻¹ A′_EC
        Ac = A_CC - A1[C][:, E] @ X_EC
        Bc = B_CC - B1[C][:, E] @ X_EC
    else:
        X_EC = np.zeros((0, C.size))
        Ac, Bc = A_CC, B_CC
    Ac, Bc = np.asarray(Ac), np.asarray(Bc)
    # −Ac is the Schur complement of −A′ = Q̃ᵀKQ̃: symmetric positive semidefinite, definite
    # unless a motion of zero stiffness is left (e.g. a layer sliding as a whole)
    ev, V = np.linalg.eigh(-0.5 * (Ac + Ac.T))
    null = V[:, ev <= max(ev[-1], 0.0) / CRITICAL_COND]

    def lift(xc):
        x = np.zeros(r)
        x[C] = xc
        x[E] = -X_EC @ xc
        return x

    return Ac, Bc, Jc, lift, null


def _singular_message(what: str) -> str:
    return (f"critical_friction: {what}: a motion of zero stiffness exists with the sliding contacts "
            "held (a floating body, or a block free to slide as a whole), a σ = 0 motion at every μ; "
            "μ_c is undefined — hold the body (boundary or sticking contacts)")


def _sign_feasible(N: np.ndarray) -> bool:
    """Whether some nonzero x = N c has x ≥ 0 (LP: N c ≥ 0, Σ(N c) = 1), or x = 0 on these
    rows for some c ≠ 0 (N rank deficient)."""
    if np.linalg.matrix_rank(N) < N.shape[1]:
        return True
    res = linprog(np.zeros(N.shape[1]), A_ub=-N, b_ub=np.zeros(N.shape[0]), A_eq=N.sum(axis=0)[None, :],
                  b_eq=[1.0], bounds=[(None, None)] * N.shape[1], method="highs")
    return res.status == 0


def _smallest_mu_condensed(A1, B1, J, mu_max):
    """Smallest μ in [0, mu_max] of ``(μB′ − A′)x = y`` by enumerating the condensed EiCP
    in ν = 1/μ, certified on the whole reduced pencil.  Returns (μ, singular): ``singular``
    when −Ac has a null space that is not sign-feasible (the enumeration met singular
    pencils; the caller must cross-check)."""
    Ac, Bc, Jc, lift, null = _condense(A1, B1, J)
    if null.shape[1] and _sign_feasible(null[Jc]):
        raise ProblemError(_singular_message(f"the condensed block −Ac (order {Ac.shape[0]}) is singular and its "
                                             "null space holds a motion with x_J ≥ 0"))
    if Ac.shape[0] > Jc.size:
        log.info("critical_friction: %d free rows carry μ and stay in the condensed EiCP", Ac.shape[0] - Jc.size)
    # μ > 0 ⇔ ν = 1/μ > 0.  μ = 0 is never a solution: −Ac is positive semidefinite and
    # x_J ≥ 0 with xᵀ(−Ac)x = xᵀy = 0 only for x in its null space, excluded just above
    # max_j: the caller sized this enumeration (enumeration_is_small), not the by-name budget
    r = solve_eicp(-Bc, -Ac, J=Jc, method="enumerate", lam_min=1.0 / mu_max if mu_max > 0 else np.inf,
                   tol=1e-9, max_j=MAX_J)
    nus = [s for s in r.solutions if s.lam > 0 and 1.0 / s.lam <= mu_max]
    if not nus:
        return np.inf, bool(null.shape[1])
    sol = max(nus, key=lambda s: s.lam)
    mu = 1.0 / sol.lam
    full = certify_pair(EiCPProblem.from_data(A1, B1, J), mu, lift(sol.x))
    if full.residual > 1e-9:
        raise ConvergenceError(f"critical_friction: μ_c = {mu:.10g} of the condensed EiCP fails the certificate on "
                               f"the whole reduced lattice (residual {full.residual:.1e})", r)
    return mu, bool(null.shape[1])


#: a σ ≥ 0 mode whose σ is above this multiple of max|A|/max|B| where modes start is born at
#: σ > 0 (a pair of real σ out of a complex pair: flutter turning into divergence), not
#: through σ = 0 — no contradiction of μ_c, which is about σ = 0
BORN_ABOVE_ZERO = 1e-6


def _largest_sigma(K, M, sets, model, mu) -> float | None:
    """The largest σ ≥ 0 of a mode with every contact's friction set to μ (enumeration; K, M
    the lattice's, which μ does not change), relative to max|A|/max|B|; None without a mode."""
    scaled = [dataclasses.replace(cs, friction=mu) for cs in sets]
    best = None
    for case in grazing_cases(scaled):
        pen = pencil_of(K, M, model, scaled, case)
        if pen.A is None:
            continue  # every DOF held: no mode (as in analyze)
        A, B = pen.A.toarray(), pen.B.toarray()
        r = solve_eicp(A, B, J=pen.J, method="enumerate", lam_min=0.0, max_j=MAX_J)  # internal: no budget
        if r.solutions:
            sigma = max(sol.lam for sol in r.solutions) / (np.abs(A).max() / max(np.abs(B).max(), 1e-300))
            best = sigma if best is None else max(best, sigma)
    return best


def _check_by_bisection(K, M, sets, model, mu_c, mu_max, tol) -> str:
    """Existence of a σ ≥ 0 mode against μ_c: one just above it, and where modes exist below
    it (or, without μ_c, at ``mu_max``) they must start at σ > 0 — a pair born there, not a
    σ = 0 crossing that μ as an eigenvalue missed.  Returns a note for the evidence ("" when
    modes start at μ_c); ConvergenceError on a contradiction."""
    def sigma_at(mu):
        return _largest_sigma(K, M, sets, model, mu)

    top = mu_c * (1 - 1e-6) - 1e-12 if np.isfinite(mu_c) else mu_max
    if np.isfinite(mu_c) and sigma_at(mu_c * (1 + 1e-6) + 1e-12) is None:
        raise ConvergenceError(f"no σ ≥ 0 mode just above μ_c = {mu_c:.8g}: μ as an eigenvalue and "
                               "existence disagree")
    sigma = None if top < 0 else sigma_at(top)
    if sigma is None:
        return ""
    start, at_zero = 0.0, sigma_at(0.0)
    if at_zero is not None:
        sigma = at_zero
    else:  # bisect down to where modes start, keeping the largest σ there
        lo, hi = 0.0, top
        while hi - lo > tol * max(1.0, hi):
            mid = 0.5 * (lo + hi)
            found = sigma_at(mid)
            lo, hi, sigma = (lo, mid, found) if found is not None else (mid, hi, sigma)
        start = hi
    where = f"below μ_c = {mu_c:.8g}" if np.isfinite(mu_c) else f"with no σ = 0 mode up to μ = {mu_max:g}"
    if sigma <= BORN_ABOVE_ZERO:
        raise ConvergenceError(f"σ ≥ 0 modes start at μ ≈ {start:.8g} with σ ≈ 0, {where}: a σ = 0 crossing that "
                               "μ as an eigenvalue missed")
    if start == 0.0:  # without friction the pencil is symmetric: unstable already, no crossing involved
        return (f"; divergence modes exist {where} already at μ = 0 (σ = {sigma:.3g}·max|A|/max|B|; enumeration "
                "of the σ-problem)")
    return (f"; divergence modes exist {where}, from μ ≈ {start:.8g}, born at σ = {sigma:.3g}·max|A|/max|B| > 0 "
            "(a pair of real σ, not through σ = 0; enumeration of the σ-problem)")

