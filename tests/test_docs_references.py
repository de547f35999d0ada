"""What the README and docs cite exists: every ``meicp.x.y`` name, every source, test or
script path, every test named, every Markdown link with its anchor, every section of
docs/benchmarks.md or docs/benchmarks-notes.md that the code and docs point to by name, and
every constant quoted as ``NAME = value`` with that value."""

import ast
import importlib
import re
import unicodedata

import pytest

from .conftest import ROOT

DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md")), ROOT / "data" / "scenes" / "README.md"]
#: files that cite benchmarks.md / benchmarks-notes.md sections by name
CITING = [*DOCS, ROOT / "Makefile", *sorted((ROOT / "src").rglob("*.py")), *sorted((ROOT / "scripts").glob("*.*")),
          *sorted(p for p in (ROOT / "tests").glob("*.py") if p.name != "test_docs_references.py")]


def _rel(path) -> str:
    return str(path.relative_to(ROOT))


def _found(pattern: str, files=DOCS) -> list:
    """(file, match) for every distinct match of ``pattern`` in ``files``."""
    return sorted({(_rel(f), m) for f in files for m in re.findall(pattern, f.read_text())})


DOTTED = _found(r"\bmeicp(?:\.[A-Za-z_]\w*)+")


def _resolves(dotted: str) -> bool:
    """Whether ``dotted`` is a module, or an attribute path inside the longest module prefix."""
    parts = dotted.split(".")
    for k in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:k]))
        except ImportError:
            continue
        for name in parts[k:]:
            if not hasattr(obj, name):
                return False
            obj = getattr(obj, name)
        return True
    return False


@pytest.mark.parametrize("where, name", DOTTED, ids=[f"{w}:{n}" for w, n in DOTTED])
def test_a_cited_meicp_name_exists(where, name):
    assert _resolves(name), f"{where} cites {name}, which does not exist"


#: paths from the repository root, and paths inside src/meicp (``contact/maps.py``,
#: ``divergence/cover.py``: somewhere under src/meicp)
ROOTED = [(w, p.rstrip(".")) for w, p in _found(r"(?<![\w/.])((?:src|tests|scripts|data|docs)/[\w./*-]*)")
          if "*" not in p]
INNER = [(w, p) for w, p in _found(r"(?<![\w/.])((?:[a-z_]+/)+[a-z_0-9]+\.py)\b")
         if not p.startswith(("src/", "tests/", "scripts/", "data/", "docs/"))]


@pytest.mark.parametrize("where, path", ROOTED, ids=[f"{w}:{p}" for w, p in ROOTED])
def test_a_cited_repository_path_exists(where, path):
    assert (ROOT / path).exists(), f"{where} cites {path}, which does not exist"


@pytest.mark.parametrize("where, path", INNER, ids=[f"{w}:{p}" for w, p in INNER])
def test_a_cited_module_path_exists_under_src_meicp(where, path):
    assert any((ROOT / "src" / "meicp").rglob(path)), f"{where} cites {path}: no such file under src/meicp"


TESTS_TEXT = "\n".join(p.read_text() for p in (ROOT / "tests").glob("*.py"))
TEST_NAMES = [(w, n) for w, n in _found(r"\b(test_\w+)(?![\w*]|\.py)") if not (ROOT / "tests" / f"{n}.py").exists()]


@pytest.mark.parametrize("where, name", TEST_NAMES, ids=[f"{w}:{n}" for w, n in TEST_NAMES])
def test_a_cited_test_exists(where, name):
    assert re.search(rf"\bdef {name}\b", TESTS_TEXT), f"{where} cites the test {name}, which does not exist"


def slug(heading: str) -> str:
    """GitHub's anchor of a Markdown heading."""
    text = unicodedata.normalize("NFC", heading.strip().lower())
    return re.sub(r"[^\w\- ]", "", text).replace(" ", "-")


def headings(path) -> list[str]:
    return [m.group(1) for m in re.finditer(r"^#{1,6} +(.+?) *$", path.read_text(), re.M)]


LINKS = _found(r"\]\(([^)\s]+)\)")


@pytest.mark.parametrize("where, target", LINKS, ids=[f"{w}:{t}" for w, t in LINKS])
def test_a_markdown_link_resolves(where, target):
    if re.match(r"[a-z]+:", target):  # http(s), mailto: not checked here
        return
    file, _, anchor = target.partition("#")
    path = (ROOT / where).parent / file if file else ROOT / where
    assert path.exists(), f"{where} links to {target}: no such file"
    if anchor:
        assert anchor in {slug(h) for h in headings(path)}, f"{where} links to {target}: no such heading"


#: ``benchmarks.md, Flutter)``, ``benchmarks.md ("Failure map")``: a section by its name's start
SECTION = r'benchmarks\.md\)?(?:, | \()(?:"([^"]+)"|([A-Za-z]+)(?=[):,]| section))'
NOTE = r'benchmarks-notes\.md\)?(?:, | \()(?:"([^"]+)"|([a-z]+)(?=[):,]))'


def _cited(pattern: str) -> list:
    return sorted({(w, a or b) for w, (a, b) in _found(pattern, CITING)})


@pytest.mark.parametrize("where, name", _cited(SECTION))
def test_a_benchmarks_section_cited_by_name_exists(where, name):
    assert any(h.lower().startswith(name.lower()) for h in headings(ROOT / "docs" / "benchmarks.md")), \
        f"{where} cites the section {name!r} of docs/benchmarks.md, which has none of that name"


@pytest.mark.parametrize("where, name", _cited(NOTE))
def test_a_benchmark_note_cited_by_name_exists(where, name):
    notes = ROOT / "docs" / "benchmarks-notes.md"
    text = notes.read_text()
    assert f'"{name}"' in text or f"`{name}`" in text or name in headings(notes), \
        f"{where} cites {name!r} in docs/benchmarks-notes.md, which has no such note or section"


def _constants() -> dict:
    """Module-level ``NAME = literal`` of every meicp module: NAME → the list of its values."""
    out: dict = {}
    for path in (ROOT / "src" / "meicp").rglob("*.py"):
        for node in ast.parse(path.read_text()).body:
            if isinstance(node, (ast.Assign, ast.AnnAssign)) and node.value is not None:
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                try:
                    value = ast.literal_eval(node.value)
                except (ValueError, TypeError, SyntaxError):
                    continue
                for t in targets:
                    if isinstance(t, ast.Name) and t.id.isupper():
                        out.setdefault(t.id, []).append(value)
    return out


CONSTANTS = _constants()
#: ``NAME = value`` in backticks, NAME upper case: a constant of the code with its value
QUOTED = [(w, m) for w, m in _found(r"`([A-Z][A-Z0-9_]{2,}) = ([^`]+)`") if not re.search(r"[^\w.+-]", m[1])]


@pytest.mark.parametrize("where, constant", QUOTED, ids=[f"{w}:{c[0]}" for w, c in QUOTED])
def test_a_quoted_constant_has_the_quoted_value(where, constant):
    name, value = constant
    assert name in CONSTANTS, f"{where} quotes {name}, which no meicp module defines"
    assert ast.literal_eval(value) in CONSTANTS[name], f"{where} quotes {name} = {value}; the code has {CONSTANTS[name]}"
