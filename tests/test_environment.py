"""A Python without Debian's stack gets a message saying what is missing and how to set
up, not a traceback; the licence and the typing marker ship with the package."""

import subprocess
import sys
import tomllib

from meicp.core.environment import MissingDependency, numpy_mismatch

from .conftest import ROOT, clean_env

#: what the console script `meicp` does, with some modules made unimportable first
CONSOLE = ("import sys\n"
           "for m in {blocked!r}: sys.modules[m] = None\n"
           "sys.argv = ['meicp', 'info']\n"
           "from meicp.cli.main import main\n"
           "sys.exit(main())\n")


def _run(python, *args, blocked=()):
    code = CONSOLE.format(blocked=list(blocked))
    env = dict(clean_env(), PYTHONPATH=str(ROOT / "src"))
    return subprocess.run([str(python), *(args or ("-c", code))], capture_output=True, text=True,
                          timeout=60, env=env, cwd=ROOT)


def _assert_told(out, *words):
    assert out.returncode == 1 and "Traceback" not in out.stderr, out.stderr
    for word in words + ("make setup",):
        assert word in out.stderr, out.stderr


def test_plain_venv_is_told_what_is_missing(tmp_path):
    """A venv without Debian's site-packages (the state `pip install` users end up in)."""
    subprocess.run(["/usr/bin/python3", "-m", "venv", "--without-pip", str(tmp_path / "v")], check=True)
    python = tmp_path / "v" / "bin" / "python"
    for args in (("-m", "meicp", "info"), ("-c", "import meicp")):
        _assert_told(_run(python, *args), "numpy is missing (Debian package python3-numpy)",
                     "mpi4py is missing", "--system-site-packages")


def test_console_run_without_numpy_prints_the_message_alone():
    _assert_told(_run(sys.executable, blocked=["numpy"]), "numpy is missing")


def test_a_library_caller_can_catch_it():
    code = ("import sys; sys.modules['scipy'] = None\n"
            "try:\n    import meicp\n"
            "except ImportError as exc:\n    print(type(exc).__name__, 'scipy is missing' in str(exc))\n")
    out = _run(sys.executable, "-c", code)
    assert out.returncode == 0 and out.stdout.split() == ["MissingDependency", "True"], out.stderr


def test_missing_petsc_bindings_are_named_by_the_cli():
    out = _run(sys.executable, blocked=["petsc4py", "slepc4py"])
    _assert_told(out, "petsc4py is missing (Debian package python3-petsc4py-real)", "slepc4py is missing")


def test_numpy_2_cannot_load_debians_petsc4py():
    debian = "/usr/lib/petscdir/petsc3.18/x86_64-linux-gnu-real/lib/python3/dist-packages/petsc4py/__init__.py"
    assert "numpy 2.1.0 is installed" in numpy_mismatch("2.1.0", debian)
    assert numpy_mismatch("1.24.2", debian) is None
    assert numpy_mismatch("2.1.0", "/opt/venv/lib/python3.11/site-packages/petsc4py/__init__.py") is None
    assert issubclass(MissingDependency, ImportError)


def test_licence_and_typing_marker_ship():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert project["project"]["license"] == {"text": "BSD-3-Clause"}
    assert (ROOT / "LICENSE").read_text().startswith("BSD 3-Clause License")
    assert "py.typed" in project["tool"]["setuptools"]["package-data"]["meicp"]
    assert (ROOT / "src" / "meicp" / "py.typed").is_file()


def test_missing_mpi4py_is_named_before_mpi_starts():
    _assert_told(_run(sys.executable, blocked=["mpi4py"]), "mpi4py is missing")


def test_petsc_runs_with_the_stack_limit_raised_to_the_hard_one():
    """MUMPS recurses over the elimination tree: a long, shallow lattice crashed under the
    default 8 MB (docs/benchmarks-notes.md, "stack limit")."""
    import resource

    from meicp.petsc import import_petsc

    import_petsc()
    soft, hard = resource.getrlimit(resource.RLIMIT_STACK)
    assert soft == hard or soft == resource.RLIM_INFINITY
