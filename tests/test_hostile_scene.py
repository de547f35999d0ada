"""Hostile scenes and ``analyze`` arguments (issue 11, part 2): every case has one exact
outcome — a ProblemError naming the key or the file, or an honest verdict (unstable with a
certified mode, undecided with the reason) — never a false "stable", never a traceback or an
unbounded read.  docs/hostile-input.md lists the cases."""

from __future__ import annotations

import dataclasses
import os
import re
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

import meicp
from meicp.contact import instability
from meicp.contact.divergence import enumeration
from meicp.contact.rayleigh import pencil_is_negative
from meicp.core.errors import ProblemError
from meicp.eicp.problem import EiCPResult
from meicp.io import scene as scene_io
from meicp.io.scene import load_scene, loads_scene
from meicp.lattice.size import check_size, estimate_size
from meicp.petsc.comm import index_max
from meicp.petsc.mat import mat_from_scipy

from .conftest import ROOT, meicp_cmd, run

SCENES = ROOT / "data" / "scenes"
TWO_LAYERS = (SCENES / "two_layers.toml").read_text()
#: two_layers.toml's one divergence mode
SIGMA = 0.3290549424


def _with(text: str = TWO_LAYERS, **changes) -> str:
    """two_layers.toml with ``old=new`` line edits (keyword: a label, value: (old, new))."""
    for old, new in changes.values():
        assert old in text, old
        text = text.replace(old, new)
    return text


def _layer(layer: str, key: str, value: str, text: str = TWO_LAYERS) -> str:
    blocks = text.split("[[layers]]")
    blocks = [re.sub(rf"{key} = [0-9.e+-]+", f"{key} = {value}", b) if f'name = "{layer}"' in b else b
              for b in blocks]
    return "[[layers]]".join(blocks)


def _solver(line: str) -> str:
    return _with(s=('method = "auto"', f'method = "auto"\n{line}'))


def _write(path: Path, data) -> Path:
    path.write_bytes(data if isinstance(data, bytes) else data.encode())
    return path


# ---------------------------------------------------------------------------------------
# Scene files: read within bounds, a ProblemError naming the file and the problem
# ---------------------------------------------------------------------------------------

def _fifo(d: Path) -> Path:
    os.mkfifo(d / "pipe.toml")
    return d / "pipe.toml"


def _symlink(d: Path) -> Path:
    (d / "zero.toml").symlink_to("/dev/zero")
    return d / "zero.toml"


def _directory(d: Path) -> Path:
    (d / "dir.toml").mkdir()
    return d / "dir.toml"


#: (id, build(tmp_path) -> path, pattern of the ProblemError)
FILE_ERRORS = [
    ("dev-zero", lambda d: Path("/dev/zero"), r"/dev/zero: not a regular file .* cannot be read as a scene"),
    ("symlink-to-dev-zero", _symlink, r"zero\.toml: not a regular file"),
    ("fifo", _fifo, r"pipe\.toml: not a regular file"),
    ("directory", _directory, r"dir\.toml: not a regular file"),
    ("missing", lambda d: d / "missing.toml", r"cannot read scene file .*missing\.toml.*: no such file"),
    ("invalid-utf8", lambda d: _write(d / "a.toml", TWO_LAYERS.encode().replace(b"two layers", b"two \xff layers")),
     r"a\.toml: not UTF-8 text \(byte 0xff at offset \d+ is invalid\)"),
    ("nul-bytes", lambda d: _write(d / "a.toml", TWO_LAYERS.encode() + b"\0"), r"a\.toml: binary data \(a NUL byte"),
    ("nested-arrays", lambda d: _write(d / "a.toml", "title = " + "[" * 5000 + "]" * 5000),
     r"a\.toml: line 1: arrays or inline tables nested deeper than 32 levels"),
    ("nested-inline-tables", lambda d: _write(d / "a.toml", "x = " + "{a = " * 1000 + "1" + "}" * 1000),
     r"nested deeper than 32 levels"),
    ("dotted-key", lambda d: _write(d / "a.toml", "a" + ".a" * 30000 + " = 1\n"),
     r"a\.toml: line 1: a dotted key deeper than 32 levels"),
    ("not-toml", lambda d: _write(d / "a.toml", "[lattice\nnx = 5\n"), r"a\.toml: not valid TOML"),
]


@pytest.mark.parametrize("build, pattern", [c[1:] for c in FILE_ERRORS], ids=[c[0] for c in FILE_ERRORS])
def test_scene_files_refuse_hostile_content(tmp_path, build, pattern):
    with pytest.raises(ProblemError, match=pattern):
        load_scene(build(tmp_path))


def test_scene_file_size_is_bounded_before_reading(tmp_path, monkeypatch):
    """A scene larger than MAX_SCENE_BYTES (lowered here) is refused having read at most
    one byte past the limit (``/dev/zero`` as a scene used to be read for ever)."""
    path = _write(tmp_path / "a.toml", TWO_LAYERS)
    monkeypatch.setattr(scene_io, "MAX_SCENE_BYTES", len(TWO_LAYERS) - 1)
    with pytest.raises(ProblemError, match=r"a\.toml: larger than \d+ bytes, the limit for a text scene file "
                                           r"\(meicp\.io\.scene\.MAX_SCENE_BYTES\)"):
        load_scene(path)


def test_a_byte_order_mark_is_accepted(tmp_path):
    """A UTF-8 BOM (Windows editors write one) used to fail with "Invalid statement"."""
    plain = load_scene(_write(tmp_path / "plain.toml", TWO_LAYERS))
    bom = load_scene(_write(tmp_path / "bom.toml", b"\xef\xbb\xbf" + TWO_LAYERS.encode()))
    assert dataclasses.replace(bom, source=None) == dataclasses.replace(plain, source=None)
    assert loads_scene("\ufeff" + TWO_LAYERS).lattice == plain.lattice


#: (id, scene text, pattern): values in range alone but not together, and [solver] values
VALUE_ERRORS = [
    ("spacing-1e300", _with(a=("spacing = 1.0", "spacing = 1e300")),
     r"lattice\.spacing = 1e\+300: the node mass per unit density a³ = inf is beyond double precision"),
    ("spacing-1e-120", _with(a=("spacing = 1.0", "spacing = 1e-120")), r"lattice\.spacing = 1e-120: .* a³ = 0"),
    ("shear-overflow", _with(a=("shear = 0.0 ", "shear = 1e308 "), b=("spacing = 1.0", "spacing = 10.0")),
     r"lattice\.spacing = 10 with nx = 5, 4 rows and shear = 1e\+308 puts nodes beyond double precision"),
    ("density-mass-underflow", _layer("A", "density", "1e-300", _with(a=("spacing = 1.0", "spacing = 1e-5"))),
     r"layers\[0\]\.density = 1e-300 with lattice\.spacing = 1e-05 gives a node mass ρ·a³ = 1e-315, beyond double"),
    ("gravity-overflow", _with(a=("top_displacement = [0.06, -0.1]", "top_displacement = [0.06, -0.1]\ngravity = 1e308")),
     r"load\.gravity = 1e\+308 times the node mass of layers\[1\]\.density overflows"),
    ("stiffness-contrast-1e20", _layer("B", "stiffness", "5e20"),
     r"layers\[0\]\.stiffness = 1 and layers\[1\]\.stiffness = 5e\+20 differ by 5\.0e\+20, more than 1e\+12"),
    ("stiffness-1e300", _layer("A", "stiffness", "1e300"), r"layers\[1\]\.stiffness = 5 and layers\[0\]\.stiffness = 1e\+300"),
    ("interface-stiffness-contrast", _with(a=('kind = "bonded"', 'kind = "bonded"\nstiffness = 1e-20')),
     r"interfaces\.stiffness \(below = 'A'\) = 1e-20 and layers\[1\]\.stiffness = 5"),
    ("friction-1e300", _with(a=("friction = 3.0", "friction = 1e300")),
     r"contact\.friction = 1e\+300 is above 1e\+12: a slipping node's row sums μ times the normal stiffness"),
    ("lam-min-negative", _solver("lam_min = -5"), r"solver\.lam_min must be >= 0, got -5"),
    ("lam-min-inf", _solver("lam_min = inf"), r"solver\.lam_min must be finite"),
    ("tol-0.5", _solver("tol = 0.5"), r"solver\.tol must be <= 0\.01 .*, got 0\.5"),
    ("nx-int64", _with(a=("nx = 5", "nx = 9223372036854775807")), r"layers declare 4 rows x 9223372036854775807 columns"),
]


@pytest.mark.parametrize("text, pattern", [c[1:] for c in VALUE_ERRORS], ids=[c[0] for c in VALUE_ERRORS])
def test_scene_values_out_of_range_together_name_the_key(text, pattern):
    with pytest.raises(ProblemError, match=pattern):
        loads_scene(text)


def test_a_long_value_is_shortened_in_the_message():
    """A million-entry list where a number belongs: the message stays one short line."""
    with pytest.raises(ProblemError) as err:
        loads_scene(_with(a=("nx = 5", "nx = [" + ", ".join(["1"] * 100000) + "]")))
    assert "lattice.nx must be an integer" in str(err.value) and len(str(err.value)) < 200


# ---------------------------------------------------------------------------------------
# Size guards: refused before anything is allocated, naming the keys
# ---------------------------------------------------------------------------------------

@pytest.mark.parametrize("changes, pattern", [
    ({"a": ("nx = 5", "nx = 1000000000")},
     r"lattice\.nx = 1,000,000,000 columns × 4 rows \(layers\[0\]\.rows = 2, layers\[1\]\.rows = 2\) = 8,000,000,000 DOFs"),
    ({"a": ("rows = 2", "rows = 1000000000")},
     r"lattice\.nx = 5 columns × 2,000,000,000 rows .* = 20,000,000,000 DOFs"),
], ids=["nx-1e9", "rows-1e9"])
def test_a_scene_beyond_32_bit_indices_is_refused_by_analyze_at_once(changes, pattern):
    """``nx = 10⁹`` used to grow to 15 GB and beyond without a message."""
    scene = loads_scene(_with(**changes))
    with pytest.raises(ProblemError, match=pattern + r": (more than the 2,147,483,647 that this PETSc build's "
                                                     r"32-bit indices can number|an analysis needs at least)"):
        meicp.analyze(scene)
    with pytest.raises(ProblemError, match=pattern):
        meicp.critical_friction(scene)


def test_a_scene_beyond_the_machine_memory_is_refused(monkeypatch):
    """The memory estimate (3 kB per DOF for an analysis, below every measurement) against
    what the machine has; here the machine is said to have 1 GB."""
    scene = loads_scene(_with(a=("nx = 5", "nx = 200000")))
    monkeypatch.setattr(instability, "available_memory_on", lambda comm: (10 ** 9, "this machine"))
    with pytest.raises(ProblemError, match=r"lattice\.nx = 200,000 columns × 4 rows .* = 1,600,000 DOFs: an "
                                           r"analysis needs at least about 4\.8 GB .* but this machine has 1 GB"):
        meicp.analyze(scene)


def test_size_estimate_and_limits():
    scene = loads_scene(TWO_LAYERS)
    est = estimate_size(scene)
    assert est.dofs == 40 and est.nonzeros == 18 * 40 and est.bytes == 3000 * 40
    assert check_size(scene, memory=est.bytes, index_max=720) == est  # exactly at the limits: accepted
    with pytest.raises(ProblemError, match="more than the 39 that this PETSc build's 7-bit indices"):
        check_size(scene, memory=None, index_max=39)
    with pytest.raises(ProblemError, match=r"K would have up to 720 nonzeros, more than 2 rank\(s\) can hold .* "
                                           r"use at least 8 ranks"):
        check_size(scene, memory=None, index_max=100, ranks=2)
    with pytest.raises(ProblemError, match=r"the lattice geometry needs at least about 6 kB"):
        check_size(scene, memory=5000, use="geometry")
    assert index_max() in (2 ** 31 - 1, 2 ** 63 - 1)


# ---------------------------------------------------------------------------------------
# analyze: lam_min filters the modes listed, the verdict is about σ ≥ 0; arguments checked
# ---------------------------------------------------------------------------------------

@pytest.mark.parametrize("method", ["enumerate", "active-set"])
@pytest.mark.parametrize("lam_min", [0.5, 1e300])
def test_lam_min_above_the_mode_filters_it_but_the_scene_stays_unstable(method, lam_min):
    """Before: ``[solver] lam_min = 0.5`` or ``1e300`` turned the unstable scene (σ = 0.329)
    into STABLE "(a proof)"; now the search covers σ ≥ 0 and lam_min only filters the list."""
    r = meicp.analyze(loads_scene(_solver(f"lam_min = {lam_min!r}")), method=method)
    assert r.stable is False and r.modes == []
    assert f"1 with 0 ≤ σ < lam_min = {lam_min:g} not listed" in r.evidence
    same = meicp.analyze(loads_scene(TWO_LAYERS), method=method, lam_min=lam_min)
    assert same.stable is False and same.modes == [] and same.evidence == r.evidence


def test_lam_min_below_the_mode_keeps_it():
    r = meicp.analyze(loads_scene(_solver("lam_min = 0.3")))
    assert r.stable is False and len(r.modes) == 1 and np.isclose(r.modes[0].sigma, SIGMA, rtol=1e-9)


@pytest.mark.parametrize("kwargs, pattern", [
    ({"lam_min": -5}, r"^lam_min must be ≥ 0, got -5\.0: a mode with σ < 0 is an oscillation, never a divergence mode"),
    ({"lam_min": float("nan")}, r"^lam_min must be a finite number, got nan"),
    ({"lam_min": float("inf")}, r"^lam_min must be a finite number"),
    ({"lam_min": "0.5"}, r"^lam_min must be a real number"),
    ({"lam_max": 1.0}, r"^analyze does not take 'lam_max': the verdict covers every σ ≥ 0"),
    ({"J": [0]}, r"^analyze does not take 'J': analyze sets it itself"),
    ({"tol": 0.5}, r"^tol must lie in \(0, 0\.01\]"),
    ({"method": "nosuch"}, r"^method must be one of active-set, enumerate, rayleigh, semismooth, auto, got 'nosuch'"),
], ids=["lam-min-negative", "lam-min-nan", "lam-min-inf", "lam-min-string", "lam-max", "J", "tol", "method"])
def test_analyze_refuses_bad_arguments(kwargs, pattern):
    """``analyze(scene, lam_min=…)`` used to raise TypeError (lam_min given twice)."""
    with pytest.raises(ProblemError, match=pattern):
        meicp.analyze(SCENES / "two_layers.toml", **kwargs)


def test_a_scene_built_in_code_with_negative_lam_min_is_refused():
    """A Scene that did not come through the parser: analyze checks ``[solver] lam_min`` too
    (before: 27 "divergence modes", 26 of them with σ < 0)."""
    scene = loads_scene(TWO_LAYERS)
    scene = dataclasses.replace(scene, solver=dataclasses.replace(scene.solver, lam_min=-5.0))
    with pytest.raises(ProblemError, match=r"^\[solver\] lam_min must be ≥ 0, got -5\.0"):
        meicp.analyze(scene)


@pytest.mark.parametrize("method", [None, "active-set"])
def test_a_layer_of_density_1e16_is_never_stable(method):
    """The issue's first case at the analyze level for the other methods (enumeration:
    tests/test_hostile_api.py): the light bottom layer's mode σ ≈ 3.29e15 is found, by
    enumeration (auto) or by the search from the top of the σ-window (active-set) — never STABLE
    (before issue 14 the active-set's shift at 0 missed it: undecided)."""
    r = meicp.analyze(loads_scene(_layer("A", "density", "1e-16")), method=method)
    assert r.divergence is True and np.isclose(r.modes[0].sigma, 0.32866195834394e16, rtol=1e-9)


def test_an_enumeration_that_cannot_resolve_its_pencil_is_undecided():
    """density 1e-300 in one layer: LAPACK's QZ does not converge on some supports (it used
    to raise LinAlgError out of analyze); the enumeration says undecided, analyze too.

    The scene also has certified flutter modes, which prove it unstable: the question is
    answered, so the run is ``solved`` (it used to be ``inconclusive``, a failure) with
    divergence undecided and the failure named; without flutter nothing is decided and the
    run is ``inconclusive``."""
    scene = loads_scene(_layer("A", "density", "1e-300"))
    r = meicp.analyze(scene, method="enumerate")
    assert r.divergence is None and r.eicp[0].status == "undecided"
    assert r.flutter is True and r.stable is False and r.status == "solved" and r.success
    assert "the QZ eigen-solve (LAPACK) did not converge" in r.evidence and "not a proof" in r.evidence
    assert "did not converge" in r.divergence_failure and r.message == r.divergence_failure
    assert r.divergence_verdict == "DIVERGENCE UNDECIDED (search inconclusive: enumerate ended undecided)"
    r = meicp.analyze(scene, method="enumerate", flutter=False)
    assert r.stable is None and r.status == "inconclusive" and not r.success and "did not converge" in r.message


@pytest.mark.parametrize("status", ["undecided", "out_of_range", "max_iterations"])
def test_only_a_no_solution_enumeration_proves_stability(monkeypatch, status):
    """An enumeration that found nothing proves stability only with status ``no_solution``
    (before: any empty list was "(a proof)")."""
    def fake(A, B, **kw):
        return EiCPResult(method="enumerate", status=status, message=f"{status}: the reason")

    monkeypatch.setattr(enumeration, "solve_eicp", fake)  # the enumeration path's solver
    # without flutter the question stays open: a failure (inconclusive)
    r = meicp.analyze(SCENES / "two_layers.toml", method="enumerate", flutter=False)
    assert r.divergence is None and r.stable is None and r.status == "inconclusive"
    assert f"not a proof ({status})" in r.evidence and r.message == f"{status}: the reason"
    # the scene's certified flutter mode answers it (UNSTABLE): solved, divergence still undecided
    r = meicp.analyze(SCENES / "two_layers.toml", method="enumerate")
    assert r.divergence is None and r.flutter is True and r.stable is False and r.status == "solved"
    assert r.divergence_failure == f"{status}: the reason" and f"not a proof ({status})" in r.evidence


# ---------------------------------------------------------------------------------------
# The inertia proof (symmetric pencils, active-set path): rounding is undecided, never stable
# ---------------------------------------------------------------------------------------

def _pencil(A, B, petsc: bool):
    A, B = sp.csr_matrix(np.array(A, dtype=float)), sp.csr_matrix(np.array(B, dtype=float))
    return (mat_from_scipy(None, A), mat_from_scipy(None, B)) if petsc else (A, B)


@pytest.mark.parametrize("petsc", [False, True], ids=["scipy", "petsc"])
@pytest.mark.parametrize("A, B, proved, words", [
    (-np.array([[1, 1], [1, 1 + 1e-15]]), np.eye(2), None, "within rounding of 0"),  # before: "a proof"
    (-np.array([[1, 1], [1, 1.0]]), np.eye(2), None, "within rounding of 0"),        # σ = 0 exactly
    (-np.array([[1, 1], [1, 1 + 1e-6]]), np.eye(2), True, "negative definite"),
    (-np.array([[1, 1], [1, 1 - 1e-6]]), np.eye(2), False, "above rounding"),
    (np.diag([-1.0, -1e-20]), np.eye(2), True, "negative definite"),                  # graded, exactly definite
    (np.diag([-1.0, -2.0]), np.array([[2.0, 1.0], [1.0, 1.0]]), True, "B − η·diag|B| is positive definite"),
    (np.diag([-1.0, -2.0]), np.array([[1.0, 2.0], [2.0, 1.0]]), False, "B is not proved positive definite"),
    (np.diag([-1.0, -2.0]), np.diag([1.0, 0.0]), False, "B is diagonal with an entry 0"),
], ids=["rounding-below", "exact-zero", "definite", "indefinite", "graded", "B-full", "B-indefinite", "B-singular"])
def test_inertia_proof_holds_only_beyond_rounding(A, B, proved, words, petsc):
    pa, pb = _pencil(A, B, petsc)
    try:
        proof = pencil_is_negative(pa, pb)
    finally:
        if petsc:
            pa.destroy()
            pb.destroy()
    assert proof.proved is proved and words in proof.reason, proof


def test_inertia_of_a_nonsymmetric_pencil_is_no_proof():
    assert pencil_is_negative(sp.csr_matrix(np.array([[-1.0, 1.0], [0.0, -1.0]])), sp.identity(2, format="csr")) is None


def test_a_free_body_is_undecided_not_stable_by_inertia():
    """Every base node separated and the top free: the lattice floats (three σ = 0 rigid
    motions).  An active-set search aimed elsewhere finds no mode; the inertia of A then has
    three zero eigenvalues within rounding: undecided, with that reason."""
    text = _with(a=('top = "fixed"', 'top = "free"'), b=("top_displacement = [0.06, -0.1]", ""),
                 c=('states = "slip+"', 'states = "separated"'))
    r = meicp.analyze(loads_scene(text), method="active-set", target=-5.0, nev=1)
    assert r.stable is None and "3 eigenvalue(s) of sym(A) lie within rounding of 0" in r.evidence



ONE_ROW = """
title = "one row sliding"
[lattice]
nx = 20
spacing = 1.0
[[layers]]
name = "A"
rows = 1
stiffness = 1.0
density = 1.0
[boundary]
top = "free"
bottom = "contact"
left = "free"
right = "free"
[contact]
friction = 0.3
states = ["slip-", "slip+", "slip-", "slip-", "slip-", "slip-", "slip+", "slip-", "slip-", "slip+",
          "slip-", "slip+", "slip-", "slip-", "slip-", "slip-", "slip+", "slip-", "slip-", "slip+"]
"""


def test_a_lattice_whose_every_free_dof_is_a_contact_dof_is_condensed_without_solves():
    """One row on the base, top free: every retained DOF is a contact DOF (F empty), so
    G(σ) = H_JJ(σ).  The condensed proof crashed ("cannot reshape array of size 0"); the
    block slides as a whole (σ = 0 within rounding), so the verdict is undecided, saying why."""
    r = meicp.analyze(loads_scene(ONE_ROW), flutter=False)
    assert r.divergence is None and "condensed test: σ = 0 not excluded" in r.evidence

# ---------------------------------------------------------------------------------------
# meicp solve: one message, the right exit code, no traceback (concurrent processes)
# ---------------------------------------------------------------------------------------

TITLE = 'title = "two layers on a rough base"'
#: the lower layer floating on the sliding base (top free, no load): unstable, μ_c undefined
FLOATING = _with(t=('top = "fixed"', 'top = "free"'), l=("top_displacement = [0.06, -0.1]", ""))
#: no divergence, decided by the window procedure (the inertia proof, then the condensation)
BELOW_WIDE = (SCENES / "two_layers_below_mu_c.toml").read_text().replace("nx = 5", "nx = 30")
#: write the outputs into the case's own directory, to be checked
OUT = ["-o", "{out}"]

#: (id, scene text or a path, exit code, pattern in stderr (exit 2) or stdout[, arguments
#: instead of --no-output])
SOLVE_CASES = [
    ("dev-zero", "/dev/zero", 2, r"meicp: error: /dev/zero: not a regular file"),
    ("invalid-utf8", TWO_LAYERS.encode().replace(b"two layers", b"two \xff layers"), 2, r"not UTF-8 text"),
    ("nested", "title = " + "[" * 5000 + "]" * 5000, 2, r"nested deeper than 32 levels"),
    ("nx-1e9", _with(a=("nx = 5", "nx = 1000000000")), 2, r"8,000,000,000 DOFs: more than the 2,147,483,647"),
    ("rows-1e9", _with(a=("rows = 2", "rows = 1000000000")), 2, r"20,000,000,000 DOFs"),
    ("spacing-1e300", _with(a=("spacing = 1.0", "spacing = 1e300")), 2, r"lattice\.spacing = 1e\+300"),
    ("lam-min-negative", _solver("lam_min = -5"), 2, r"solver\.lam_min must be >= 0"),
    # past 16 contacts the divergence search reads [petsc]: a value PETSc rejects is bad input,
    # not an inconclusive search (it exited 1 with results written)
    ("petsc-value-rejected", _with(a=("nx = 5", "nx = 30"), b=("eps_tol = 1e-10", 'eps_tol = "abc"')), 2,
     r"PETSc cannot use an option value under -meicp_as_: Input string abc has no numeric value"),
    ("method-unknown", _with(a=('method = "auto"', 'method = "nosuch"')), 2, r"\[solver\] method must be one of"),
    ("stiffness-1e20", _layer("B", "stiffness", "5e20"), 2, r"differ by 5\.0e\+20"),
    ("lam-min-0.5", _solver("lam_min = 0.5"), 0, r"verdict +UNSTABLE\ndivergence +DIVERGENCE\n.*1 with 0 ≤ σ < lam_min = 0\.5 not listed"),
    ("bom", b"\xef\xbb\xbf" + TWO_LAYERS.encode(), 0, r"verdict +UNSTABLE(.|\n)*0\.32905494"),
    ("density-1e-16", _layer("A", "density", "1e-16"), 0, r"verdict +UNSTABLE(.|\n)*3\.2866196e\+15"),
    # flutter modes prove it unstable while the divergence enumeration is undecided: the
    # question is answered (exit 0; it exited 1, "FAILED (inconclusive), last verdict UNSTABLE")
    ("density-1e-300", _layer("A", "density", "1e-300"), 0,
     r"verdict +UNSTABLE\ndivergence +DIVERGENCE UNDECIDED \(search inconclusive: enumerate ended undecided\)\n"
     r"evidence .*QZ eigen-solve \(LAPACK\) did not converge(.|\n)*flutter +FLUTTER\n"),
    # issue 30: hostile residue, each with its files written (args after the case's pattern).
    # A long title made Matplotlib refuse the image size (10 kB: exit 3, "Image size of
    # 124492x958 pixels is too large") or never finish the PNG (3 MB); '$' started mathtext
    ("title-10kB", _with(t=(TITLE, 'title = "' + "x" * 10_000 + '"')), 0, r"verdict +UNSTABLE", OUT),
    ("title-3MB", _with(t=(TITLE, 'title = "' + "x y$" * 750_000 + '"')), 0, r"scene +(x y\$){19}x y…  \(", OUT),
    ("title-mathtext", _with(t=(TITLE, "title = 'cost $\\frac{ and $'")), 0, r"scene +cost \$\\frac\{ and \$", OUT),
    # values PETSc accepts but the proofs cannot use: exit 3 "internal error ... No method
    # getfactoredmatrix for PC of type jacobi"
    ("schur-pc-jacobi", BELOW_WIDE, 2, r"meicp: error: -meicp_schur_pc_type jacobi: the condensation onto the "
     r"contact DOFs reads a MUMPS factorisation \(pc_type cholesky or lu", ["--", "-meicp_schur_pc_type", "jacobi"]),
    ("inertia-pc-none", BELOW_WIDE, 2, r"meicp: error: -meicp_inertia_pc_type none: the inertia proof reads a MUMPS "
     r"factorisation", ["--", "-meicp_inertia_pc_type", "none"]),
    # the lower layer floats: μ_c is undefined; --critical-friction exited 2 and threw the
    # UNSTABLE verdict and its files away
    ("critical-friction-floating", FLOATING, 0, r"verdict +UNSTABLE(.|\n)*μ_c +not determined: .*μ_c is undefined",
     ["--critical-friction"] + OUT),
]


@pytest.fixture(scope="module")
def solve_outcomes(tmp_path_factory):
    d = tmp_path_factory.mktemp("hostile_solve")

    def one(case):
        name, content = case[0], case[1]
        path = content if isinstance(content, str) and content.startswith("/dev/") else \
            str(_write(d / f"{name}.toml", content))
        args = [str(d / name) if a == "{out}" else a for a in (case[4] if len(case) > 4 else [])]
        if "-o" not in args:
            args = ["--no-output"] + args
        return name, run(meicp_cmd() + ["solve", path, "-q"] + args, timeout=120)

    with ThreadPoolExecutor(max_workers=4) as pool:
        return dict(pool.map(one, SOLVE_CASES), _dir=d)


@pytest.mark.parametrize("name, code, pattern", [(c[0], c[2], c[3]) for c in SOLVE_CASES],
                         ids=[c[0] for c in SOLVE_CASES])
def test_solve_on_hostile_scenes(solve_outcomes, name, code, pattern):
    out = solve_outcomes[name]
    assert out.returncode == code, (out.stdout, out.stderr)
    assert "Traceback" not in out.stderr and "Warning" not in out.stderr, out.stderr
    assert re.search(pattern, out.stderr if code == 2 else out.stdout), (out.stdout, out.stderr)
    if code == 2:
        assert [line.startswith("meicp: error:") for line in out.stderr.splitlines()] == [True], out.stderr
    case = next(c for c in SOLVE_CASES if c[0] == name)
    if OUT[1] in (case[4] if len(case) > 4 else []):  # the verdict's files, whole, whatever the extras did
        written = {p.name for p in (solve_outcomes["_dir"] / name).iterdir()}
        assert written == {"results.h5", "lattice.h5", "lattice.xdmf", "mode.png", "flutter_mode.png",
                           "contacts.png"}, written


def test_an_enumeration_holds_at_most_its_stack_budget(monkeypatch):
    """A forced enumeration of 17 pairs on 85 retained DOFs held 5.8 GB for 352 s: each stack
    held up to 20,000 supports whatever their order, at about 8 order² doubles each (0.9 GB per
    array at order 76).  A stack now fits STACK_BYTES (256 MiB; here lowered to 1 MiB), as
    tracemalloc measures — and the same enumeration with stacks of 20,000 goes far past it."""
    import tracemalloc

    from meicp.eicp import enumeration as eicp_enumeration

    # the shipped budget at the order of the reported case: 580 supports per stack, 256 MiB
    assert eicp_enumeration.stack_size(76) * eicp_enumeration.STACK_ARRAYS * 8 * 76 ** 2 <= 256 * 2 ** 20
    rng = np.random.default_rng(3)
    n, pairs = 40, 10
    K = rng.standard_normal((n, n))
    A, B = -(K @ K.T + n * np.eye(n)), np.diag(rng.uniform(1.0, 2.0, n))
    J = np.arange(n - pairs, n)

    def peak(stack_bytes):
        monkeypatch.setattr(eicp_enumeration, "STACK_BYTES", stack_bytes)
        tracemalloc.start()
        try:
            r = meicp.solve_eicp(A, B, J=J, method="enumerate", lam_min=0.0)
            return tracemalloc.get_traced_memory()[1], r
        finally:
            tracemalloc.stop()

    budget = 2 ** 20
    bounded, r = peak(budget)
    unbounded, r0 = peak(2 ** 40)
    assert r.status == r0.status == "no_solution" and r.coverage["supports"] == 2 ** pairs
    assert bounded < 2 * budget + 8 * n * n * 8, bounded  # the stack, the pencil's own copies
    assert unbounded > 10 * budget, unbounded
