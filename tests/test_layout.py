"""The package's structure, read from its source: imports go one way between the rooms of the
README's layout table, no import circles, no function-level imports except of optional
heavy dependencies, PETSc/SLEPc named only inside ``meicp.petsc``."""

import ast
import io
import tokenize

import pytest

from .conftest import ROOT

SRC = ROOT / "src"
#: imported inside functions on purpose: importing them is costly or has side effects
#: (PETSc/SLEPc initialise with the command line's options, mpi4py starts MPI), or they are
#: needed by one feature only (HDF5 files, pictures, the Siconos peer)
LAZY = {"petsc4py", "slepc4py", "mpi4py", "h5py", "matplotlib", "siconos"}
#: the rooms, and those each may import (besides itself), lowest first: ``_version`` is the
#: package's version (``io``, ``info`` and ``cli`` report it: no arrow back up to the root),
#: ``meicp`` the package's ``__init__``, ``api`` the public entry points that also read scene
#: files, ``study`` the studies across a parameter built on them (``meicp.sweep``).
#: ``lcp`` and ``eicp`` know nothing of PETSc: they dispatch on matrix kinds (``core.matrix``) and name their methods in a registry, and ``petsc`` builds on them —
#: it registers the PETSc Mat's operations and the PETSc-based methods (as DOLFINx's
#: ``fem/petsc.py`` builds on ``fem/assemble.py``)
MAY_IMPORT = {
    "_version": set(),
    "core": set(),
    "scene": {"core"},
    "lattice": {"core", "scene"},
    "lcp": {"core"},
    "eicp": {"core", "lcp"},
    "petsc": {"core", "scene", "lattice", "lcp", "eicp"},
    "contact": {"core", "scene", "lattice", "lcp", "eicp", "petsc"},
    "plotting": {"core", "scene", "lattice"},
    "info": {"_version", "petsc"},
    "io": {"_version", "core", "scene", "lattice", "petsc", "plotting", "info"},
    "api": {"core", "scene", "lattice", "petsc", "contact", "io"},
    "study": {"_version", "core", "scene", "lattice", "petsc", "contact", "plotting", "io", "api"},
    "cli": {"_version", "core", "scene", "lattice", "petsc", "lcp", "eicp", "contact", "plotting", "info", "io",
            "study"},
    "meicp": {"_version", "core", "scene", "lattice", "lcp", "eicp", "petsc", "contact", "io", "api", "study"},
    "__main__": {"cli"},
    "examples": {"core", "scene", "lattice", "petsc", "contact", "io", "api", "study"},
}
#: names that mean PETSc or SLEPc in code: the bindings, their modules, and the loaders
#: that import them (comments, docstrings and other strings are prose or data, not use)
PETSC_NAMES = {"petsc4py", "slepc4py", "PETSc", "SLEPc", "import_petsc", "import_slepc"}


def _modules() -> dict:
    """module name → (path, is_package)."""
    out = {}
    for path in sorted((SRC / "meicp").rglob("*.py")):
        parts = list(path.relative_to(SRC).with_suffix("").parts)
        package = parts[-1] == "__init__"
        if package:
            parts = parts[:-1]
        out[".".join(parts)] = (path, package)
    return out


MODULES = _modules()


def _imports(name: str):
    """``(target, lineno, at_module_level)`` of every import in module ``name``; relative
    imports resolved, ``from pkg import sub`` pointing at the submodule when there is one."""
    path, package = MODULES[name]
    tree = ast.parse(path.read_text(encoding="utf-8"))
    base = name.split(".") if package else name.split(".")[:-1]
    top_level = {id(node) for node in tree.body}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name, node.lineno, id(node) in top_level
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                anchor = base[:len(base) - node.level + 1]
                module = ".".join(anchor + ([node.module] if node.module else []))
            else:
                module = node.module
            for alias in node.names:
                sub = f"{module}.{alias.name}"
                yield (sub if sub in MODULES else module), node.lineno, id(node) in top_level


def _room(module: str) -> str:
    parts = module.split(".")
    return "meicp" if len(parts) == 1 else parts[1]


def _graph() -> dict:
    """Import edges between meicp modules (at any level: a function-level import hides a
    circle only until the function runs), with the packages whose ``__init__`` an import
    runs (not the importer's own: those are already running)."""
    graph = {}
    for name in MODULES:
        own = {".".join(name.split(".")[:k]) for k in range(1, name.count(".") + 1)}
        edges = set()
        for target, _, _ in _imports(name):
            if not target.startswith("meicp"):
                continue
            parts = target.split(".")
            edges.update(p for p in (".".join(parts[:k]) for k in range(1, len(parts) + 1))
                         if p in MODULES and p not in own and p != name)
            if target in own:
                edges.add(target)  # an explicit import of an ancestor (``from .. import __version__``)
        graph[name] = edges
    return graph


def test_no_function_level_imports_but_the_lazy_heavy_ones():
    found = [f"{name}:{line} imports {target}" for name in MODULES for target, line, top in _imports(name)
             if not top and target.split(".")[0] not in LAZY]
    assert not found, "\n".join(found)


def test_petsc_and_slepc_are_imported_only_in_the_petsc_package():
    found = [f"{name}:{line}" for name in MODULES for target, line, _ in _imports(name)
             if target.split(".")[0] in ("petsc4py", "slepc4py") and not name.startswith("meicp.petsc")]
    assert not found, found


def test_no_petsc_name_outside_the_petsc_package():
    """``lcp``, ``eicp`` and ``contact`` reach PETSc only through what ``meicp.petsc``
    registers or offers: no PETSc object, exception or loader is named outside it."""
    found = []
    for name, (path, _) in MODULES.items():
        if name == "meicp.petsc" or name.startswith("meicp.petsc."):
            continue
        tokens = tokenize.generate_tokens(io.StringIO(path.read_text(encoding="utf-8")).readline)
        found += [f"{name}:{tok.start[0]} {tok.string}" for tok in tokens
                  if tok.type == tokenize.NAME and tok.string in PETSC_NAMES]
    assert not found, "\n".join(found)


def test_no_import_circles():
    graph = _graph()
    index, low, stack, on_stack, circles = {}, {}, [], set(), []

    def visit(v):  # Tarjan's strongly connected components
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                circles.append(sorted(component))

    for v in graph:
        if v not in index:
            visit(v)
    assert not circles, circles


@pytest.mark.parametrize("room", sorted(MAY_IMPORT))
def test_imports_go_one_way_between_rooms(room):
    allowed = MAY_IMPORT[room] | {room}
    found = sorted({f"{name} imports {target}" for name in MODULES if _room(name) == room
                    for target, _, _ in _imports(name)
                    if target.startswith("meicp") and _room(target) not in allowed})
    assert not found, "\n".join(found)


def test_every_module_is_in_a_room():
    assert {_room(name) for name in MODULES} <= set(MAY_IMPORT)


def test_no_test_imports_from_scripts():
    """Tests import what they use as users do (the scene builder is :mod:`meicp.examples`);
    scripts/ is run, never imported: no ``sys.path`` pointing into it."""
    tests = ROOT / "tests"
    found = [f"{path.relative_to(ROOT)}:{node.lineno}"
             for path in sorted(tests.rglob("*.py"))
             for node in ast.walk(ast.parse(path.read_text(encoding="utf-8")))
             if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
             and ast.unparse(node.func.value) == "sys.path" and "scripts" in ast.unparse(node)]
    assert not found, found
