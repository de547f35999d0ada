"""Budgets and size limits: where a method changes with the problem's size, and what work is
refused before it starts.  One place, so that a reader sees every threshold together and a
test or a benchmark changes one attribute (``monkeypatch.setattr(limits, NAME, value)``);
the code reads them as ``limits.NAME`` at the call, never as a copy taken at import.

Each value was chosen on this project's 2-core machine; where a measurement backs it, the
figures are in the comment above it or in docs/benchmarks-notes.md (a section named after the
constant) and docs/benchmarks.md.  The
limits are speed budgets: none of them can turn a wrong answer into a proof, because every
path certifies what it returns.
"""

# -- enumeration of supports (2^|J| dense eigen-solves of order r) -------------------------

#: ``analyze``'s ``auto`` enumerates a contact state's MEiCP when 2^|J|·r³ is at most
#: ENUMERATE_FLOPS with r ≤ ENUMERATE_N and |J| ≤ ENUMERATE_J (seconds at most); ENUMERATE_J
#: also bounds ``method="enumerate"`` asked for by name unless ``max_j`` raises it
ENUMERATE_FLOPS = 2e9
ENUMERATE_N = 600
ENUMERATE_J = 16
#: the largest 2^|J|·r³ an enumeration by name may start: about an hour at SECONDS_PER_FLOP
#: (16 pairs up to r ≈ 310, 20 pairs up to r ≈ 125, 24 pairs up to r ≈ 50)
ENUMERATE_MAX_FLOPS = 2e12
#: seconds per unit of 2^|J|·r³ of a whole enumeration (one core, one BLAS thread): the
#: pessimistic middle of the measured range, so that a refused enumeration would really have
#: taken too long
SECONDS_PER_FLOP = 2e-9
#: the largest ``max_j`` a caller may pass: 2^26 supports already take hours (more is a hang)
MAX_ENUMERATED = 26
#: ``solve_eicp``'s enumeration default ``max_j`` (internal callers size their problems first)
EICP_MAX_J = 24
#: ``solve_eicp(method="auto")`` enumerates when |J| and n are at most these
AUTO_ENUMERATE_J = 16
AUTO_ENUMERATE_N = 400
#: ``solve_eicp(method="auto")`` tries the Rayleigh-quotient method up to this n: SPG needs
#: only products, but 8 starts of up to 5000 iterations, and its SPD check of a non-diagonal B
#: is a dense Cholesky; past it the SLEPc active-set search leads
AUTO_RAYLEIGH_N = 5000
#: above this reduced size the Rayleigh method's polishing eigen-solve is sparse
DENSE_POLISH_LIMIT = 2000
#: grazing contacts whose 3 tangential cases each are enumerated (3^6 = 729 MEiCPs)
MAX_GRAZING = 6

# -- critical friction ------------------------------------------------------------------------

#: ``critical_friction`` enumerates its condensed EiCP (order ≤ |J|) up to this many pairs;
#: the time grows about ×2.2 per pair; beyond it μ_c is bracketed
CRITICAL_J = 20
#: seconds allowed to the bracket's active-set starts, and to each extension of its lower end
#: (what is found or proved by then stands, and the evidence says so)
CRITICAL_DENSE_SECONDS = 60.0
#: largest support the μ-bracket's active set solves densely
MU_ACTIVE_SET_MAX = 300

# -- condensation onto the contact DOFs -------------------------------------------------------

#: the condenser's ``method="auto"`` condenses by solves (a rigorous error bound) while
#: |F|·|J| stays below this, else by Schur complements (a measured error)
SOLVES_LIMIT = 2e7

# -- flutter of steady sliding ----------------------------------------------------------------

#: dense QZ up to this many retained DOFs: its time grows as n³, to minutes past this
FLUTTER_DENSE_MAX = 2500
#: at and above this many retained DOFs the search takes one target with a short basis and a
#: block-low-rank factor: a few eigen-solves of the pencil
FLUTTER_SEARCH_LARGE = 50_000
#: from this many retained DOFs the search starts off the cluster of slow vibrations
FLUTTER_OFF_CLUSTER_FROM = 200_000
#: memory the search adds per retained DOF, all ranks together (the factor of the 2n real
#: form, rounded up); the search is skipped when that much is not available
FLUTTER_SEARCH_BYTES_PER_DOF = 10_000

#: the flutter onset's bracket (critical_friction): at most this many dense eigen-decompositions
#: (the interval cover and the verdicts together) and this many seconds; past FLUTTER_DENSE_MAX
#: at most FLUTTER_ONSET_SEARCHES searches (each a complex factorisation of the pencil)
FLUTTER_ONSET_SOLVES = 4000
FLUTTER_ONSET_SECONDS = 60.0
FLUTTER_ONSET_SEARCHES = 6

# -- static frictional equilibrium ------------------------------------------------------------

#: most contacts (all lines together) for the condensed dense formulation
STATIC_MAX_CONTACTS = 2000
#: ``formulation="auto"`` uses the condensed (dense) path up to this many contacts, else mixed
STATIC_AUTO_CONDENSED_LIMIT = 200
#: most contacts for the Schur formulation (its dense compliance G has (2·contacts)² entries)
STATIC_SCHUR_MAX_CONTACTS = 4000
#: largest LCP for which the condensed path falls back to dense Lemke when its choice failed
STATIC_LEMKE_LIMIT = 4 * STATIC_MAX_CONTACTS

# -- studies ------------------------------------------------------------------------------------

#: ``meicp.sweep`` gives each rank values of its own (each analysed on one process) below this
#: many DOFs, and analyses every value on all ranks together from it on.  Split, P ranks do P
#: values at a time, where one analysis on 2 ranks is 1.6× faster than on 1 (10⁶ DOFs, README);
#: the price is memory, each rank holding a whole lattice: 4.1 GB at 10⁶ DOFs on one rank,
#: so about 0.8 GB per rank here (time and memory ∝ n^1.1, n^1.05, docs/benchmarks.md)
SWEEP_SPLIT_DOFS = 200_000
