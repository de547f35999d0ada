"""The vendored reference sets: every file tests/data/README.md lists is present and
unchanged, nothing unlisted was added, each set keeps its licence, and no test module
reads data from outside the repository (nor does a script, nor does any docstring cite notes
the repository does not carry)."""

import hashlib
import re

from .conftest import DATA, ROOT

LISTED = dict(re.findall(r"^\| `([^`]+)` \| `([0-9a-f]{64})` \|$", (DATA / "README.md").read_text(), re.M))


def test_every_listed_file_is_present_and_unchanged():
    assert len(LISTED) == 26  # 20 Siconos LCPs, 6 Niu EiCPs
    for name, digest in LISTED.items():
        assert hashlib.sha256((DATA / name).read_bytes()).hexdigest() == digest, name


def test_nothing_unlisted_and_each_set_keeps_its_licence():
    present = {p.relative_to(DATA).as_posix() for p in DATA.rglob("*") if p.is_file()}
    licences = {f"{d}/LICENSE" for d in ("siconos-lcp", "eicp-niu")}
    assert present == set(LISTED) | licences | {"README.md"}
    assert "Apache License" in (DATA / "siconos-lcp" / "LICENSE").read_text()
    assert "MIT License" in (DATA / "eicp-niu" / "LICENSE").read_text()


def _sources():
    """Every test module, script and source file, except this one (it names the patterns)."""
    for pattern in ("tests/*.py", "scripts/*.py", "scripts/*.sh", "src/meicp/**/*.py"):
        for path in sorted(ROOT.glob(pattern)):
            if path.name != "test_data.py":
                yield path


def test_no_test_or_script_reads_beside_the_repository():
    for path in _sources():
        text = path.read_text()
        assert "ROOT.parent" not in text and "../shared" not in text, path.name


def test_citations_name_the_notes_the_repository_carries():
    """The code cited "DESIGN §…", a file outside the repository: docs/design.md replaces it."""
    for path in _sources():
        assert "DESIGN" not in path.read_text(), path.relative_to(ROOT)
    assert (ROOT / "docs" / "design.md").is_file()
