"""docs/tutorial.md runs as written and prints what it says.

Its fenced blocks are taken in order, in a temporary directory (the files they write land
there): a ```toml block whose first line is ``# NAME.toml ...`` is saved as NAME.toml; the
```python blocks run one top-level statement at a time in one namespace, and where a
statement is followed by ``# → text`` (on its last line, or on comment lines of their own
below it, one per printed line) what it prints must match; every line of a ```sh block that
starts with ``meicp `` runs through the command's entry point (``> FILE`` saves its stdout),
and every line of a ```text block must be found, in order, in the last such command's
output.  A ``…`` in a quoted line stands for any text; a number matches the printed one
rounded to the digits quoted (``0.329`` matches 0.32905494…).  Lines that start otherwise
(``mpirun ...``) are not run here.
"""

import ast
import contextlib
import io
import math
import re
import shlex

import pytest

from meicp.cli.exit import Exit

from .conftest import ROOT

TUTORIAL = ROOT / "docs" / "tutorial.md"
BLOCK = re.compile(r"^```(\w+)\n(.*?)^```", re.S | re.M)
NUMBER = r"[-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?"
ARROW = re.compile(r"#\s*→ ?(.*?)\s*$")


def blocks() -> list:
    """(language, text, first line number of the text) of every fenced block, in order."""
    text = TUTORIAL.read_text()
    return [(m.group(1), m.group(2), text.count("\n", 0, m.start(2)) + 1) for m in BLOCK.finditer(text)]


def _pattern(expected: str) -> re.Pattern:
    """A quoted line as a regex: ``…`` any text, each number a group, the rest literal,
    runs of blanks any run of blanks."""
    parts = []
    for k, piece in enumerate(re.split(rf"((?<![\w.]){NUMBER}|…|\s+)", expected.strip())):
        if k % 2 == 0:
            parts.append(re.escape(piece))
        elif piece == "…":
            parts.append(".*?")
        elif piece.isspace():
            parts.append(r"\s+")
        else:
            parts.append(f"({NUMBER})")
    return re.compile("".join(parts) + r"\s*")


def _close(quoted: str, printed: str) -> bool:
    """Whether ``printed`` rounds to ``quoted`` at the digits ``quoted`` shows."""
    mantissa, _, exponent = quoted.lower().partition("e")
    decimals = len(mantissa.partition(".")[2])
    half_unit = 0.5 * 10.0 ** (int(exponent or 0) - decimals)
    return math.isclose(float(printed), float(quoted), rel_tol=0, abs_tol=half_unit * (1 + 1e-9))


def matches(expected: str, line: str) -> bool:
    m = _pattern(expected).fullmatch(line.strip())
    numbers = re.findall(rf"(?<![\w.]){NUMBER}", expected.replace("…", " "))
    return bool(m) and all(_close(q, p) for q, p in zip(numbers, m.groups()))


def statements(code: str, first_line: int):
    """(compiled statement, the lines it must print or None, its source, its line in the
    page) for each top-level statement."""
    lines = code.splitlines()
    body = ast.parse(code).body
    for k, node in enumerate(body):
        following = body[k + 1].lineno - 1 if k + 1 < len(body) else len(lines)
        expected = []
        trailing = ARROW.search(lines[node.end_lineno - 1])
        if trailing:
            expected.append(trailing.group(1))
        for line in lines[node.end_lineno:following]:
            if line.strip().startswith("#") and ARROW.search(line):
                expected.append(ARROW.search(line).group(1))
        module = ast.Module([node], type_ignores=[])
        ast.increment_lineno(module, first_line - 1)
        source = "\n".join(lines[node.lineno - 1:node.end_lineno])
        yield compile(module, str(TUTORIAL), "exec"), expected or None, source, first_line + node.lineno - 1


def test_the_quoting_rules():
    assert matches("σ = 0.329, λ ≈ 0.574", "σ = 0.32905494, λ ≈ 0.5736331")
    assert not matches("σ = 0.329", "σ = 0.3296")
    assert matches("(-1.694+0.457j) …", "(-1.6938134722590643+0.4569617328362803j) 0.17")
    assert matches("[0 1 2 3 4] (40,)", "[0 1 2 3 4] (40,)")
    assert matches("results.h5  1.2e-10", "results.h5 1.24e-10")
    assert not matches("2,880 DOFs", "2,881 DOFs") and not matches("STABLE", "UNSTABLE")


def test_the_tutorial_runs_as_written(cli, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    namespace: dict = {"__name__": "tutorial"}
    last_output = None
    wrong = []  # every quoted output that differs, reported together
    seen = {"toml": 0, "python": 0, "sh": 0, "text": 0}
    for language, text, first_line in blocks():
        seen[language] = seen.get(language, 0) + 1
        where = f"{TUTORIAL.name}:{first_line}"
        if language == "toml":
            name = re.match(r"# (\S+\.toml)\b", text)
            if name:
                (tmp_path / name.group(1)).write_text(text)
        elif language == "python":
            for code, expected, source, line in statements(text, first_line):
                out = io.StringIO()
                with contextlib.redirect_stdout(out):
                    exec(code, namespace)
                printed = out.getvalue().splitlines()
                if expected is not None and not (len(printed) == len(expected) and all(map(matches, expected, printed))):
                    wrong.append(f"{TUTORIAL.name}:{line}: {source}\nprints\n" + "\n".join(printed) + "\nnot\n" + "\n".join(expected))
        elif language == "sh":
            for line in text.splitlines():
                if not line.startswith("meicp "):
                    continue
                args = shlex.split(line, comments=True)[1:]
                target = None
                if ">" in args:
                    args, target = args[:args.index(">")], args[args.index(">") + 1]
                code, last_output, err = cli(*args)
                assert code == Exit.OK, f"{where}: {line}\n{err}"
                if target:
                    (tmp_path / target).write_text(last_output)
        elif language == "text":
            assert last_output is not None, f"{where}: a text block before any command"
            printed = iter(last_output.splitlines())
            for line in text.splitlines():
                if line.strip() not in ("", "…") and not any(matches(line, p) for p in printed):
                    wrong.append(f"{where}: {line!r} not in the output of the last command (in this order):\n"
                                 f"{last_output}")
                    break
    assert not wrong, "\n\n".join(wrong)
    assert seen["toml"] >= 1 and seen["python"] >= 5 and seen["sh"] >= 2 and seen["text"] >= 1, seen
    # what the text says was written is there
    for path in ("out/scene/results.h5", "out/scene/lattice.xdmf", "out/scene-sweep/sweep.csv",
                 "out/scene-sweep/stability_map.png"):
        assert (tmp_path / path).is_file(), path
