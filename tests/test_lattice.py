"""The layered lattice (seed 000 §II; docs/design.md §5, §10.1): scene files, K and M, output.

Verification, each able to catch a real bug:
(a) the sheared 4-mass cell against the seed's block K written out here from its formulas,
    errata applied (and the seed as printed is shown to differ);
(b) symmetry, rigid translations and the infinitesimal rotation in the null space;
(c) serial SciPy and PETSc assembly identical (2 ranks: tests/test_lattice_mpi.py);
(d) analytic vibration frequencies of homogeneous lattices through a SLEPc solve;
(e) total mass = Σ ρ a³.
"""

import argparse
import copy
import dataclasses
import math
import shutil
import subprocess
import xml.etree.ElementTree as ET

import numpy as np
import pytest
import scipy.linalg

from meicp.core.errors import ProblemError
from meicp.io.scene import load_scene, scene_from_dict
from meicp.lattice.assembly import assemble_scipy
from meicp.petsc.assembly import assemble
from meicp.scene import Scene
from meicp.lattice.model import LatticeModel

from .conftest import ROOT
from .helpers import bond_stiffness

SCENES = ROOT / "data" / "scenes"


def base_scene() -> dict:
    """A valid scene as parsed TOML; the error tests break one key at a time."""
    return {
        "lattice": {"nx": 6, "spacing": 1.0, "shear": 0.0, "interface_stiffness": "mean"},
        "layers": [{"name": "A", "rows": 2, "stiffness": 1.0, "density": 1.0},
                   {"name": "B", "rows": 3, "stiffness": 5.0, "density": 2.0}],
        "boundary": {"top": "fixed", "bottom": "contact", "left": "free", "right": "free"},
        "contact": {"friction": 0.5, "states": "slip+"},
    }


def scene_of(**lattice_and_more) -> Scene:
    d = base_scene()
    d.update(lattice_and_more)
    return scene_from_dict(d)


def A_of(theta: float) -> np.ndarray:
    """The seed's A_i = [[c², cs], [cs, s²]] of an angle."""
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c * c, c * s], [c * s, s * s]])


def angle(p, q) -> float:
    return math.atan2(q[1] - p[1], q[0] - p[0])


# ----------------------------------------------------------------------------- scenes

def test_shipped_scenes_load():
    names = sorted(p.name for p in SCENES.glob("*.toml"))
    for required in ("two_layers.toml", "sheared.toml", "embedded_layer.toml",
                     "frictional_interface.toml", "extensive.toml"):
        assert required in names
    for name in names:
        scene = load_scene(SCENES / name)
        assert scene.n_dofs == 2 * scene.nx * scene.ny
    assert load_scene(SCENES / "extensive.toml").n_dofs >= 10**6


def test_design_example_scene_parses_completely():
    s = load_scene(SCENES / "two_layers.toml")
    assert (s.nx, s.ny, s.lattice.spacing, s.lattice.shear) == (5, 4, 1.0, 0.0)
    assert [(l.name, l.rows, l.stiffness, l.density) for l in s.layers] == [("A", 2, 1.0, 1.0), ("B", 2, 5.0, 2.0)]
    assert s.boundary == type(s.boundary)(top="fixed", bottom="contact", left="free", right="free")
    assert len(s.interfaces) == 1 and s.interfaces[0].kind == "bonded" and s.interfaces[0].stiffness == 3.0
    assert (s.contact.friction, s.contact.states) == (3.0, "slip+")
    assert s.load.top_displacement == (0.06, -0.1)
    assert s.solver.method == "auto" and dict(s.petsc) == {"eps_tol": 1e-10}
    with pytest.raises(dataclasses.FrozenInstanceError):
        s.lattice.nx = 7
    with pytest.raises(TypeError):
        s.petsc["eps_tol"] = 1.0
    import pickle

    assert pickle.loads(pickle.dumps(s)) == s  # scenes travel between ranks (mpi4py pickles)
    assert hash(s) == hash(pickle.loads(pickle.dumps(s)))


def test_full_schema_values():
    d = base_scene()
    d["lattice"]["interface_stiffness"] = 4.0
    d["layers"].append({"name": "C", "rows": 1, "stiffness": 2.0, "density": 1.0})
    d["interfaces"] = [{"below": "B", "kind": "frictional", "friction": 0.3,
                        "states": ["stick", "slip+", "slip-", "separated", "grazing", "stick"]}]
    d["embedded"] = [{"name": "E", "host": "B", "row": 1, "rows": 1, "column": 2, "stiffness": 9.0,
                      "density": 3.0}]
    d["contact"]["states"] = "solve"
    d["load"] = {"top_displacement": [0.1, 0], "gravity": 9.81}
    d["solver"] = {"method": "lemke", "all_solutions": True, "lam_min": 0, "nev": 3, "tol": 1e-9,
                   "max_iterations": 50}
    d["petsc"] = {"-eps_type": "krylovschur", "st_pc_type": "lu", "eps_view": True}
    s = scene_from_dict(d)
    assert [i.kind for i in s.interfaces] == ["bonded", "frictional"]
    assert s.interfaces[0].stiffness == 4.0 and not s.interfaces[0].declared  # the lattice default
    assert s.interfaces[1].states[4] == "grazing" and s.interfaces[1].friction == 0.3
    e = s.embedded[0]
    assert (e.columns, e.interface_stiffness) == (4, 4.0)  # to the right edge; lattice default k_AB
    assert s.load.gravity == 9.81 and s.solver.nev == 3 and s.solver.all_solutions
    assert dict(s.petsc) == {"eps_type": "krylovschur", "st_pc_type": "lu", "eps_view": True}
    assert s.frictional_interfaces()[0].below == "B"


def _set(path, value):
    def change(d):
        keys = path.split(".")
        target = d
        for k in keys[:-1]:
            target = target[int(k)] if k.isdigit() else target.setdefault(k, {})
        if value is _DELETE:
            del target[keys[-1]]
        else:
            target[keys[-1]] = value
        return d
    return change


_DELETE = object()


@pytest.mark.parametrize("change, words", [
    (_set("colour", "red"), r"unknown key colour"),
    (_set("lattice.nx", 1), r"lattice\.nx must be >= 2"),
    (_set("lattice.nx", 2.5), r"lattice\.nx must be an integer"),
    (_set("lattice.nx", True), r"lattice\.nx must be an integer"),
    (_set("lattice.spacing", 0), r"lattice\.spacing must be > 0"),
    (_set("lattice.shear", "0.1"), r"lattice\.shear must be a number"),
    (_set("lattice.interface_stiffness", "median"), r"lattice\.interface_stiffness"),
    (_set("lattice.interface_stiffness", -1.0), r"lattice\.interface_stiffness must be > 0"),
    (_set("lattice.periodic", True), r"unknown key lattice\.periodic"),
    (_set("lattice.nx", _DELETE), r"lattice\.nx is required"),
    (_set("layers.1.density", -2.0), r"layers\[1\]\.density must be > 0"),
    (_set("layers.0.stiffness", 0), r"layers\[0\]\.stiffness must be > 0"),
    (_set("layers.0.stiffness", True), r"layers\[0\]\.stiffness must be a number"),
    (_set("layers.0.rows", 0), r"layers\[0\]\.rows must be >= 1"),
    (_set("layers.1.colour", "red"), r"unknown key layers\[1\]\.colour"),
    (_set("layers.1.name", "A"), r"layers\[1\]\.name repeats"),
    (_set("layers", []), r"layers must have at least one"),
    (_set("layers", _DELETE), r"layers is required"),
    (_set("boundary.top", "contact"), r"boundary\.top must be one of"),
    (_set("boundary.left", "roller"), r"boundary\.left must be one of"),
    (_set("boundary.front", "fixed"), r"unknown key boundary\.front"),
    (_set("contact", _DELETE), r"contact is required when boundary\.bottom"),
    (_set("boundary.bottom", "fixed"), r"contact describes the rigid base"),
    (_set("contact.friction", -0.1), r"contact\.friction must be >= 0"),
    (_set("contact.states", "slide"), r"contact\.states must be"),
    (_set("contact.states", ["stick"] * 5), r"contact\.states must list one state per column"),
    (_set("contact.states", ["stick", "stick", "slip", "stick", "stick", "stick"]), r"contact\.states\[2\]"),
    (_set("contact.states", ["solve"] * 6), r"contact\.states\[0\].*whole list"),
    (_set("interfaces", [{"below": "C"}]), r"interfaces\[0\]\.below must name a layer"),
    (_set("interfaces", [{"below": "B"}]), r"interfaces\[0\]\.below names the top layer"),
    (_set("interfaces", [{"below": "A", "kind": "glued"}]), r"interfaces\[0\]\.kind must be one of"),
    (_set("interfaces", [{"below": "A", "kind": "frictional", "friction": 0.2, "stiffness": 2.0}]),
     r"interfaces\[0\]\.stiffness applies to kind = \"bonded\" only"),
    (_set("interfaces", [{"below": "A", "kind": "frictional"}]), r"interfaces\[0\]\.friction is required"),
    (_set("interfaces", [{"below": "A", "friction": 0.2}]), r"interfaces\[0\]\.friction applies to kind"),
    (_set("interfaces", [{"below": "A", "stiffness": 0.0}]), r"interfaces\[0\]\.stiffness must be > 0"),
    (_set("interfaces", [{"below": "A"}, {"below": "A"}]), r"interfaces\[1\]\.below repeats"),
    (_set("interfaces", [{"below": "A", "kind": "frictional", "friction": 0.2, "states": "up"}]),
     r"interfaces\[0\]\.states must be"),
    (_set("embedded", [{"name": "E", "host": "Z", "stiffness": 1, "density": 1}]), r"embedded\[0\]\.host"),
    (_set("embedded", [{"name": "E", "host": "A", "row": 1, "rows": 2, "stiffness": 1, "density": 1}]),
     r"embedded\[0\]\.rows row \+ rows = 3 exceeds the 2 rows of layer 'A'"),
    (_set("embedded", [{"name": "E", "host": "A", "column": 4, "columns": 3, "stiffness": 1,
                        "density": 1}]),
     r"embedded\[0\]\.columns"),
    (_set("embedded", [{"name": "A", "host": "A", "stiffness": 1, "density": 1}]), r"embedded\[0\]\.name repeats"),
    (_set("embedded", [{"name": "E", "host": "A", "stiffness": 1, "density": 0}]), r"embedded\[0\]\.density must be > 0"),
    (_set("embedded", [{"name": "E", "host": "B", "columns": 3, "stiffness": 1, "density": 1},
                       {"name": "F", "host": "B", "column": 2, "stiffness": 1, "density": 1}]),
     r"embedded\[1\] overlaps embedded\[0\]"),
    (_set("load", {"top_displacement": [0.1]}), r"load\.top_displacement must be a list of 2"),
    (_set("load", {"top_displacement": [0.1, "x"]}), r"load\.top_displacement\[1\] must be a number"),
    (_set("load", {"force": 1.0}), r"unknown key load\.force"),
    (_set("solver", {"nev": 0}), r"solver\.nev must be >= 1"),
    (_set("solver", {"method": ""}), r"solver\.method must not be empty"),
    (_set("solver", {"all_solutions": 1}), r"solver\.all_solutions must be true or false"),
    (_set("petsc", {"eps": {"tol": 1}}), r"petsc\.eps must be a string, number or boolean"),
])
def test_scene_errors_name_the_key(change, words):
    with pytest.raises(ProblemError, match=words):
        scene_from_dict(change(copy.deepcopy(base_scene())), source="s.toml")


@pytest.mark.parametrize("old, new, words", [
    ("lattice.nx", "lattice.nxx", r"unknown key lattice\.nxx \(did you mean nx\? known here: nx, spacing"),
    ("layers.0.stiffness", "layers.0.stifness", r"unknown key layers\[0\]\.stifness \(did you mean stiffness\?"),
    ("lattice", "latice", r"unknown key latice \(did you mean lattice\?"),
    ("contact.friction", "contact.mu", r"unknown key contact\.mu \(known here: friction, states\)"),
])
def test_a_misspelt_required_key_is_reported_as_unknown_first(old, new, words):
    """`nxx = 5` was reported as "lattice.nx is required": unknown keys come first, with the
    nearest known key, then missing ones."""
    data = copy.deepcopy(base_scene())
    *path, key = old.split(".")
    table = data
    for k in path:
        table = table[int(k)] if k.isdigit() else table[k]
    table[new.split(".")[-1]] = table.pop(key)
    with pytest.raises(ProblemError, match=words):
        scene_from_dict(data, source="s.toml")


def test_top_displacement_needs_a_held_top():
    d = base_scene()
    d["boundary"]["top"] = "free"
    d["load"] = {"top_displacement": [0.1, 0.0]}
    with pytest.raises(ProblemError, match=r"load\.top_displacement needs a top boundary"):
        scene_from_dict(d)


def test_scene_file_errors_name_the_file(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[lattice]\nnx = 4\n[[layers]]\nname = 'A'\nrows = 2\nstiffness = 1.0\ndensity = -1.0\n")
    with pytest.raises(ProblemError, match=r"bad\.toml: layers\[0\]\.density must be > 0, got -1"):
        load_scene(bad)
    bad.write_text("[lattice\nnx = 4\n")
    with pytest.raises(ProblemError, match="not valid TOML"):
        load_scene(bad)
    with pytest.raises(ProblemError, match="cannot read scene file"):
        load_scene(tmp_path / "missing.toml")


# ----------------------------------------------------------------------------- (a) the seed's cell

def seed_cell_K(p, kA, kB, kAB, *, errata=True, erratum=None):
    """Seed 000 §II's 8×8 K of the 4-mass cell (nodes 1, 2 in A; 3 above 1, 4 above 2 in B),
    written from the paper's block formulas.  ``errata=True`` applies docs/design.md §12: coupling
    blocks negative, S with θ, each diagonal with its own angle (and each horizontal with its
    own, for a general quadrilateral).  ``erratum`` reverts a single one of them."""
    p1, p2, p3, p4 = p
    a12, a34 = angle(p1, p2), angle(p3, p4)
    gamma, theta = angle(p1, p3), angle(p2, p4)
    b14, b23 = angle(p1, p4), angle(p2, p3)
    sign = -1.0
    S_angle = theta
    if not errata or erratum == "sign":
        sign = +1.0
    if not errata or erratum == "S":
        S_angle = gamma
    if not errata or erratum == "diagonals":
        b23 = b14  # "both diagonals use β"
    if not errata:
        a34 = a12
    rA, rB = kA / kAB, kB / kAB
    P = rA * A_of(a12) + A_of(b14) + A_of(gamma)
    Q = rA * A_of(a12) + A_of(b23) + A_of(theta)
    R = rB * A_of(a34) + A_of(b23) + A_of(gamma)
    S = rB * A_of(a34) + A_of(b14) + A_of(S_angle)
    c = sign
    K = kAB * np.block([
        [P, c * rA * A_of(a12), c * A_of(gamma), c * A_of(b14)],
        [c * rA * A_of(a12), Q, c * A_of(b23), c * A_of(theta)],
        [c * A_of(gamma), c * A_of(b23), R, c * rB * A_of(a34)],
        [c * A_of(b14), c * A_of(theta), c * rB * A_of(a34), S]])
    return K


@pytest.mark.parametrize("kab", ["mean", 2.7])
def test_sheared_four_mass_cell_equals_seed_block_matrix(kab):
    d = {"lattice": {"nx": 2, "spacing": 1.3, "shear": 0.3, "interface_stiffness": kab},
         "layers": [{"name": "A", "rows": 1, "stiffness": 1.0, "density": 1.0},
                    {"name": "B", "rows": 1, "stiffness": 3.0, "density": 2.0}]}
    scene = scene_from_dict(d)
    K, _ = assemble(scene)
    a, sh = 1.3, 0.3
    p = [(0, 0), (a, 0), (sh * a, a), (a + sh * a, a)]  # natural order = seed's 1, 2, 3, 4
    kAB = 2.0 if kab == "mean" else kab
    ref = seed_cell_K(p, 1.0, 3.0, kAB)
    assert np.abs(K.toarray() - ref).max() < 1e-14 * np.abs(ref).max()
    # the seed as printed (positive coupling, one β) is a different matrix: the test can tell
    assert np.abs(K.toarray() - seed_cell_K(p, 1.0, 3.0, kAB, errata=False)).max() > 0.1
    assert np.abs(K.toarray() - seed_cell_K(p, 1.0, 3.0, kAB, erratum="diagonals")).max() > 0.1
    # the shipped scene is the same cell (spacing 1)
    K1, _ = assemble(load_scene(SCENES / "four_node_cell.toml"))
    p1 = [(0, 0), (1, 0), (0.3, 1), (1.3, 1)]
    assert np.allclose(K1.toarray(), seed_cell_K(p1, 1.0, 3.0, 2.0), rtol=0, atol=1e-14)


def test_general_quadrilateral_cell_each_bond_its_own_angle():
    """In a deformed cell θ ≠ γ and the horizontals differ: the bond-by-bond reference equals
    the seed's K with errata, and each single erratum reverted is detected."""
    p = np.array([(0.0, 0.0), (1.1, 0.15), (0.2, 0.9), (1.35, 1.2)])
    kA, kB, kAB = 1.0, 4.0, 2.2
    ends = [(0, 1), (2, 3), (0, 2), (1, 3), (0, 3), (1, 2)]
    K = bond_stiffness(p, ends, [kA, kB, kAB, kAB, kAB, kAB]).toarray()
    ref = seed_cell_K(p, kA, kB, kAB)
    assert np.abs(K - ref).max() < 1e-14
    for erratum in ("sign", "S", "diagonals"):
        assert np.abs(K - seed_cell_K(p, kA, kB, kAB, erratum=erratum)).max() > 1e-2, erratum


# ----------------------------------------------------------------------------- (b) null space

def free_scene(**extra) -> Scene:
    d = {"lattice": {"nx": 7, "spacing": 0.8, "shear": 0.35, "interface_stiffness": 2.5},
         "layers": [{"name": "A", "rows": 3, "stiffness": 1.0, "density": 1.0},
                    {"name": "B", "rows": 2, "stiffness": 6.0, "density": 2.0},
                    {"name": "C", "rows": 3, "stiffness": 3.0, "density": 0.5}],
         "embedded": [{"name": "E", "host": "C", "row": 1, "rows": 1, "column": 2, "columns": 3,
                       "stiffness": 10.0, "density": 4.0, "interface_stiffness": 7.0}],
         "interfaces": [{"below": "B", "stiffness": 1.5}]}
    d.update(extra)
    return scene_from_dict(d)


def rigid_modes(model: LatticeModel) -> np.ndarray:
    x = model.positions()
    tx = np.tile([1.0, 0.0], model.n_nodes)
    ty = np.tile([0.0, 1.0], model.n_nodes)
    rot = np.stack([-x[:, 1], x[:, 0]], axis=1).ravel()
    return np.stack([tx, ty, rot], axis=1)


def test_free_lattice_symmetric_with_rigid_null_space():
    scene = free_scene()
    model = LatticeModel(scene)
    K, M = assemble(scene)
    scale = abs(K).max()
    assert abs(K - K.T).max() == 0
    R = rigid_modes(model)
    assert np.abs(K @ R).max() < 1e-13 * scale * np.abs(R).max()
    w = scipy.linalg.eigvalsh(K.toarray())
    assert np.all(np.abs(w[:3]) < 1e-12 * scale) and w[3] > 1e-3 * scale  # exactly 3 rigid modes
    # the bond-by-bond reference gives the same matrix
    ends, _, ks = model.bonds()
    assert abs(K - bond_stiffness(model.positions(), ends, ks)).max() < 1e-13 * scale


def test_frictional_interface_has_no_bonds_and_two_rigid_bodies():
    d = {"interfaces": [{"below": "A", "kind": "frictional", "friction": 0.4}]}
    scene = free_scene(**d)
    model = LatticeModel(scene)
    K, _ = assemble(scene)
    w = scipy.linalg.eigvalsh(K.toarray())
    scale = abs(K).max()
    assert np.sum(np.abs(w) < 1e-12 * scale) == 6  # each body its own rigid motions
    lower, upper = model.interface_node_pairs(0)
    dl = np.ravel(2 * lower[:, None] + [0, 1])
    du = np.ravel(2 * upper[:, None] + [0, 1])
    assert abs(K[dl][:, du]).max() == 0
    bonded, _ = assemble(free_scene())
    assert abs(bonded[dl][:, du]).max() > 0


def test_natural_numbering_and_bond_stiffness_rules():
    """No shear: a horizontal bond of layer A between nodes n, n+1 is K[2n, 2n+2] = -k_A; a
    vertical bond across the interface is K[2n+1, 2(n+nx)+1] = -k_AB (declared or mean);
    embedded-host bonds use the band's interface stiffness."""
    d = base_scene()
    d["interfaces"] = [{"below": "A", "stiffness": 2.25}]
    d["embedded"] = [{"name": "E", "host": "B", "row": 1, "rows": 1, "column": 2, "columns": 2,
                      "stiffness": 9.0, "density": 1.0, "interface_stiffness": 4.5}]
    scene = scene_from_dict(d)
    K, _ = assemble(scene)
    nx = scene.nx
    n = 0 * nx + 3  # (3, 0) in A
    assert K[2 * n, 2 * n + 2] == -1.0 and K[2 * n + 1, 2 * n + 3] == 0.0
    n = 1 * nx + 4  # (4, 1): top row of A, vertical bond to (4, 2) in B
    assert K[2 * n + 1, 2 * (n + nx) + 1] == -2.25 and K[2 * n, 2 * (n + nx)] == 0.0
    n = 3 * nx + 2  # (2, 3) in E; (1, 3) is host B, (3, 3) is E
    assert K[2 * n, 2 * (n - 1)] == -4.5 and K[2 * n, 2 * (n + 1)] == -9.0
    n = 4 * nx + 0  # (0, 4) in B
    assert K[2 * n, 2 * n + 2] == -5.0
    d.pop("interfaces")
    K2, _ = assemble(scene_from_dict(d))
    n = 1 * nx + 4
    assert K2[2 * n + 1, 2 * (n + nx) + 1] == -3.0  # mean of 1 and 5


def test_constrained_dofs():
    d = base_scene()
    d["boundary"] = {"top": "fixed", "bottom": "fixed_y", "left": "fixed_x", "right": "free"}
    d.pop("contact")
    model = LatticeModel(scene_from_dict(d))
    nx, ny = model.nx, model.ny
    expect = set()
    for i in range(nx):
        expect |= {2 * ((ny - 1) * nx + i), 2 * ((ny - 1) * nx + i) + 1, 2 * i + 1}
    for j in range(ny):
        expect.add(2 * (j * nx))
    assert model.constrained_dofs().tolist() == sorted(expect)
    assert np.array_equal(np.sort(np.concatenate([model.free_dofs(), model.constrained_dofs()])),
                          np.arange(model.n_dofs))
    contact = LatticeModel(scene_from_dict(base_scene()))
    assert contact.contact_nodes().tolist() == list(range(nx))
    assert 1 not in contact.constrained_dofs()  # the base is not a Dirichlet condition


# ----------------------------------------------------------------------------- (c) SciPy vs PETSc

@pytest.mark.parametrize("name", ["sheared.toml", "embedded_layer.toml", "frictional_interface.toml",
                                  "four_node_cell.toml"])
def test_scipy_and_petsc_assembly_identical_and_exactly_preallocated(name):
    from meicp.petsc import import_petsc
    from meicp.petsc.mat import mat_to_scipy

    PETSc = import_petsc()
    scene = load_scene(SCENES / name)
    K, M = assemble(scene)
    Kp, Mp = assemble(scene, PETSc.COMM_SELF)
    try:
        assert abs(mat_to_scipy(Kp) - K).max() == 0 and abs(mat_to_scipy(Mp) - M).max() == 0
        info = Kp.getInfo()
        assert info["mallocs"] == 0 and info["nz_unneeded"] == 0 and info["nz_used"] == K.nnz
        assert Kp.isSymmetric(0.0)
    finally:
        Kp.destroy()
        Mp.destroy()
    # chunking does not change anything
    Kc, _ = assemble_scipy(LatticeModel(scene), chunk_nodes=7)
    assert abs(Kc - K).max() == 0 and np.array_equal(Kc.indptr, K.indptr)
    assert K.has_canonical_format and np.all(np.diff(K.indptr) > 0)


# ----------------------------------------------------------------------------- (d) frequencies

def single_row_scene(nx=30, k=2.0, rho=3.0, a=0.5, shear=0.2) -> Scene:
    return scene_from_dict({
        "lattice": {"nx": nx, "spacing": a, "shear": shear},
        "layers": [{"name": "rock", "rows": 3, "stiffness": k, "density": rho}],
        "boundary": {"top": "fixed", "bottom": "fixed", "left": "fixed", "right": "fixed"}})


def single_row_frequencies(nx, k, rho, a, shear) -> np.ndarray:
    """ω² of the homogeneous 3-row lattice with all sides fixed: only the middle row moves.

    Why this is analytic: every neighbour of a free node other than its two row neighbours
    is fixed, so the free system is ``K = T ⊗ k A_h + I ⊗ G`` with T = tridiag(−1, 2, −1)
    (Dirichlet chain of nx−2 nodes, eigenvalues 2 − 2cos(mπ/(nx−1)), sine modes), A_h the
    horizontal bond's A, and G = 2k (A_v + A_d + A_a) the springs to the fixed rows (each
    direction twice: up and down).  Sine modes separate it exactly into 2×2 problems."""
    A_h = A_of(0.0)
    G = 2 * k * (A_of(math.atan2(1, shear)) + A_of(math.atan2(1, 1 + shear))
                 + A_of(math.atan2(1, shear - 1)))
    out = []
    for m in range(1, nx - 1):
        t = 2 - 2 * math.cos(m * math.pi / (nx - 1))
        out.extend(np.linalg.eigvalsh(k * t * A_h + G))
    return np.sort(np.array(out)) / (rho * a ** 3)


def free_chain_frequencies(nx, k, rho, a) -> np.ndarray:
    """ω² of a single row with free ends and u_y held: a free-free spring chain,
    ω² = (2k/m)(1 − cos(rπ/nx)), r = 0..nx−1 (r = 0 is the rigid translation)."""
    r = np.arange(nx)
    return np.sort(2 * k / (rho * a ** 3) * (1 - np.cos(r * np.pi / nx)))


def slepc_smallest(scene, nev, target, comm=None):
    """The ``nev`` eigenvalues of (K, M) restricted to the free DOFs nearest ``target``, by
    SLEPc, with the largest residual ‖Kx − λMx‖ / (‖K‖∞ ‖x‖) of the returned pairs."""
    from meicp.petsc import import_petsc
    from meicp.petsc.assembly import principal_submatrix
    from meicp.petsc.eigen import solve_ghep

    PETSc = import_petsc()
    comm = comm or PETSc.COMM_SELF
    model = LatticeModel(scene)
    K, M = assemble(scene, comm)
    free = model.free_dofs()
    Kf, Mf = principal_submatrix(K, free), principal_submatrix(M, free)
    try:
        pairs = solve_ghep(Kf, Mf, nev=nev, target=target, prefix="test_lattice_")
        order = np.argsort(pairs.values)[:nev]
        knorm = Kf.norm(PETSc.NormType.INFINITY)
        resid = 0.0
        r, t = Kf.createVecLeft(), Kf.createVecLeft()
        for i in order:
            x = pairs.vectors[i]
            Kf.mult(x, r)
            Mf.mult(x, t)
            r.axpy(-pairs.values[i], t)
            resid = max(resid, r.norm() / (knorm * x.norm()))
        for v in pairs.vectors + [r, t]:
            v.destroy()
        vals = pairs.values[order]
    finally:
        for A in (K, M, Kf, Mf):
            A.destroy()
    return vals, resid


def test_single_row_lattice_frequencies_match_analytic_dispersion():
    nx, k, rho, a, shear = 30, 2.0, 3.0, 0.5, 0.2
    vals, resid = slepc_smallest(single_row_scene(nx, k, rho, a, shear), nev=10, target=0.0)
    ref = single_row_frequencies(nx, k, rho, a, shear)[:10]
    assert resid < 1e-10
    assert np.allclose(vals, ref, rtol=1e-9, atol=0), (vals, ref)
    # the comparison is sharp: the same lattice without shear has other frequencies
    assert not np.allclose(single_row_frequencies(nx, k, rho, a, 0.0)[:10], ref, rtol=1e-3)


def test_free_chain_frequencies():
    """Free-free chain (one row, u_y held): ω² = (2k/m)(1 − cos(rπ/nx)), with the rigid
    translation at 0.  (A chain, like the single row above, is a bipartite graph: flipping
    the sign of every coupling block is a similarity there, so the sign is checked by the
    free 2-D lattice below and by tests (a), (b).)"""
    nx, k, rho, a = 16, 2.0, 3.0, 0.5
    scene = scene_from_dict({
        "lattice": {"nx": nx, "spacing": a},
        "layers": [{"name": "chain", "rows": 1, "stiffness": k, "density": rho}],
        "boundary": {"bottom": "fixed_y"}})
    assert LatticeModel(scene).free_dofs().tolist() == list(range(0, 2 * nx, 2))
    vals, resid = slepc_smallest(scene, nev=6, target=-0.1 * k / (rho * a ** 3))
    ref = free_chain_frequencies(nx, k, rho, a)[:6]
    assert resid < 1e-10
    assert abs(vals[0]) < 1e-9 * k / (rho * a ** 3)
    assert np.allclose(vals[1:], ref[1:], rtol=1e-9, atol=0), (vals, ref)


def test_free_2d_lattice_has_exactly_three_zero_frequencies():
    """A free, connected 2-D lattice vibrates at zero frequency exactly in its 3 rigid motions.
    Its graph has triangles, so positive coupling blocks (the seed's sign error) or a wrong
    bond direction would leave no zero frequency at all."""
    scene = scene_from_dict({"lattice": {"nx": 9, "spacing": 0.7, "shear": 0.3},
                             "layers": [{"name": "a", "rows": 5, "stiffness": 2.0, "density": 3.0}]})
    unit = 2.0 / (3.0 * 0.7 ** 3)
    # nev above the multiplicity: a Krylov solver may stop before a third copy of 0 appears
    vals, resid = slepc_smallest(scene, nev=6, target=-0.05 * unit)
    assert resid < 1e-10
    assert np.sum(np.abs(vals) < 1e-9 * unit) == 3 and np.all(vals[3:] > 1e-3 * unit), vals


# ----------------------------------------------------------------------------- (e) mass

def test_total_mass_is_sum_of_rho_a_cubed():
    scene = free_scene()
    _, M = assemble(scene)
    a = scene.lattice.spacing
    expect = sum(l.density * a ** 3 * l.rows * scene.nx for l in scene.layers)
    e = scene.embedded[0]
    host = scene.layers[scene.layer_index(e.host)]
    expect += (e.density - host.density) * a ** 3 * e.rows * e.columns
    d = M.diagonal()
    assert np.array_equal(d[0::2], d[1::2])
    assert math.isclose(d.sum() / 2, expect, rel_tol=1e-14)
    assert math.isclose(LatticeModel(scene).total_mass(), expect, rel_tol=1e-14)
    assert M.nnz == M.shape[0]  # lumped: diagonal only
    assert set(np.unique(d)) == {l.density * a ** 3 for l in scene.layers} | {e.density * a ** 3}


# ----------------------------------------------------------------------------- output

def _bond_count(nx, ny):
    return (nx - 1) * ny + nx * (ny - 1) + 2 * (nx - 1) * (ny - 1)


def test_hdf5_and_xdmf_content(tmp_path):
    import h5py

    from meicp.io.lattice_output import write_lattice

    scene = load_scene(SCENES / "sheared.toml")
    model = LatticeModel(scene)
    u = np.arange(model.n_dofs, dtype=float)
    files = write_lattice(tmp_path / "s.h5", scene, fields={"u": u, "level": np.arange(model.n_nodes)})
    assert files.xdmf == tmp_path / "s.xdmf"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.h5", "s.xdmf"]  # no temporaries left
    with h5py.File(files.h5, "r") as f:
        assert f.attrs["format"] == "meicp-lattice" and f.attrs["nx"] == 12 and f.attrs["ny"] == 8
        pts = f["geometry/points"][...]
        assert np.array_equal(pts[:, :2], model.positions()) and np.all(pts[:, 2] == 0)
        conn = f["bonds/connectivity"][...]
        assert conn.shape == (_bond_count(12, 8), 2) == (f.attrs["n_bonds"], 2)
        assert np.all(conn[:, 0] < conn[:, 1])
        # the bonds rebuild K
        K, _ = assemble(scene)
        Kb = bond_stiffness(pts[:, :2], conn, f["bonds/stiffness"][...])
        assert abs(Kb - K).max() < 1e-13 * abs(K).max()
        assert np.array_equal(f["fields/u"][:, :2], u.reshape(-1, 2)) and np.all(f["fields/u"][:, 2] == 0)
        assert f["fields/level"].shape == (model.n_nodes,)
        assert np.array_equal(f["nodes/material"][...], model.material())
        assert f["materials/name"][...].tolist() == [b"A", b"B"]
        fixed = f["nodes/fixed"][...]
        assert np.all(fixed[:12, :2] == 1) and np.all(fixed[-12:, 0] == 0) and np.all(fixed[-12:, 1] == 1)
        assert "shear = 0.25" in f["scene"][()].decode()
        datasets = set()
        f.visit(lambda name: datasets.add(name))
    root = ET.parse(files.xdmf).getroot()
    items = root.findall(".//DataItem")
    assert items
    for item in items:
        h5name, _, dset = item.text.partition(":/")
        assert h5name == "s.h5" and dset in datasets
        dims = tuple(int(x) for x in item.get("Dimensions").split())
        with h5py.File(files.h5, "r") as f:
            assert f[dset].shape == dims
    topo = root.find(".//Topology")
    assert topo.get("TopologyType") == "Polyline" and topo.get("NodesPerElement") == "2"
    names = {a.get("Name"): a.get("AttributeType") for a in root.findall(".//Attribute")}
    assert names["u"] == "Vector" and names["material"] == "Scalar" and names["bond_stiffness"] == "Scalar"


def test_output_errors_before_any_file(tmp_path):
    from meicp.io.lattice_output import write_lattice

    scene = load_scene(SCENES / "two_layers.toml")
    with pytest.raises(ProblemError, match="field 'u' has 7 values"):
        write_lattice(tmp_path / "x.h5", scene, fields={"v": np.zeros(40), "u": np.zeros(7)})
    with pytest.raises(ProblemError, match="field name"):
        write_lattice(tmp_path / "x.h5", scene, fields={"a/b": np.zeros(40)})
    with pytest.raises(ProblemError, match="'mass' is taken"):
        write_lattice(tmp_path / "x.h5", scene, fields={"mass": np.zeros(20)})
    with pytest.raises(ProblemError, match="does not exist"):
        write_lattice(tmp_path / "no" / "x.h5", scene)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(shutil.which("pvpython") is None, reason="ParaView (pvpython) not installed")
def test_paraview_opens_the_xdmf(tmp_path):
    from meicp.io.lattice_output import write_lattice

    scene = load_scene(SCENES / "embedded_layer.toml")
    model = LatticeModel(scene)
    files = write_lattice(tmp_path / "e.h5", scene, fields={"u": np.ones(model.n_dofs)})
    script = tmp_path / "pv.py"
    script.write_text(
        "import sys\nfrom paraview.simple import OpenDataFile, servermanager\n"
        "r = OpenDataFile(sys.argv[1]); r.UpdatePipeline(); d = servermanager.Fetch(r)\n"
        "pd = d.GetPointData()\n"
        "print('RESULT', d.GetNumberOfPoints(), d.GetNumberOfCells(), d.GetCellType(0),"
        " pd.GetArray('u').GetNumberOfComponents(), pd.GetArray('material').GetRange()[1])\n")
    out = subprocess.run(["pvpython", "--force-offscreen-rendering", str(script), str(files.xdmf)],
                         capture_output=True, text=True, timeout=120)
    line = [x for x in out.stdout.splitlines() if x.startswith("RESULT")]
    assert line, out.stdout + out.stderr
    got = line[0].split()[1:]
    assert got == [str(model.n_nodes), str(_bond_count(40, 15)), "4", "3", "1.0"]  # 4 = VTK poly-line


def test_png(tmp_path):
    from meicp.plotting.lattice import plot_lattice

    for name, max_bonds in (("embedded_layer.toml", 60000), ("sheared.toml", 10)):
        png = plot_lattice(load_scene(SCENES / name), tmp_path / f"{name}.png", max_bonds=max_bonds)
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10000


def test_cli_lattice_command(tmp_path):
    from meicp.cli import lattice

    parser = argparse.ArgumentParser()
    lattice.register(parser.add_subparsers())
    args = parser.parse_args(["lattice", str(SCENES / "frictional_interface.toml"), "-o",
                              str(tmp_path / "out")])
    assert args.run(args) == 0
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == [
        "frictional_interface.h5", "frictional_interface.png", "frictional_interface.xdmf"]
    import h5py

    with h5py.File(tmp_path / "out" / "frictional_interface.h5", "r") as f:
        K, _ = assemble(load_scene(SCENES / "frictional_interface.toml"))
        assert np.array_equal(f["fields/K_diagonal"][:, :2].ravel(), K.diagonal())
    args = parser.parse_args(["lattice", str(tmp_path / "missing.toml")])
    with pytest.raises(ProblemError, match="cannot read"):
        args.run(args)
