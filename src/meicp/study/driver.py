"""``meicp.sweep``: the verdicts of one scene over a range of one parameter.

Each value is one :func:`meicp.analyze` of the scene changed by
:func:`~meicp.study.parameters.scene_with`.  Under ``mpirun`` the values are shared out:

- ``per_point_comm="split"`` (default below :data:`~meicp.core.limits.SWEEP_SPLIT_DOFS`
  DOFs): each rank analyses its own values alone, P values at a time in rounds (value k of
  the round on rank k), and rank 0 gathers each round's rows (mpi4py) and writes them; a
  round lasts as long as its slowest value.
- ``"world"`` (from that size on): every value on all ranks together, one after another.

Rank 0 alone writes, into ``out``: ``sweep.csv`` one row per value, appended and flushed as
each round ends, so a run that is stopped keeps what it finished; ``sweep.json`` the summary
(written when the run starts, with the *fingerprint* of the scene and the options, and again
at the end with the onsets); ``stability_map.png``.  Run again into the same ``out``, a
sweep with the same fingerprint skips the values sweep.csv already has (``resume=True``);
another scene or other options start over, and say so.
"""

from __future__ import annotations

import hashlib
import inspect
import json
import logging
import os
import sys
import time
from pathlib import Path

from .._version import __version__
from ..api import analyze
from ..core import limits
from ..core.comm import mpi_comm, world_if_none
from ..core.errors import MeicpError, ProblemError
from ..contact.flutter import flutter_asked
from ..contact.instability import REFUSED_OPTIONS
from ..core.json_values import FORMAT_VERSION
from ..core.progress import duration
from ..core.validation import check_keywords
from ..io.results_records import scene_to_toml
from .. import petsc
from ..io.scene import as_scene
from ..scene import Scene
from .parameters import _canonical, describe, is_friction, parse_values, scene_with
from .result import SweepResult, SweepRow, append_csv, read_rows, write_csv

log = logging.getLogger("meicp")

#: the files of a sweep's output directory
CSV, JSON, PNG = "sweep.csv", "sweep.json", "stability_map.png"
#: what ``per_point_comm`` may be
PER_POINT = ("auto", "split", "world")
#: keywords the sweep sets itself: not passed on to ``analyze``
RESERVED = ("comm", "scene_path")
#: the options a sweep hands on to every ``analyze``
ANALYZE_OPTIONS = frozenset(inspect.signature(analyze).parameters) - {"scene", "comm"}


def sweep(scene, parameter: str = "friction", values=None, *, out=None, comm=None, resume: bool = True,
          flutter: bool | None = None, progress: bool = True, per_point_comm: str = "auto",
          **analyze_options) -> SweepResult:
    """The verdicts of ``scene`` over a range of one parameter (module docstring).

    Parameters
    ----------
    scene : Scene or path
        The scene (a :class:`~meicp.scene.Scene` or a scene file).
    parameter : str
        What to vary: ``"friction"`` (every frictional contact), ``"contact.friction"``,
        ``"interfaces.NAME.friction"``, ``"layers.NAME.stiffness"``, ``"layers.NAME.density"``,
        ``"shear"``, ``"compression"``, ``"gravity"``, ``"lattice.shear"``
        (:mod:`meicp.study.parameters`).
    values : str or sequence of float
        ``"A:B:N"`` (N values from A to B), ``"0.5,1,2"`` or numbers.
    out : str or Path, optional
        Directory to write sweep.csv, sweep.json and stability_map.png into (created if
        missing); None writes nothing (and resumes nothing).
    comm : mpi4py communicator, optional
        The ranks to share the values among; None: ``COMM_WORLD`` under ``mpirun`` (several
        ranks), else this process alone.
    resume : bool
        Skip the values ``out``'s sweep.csv already has, when it was written for the same scene
        and options; False starts over.
    flutter : bool, optional
        Decide flutter too (default: the scene's ``[solver] flutter``, true).
    progress : bool
        One line per finished value on stderr (rank 0).
    per_point_comm : {"auto", "split", "world"}
        ``split``: each rank analyses its own values alone; ``world``: every value on all
        ranks; ``auto``: split below :data:`~meicp.core.limits.SWEEP_SPLIT_DOFS` DOFs.
    **analyze_options
        Passed to :func:`meicp.analyze` for every value (``method``, ``tol``, ...).

    Returns
    -------
    SweepResult
        The same on every rank: a row per value, sorted by value (with the values an earlier
        run left in ``out`` when resumed), the onsets the grid brackets, the files written.

    Raises
    ------
    ProblemError
        A bad key, value, grid or option, or an ``out`` that cannot be written — before any
        analysis; or an analysis that refuses its scene (on every rank alike).
    """
    t0 = time.perf_counter()
    scene = as_scene(scene)
    if not isinstance(scene, Scene):
        raise ProblemError(f"scene must be a Scene or a scene file, got {type(scene).__name__}")
    if values is None:
        raise ProblemError("values: none given (e.g. values='0:3:31' or [0.5, 1, 2])")
    key = _canonical(scene, parameter)
    values = [float(v) for v in parse_values(values)]
    scenes = [scene_with(scene, key, v) for v in values]  # every value checked before any work
    reserved = sorted(set(analyze_options) & set(RESERVED))
    if reserved:
        raise ProblemError(f"sweep sets {reserved[0]!r} itself: pass comm=... to sweep, not to analyze")
    # a misspelt analyze option is refused here, as analyze refuses it, not at the first value
    # with a sweep.json left saying "running"
    check_keywords("sweep", analyze_options, ANALYZE_OPTIONS, REFUSED_OPTIONS)
    flutter = flutter_asked(scene, flutter)
    if per_point_comm not in PER_POINT:
        raise ProblemError(f"per_point_comm must be one of {', '.join(PER_POINT)}, got {per_point_comm!r}")
    comm = _communicator(comm)
    ranks = 1 if comm is None else comm.Get_size()
    mode = per_point_comm
    if mode == "auto":
        mode = "split" if scene.n_dofs < limits.SWEEP_SPLIT_DOFS else "world"
    options = dict(analyze_options, flutter=flutter)
    run = _Run(scene, key, values, out, comm, options, progress, mode, t0)
    done = run.start(resume)
    todo = [k for k, v in enumerate(values) if v not in done]
    if mode == "split" or ranks == 1:
        run.split(todo, scenes)
    else:
        run.world(todo, scenes)
    return run.finish(done)


def _communicator(comm):
    """``comm`` made canonical; None means ``COMM_WORLD``, as for :func:`meicp.analyze` (a
    sweep on every rank alone would write one directory from each)."""
    return mpi_comm(world_if_none(comm))


def fingerprint(scene: Scene, key: str, options: dict) -> str:
    """What a resumed sweep must share with the run that wrote sweep.csv: the scene (as its
    TOML record, wherever it was read from), the key and the analysis options."""
    text = json.dumps({"scene": scene_to_toml(scene), "parameter": key, "options": options},
                      sort_keys=True, default=repr)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]


class _Run:
    """One sweep's state: the communicator, the output directory (rank 0), progress."""

    def __init__(self, scene, key, values, out, comm, options, progress, mode, t0):
        self.scene, self.key, self.values, self.comm, self.options = scene, key, values, comm, options
        self.out = None if out is None else Path(out)
        self.rank = 0 if comm is None else comm.Get_rank()
        self.ranks = 1 if comm is None else comm.Get_size()
        self.progress, self.mode, self.t0 = progress, mode, t0
        self.print_rows = progress and self.rank == 0
        self.fingerprint = fingerprint(scene, key, options)
        self.name = scene.title or (Path(scene.source).stem if scene.source else "scene")
        self.new, self.file, self.resumed, self.finished = [], None, 0, 0
        self.total = len(values)

    # -- collective helpers ----------------------------------------------------------------------
    def _bcast(self, value):
        return value if self.comm is None else self.comm.bcast(value, root=0)

    def _on_root(self, work):
        """``work()`` on rank 0, its value broadcast; its error raised on every rank (an OSError
        as bad input: the output directory cannot be written)."""
        error, value = None, None
        if self.rank == 0:
            try:
                value = work()
            except ProblemError as exc:
                error = ("problem", str(exc))
            except OSError as exc:
                error = ("problem", f"cannot write the sweep into {str(self.out)!r}: {exc.strerror or exc}")
            except Exception as exc:  # noqa: BLE001 - said on every rank, never a hang
                error = ("internal", f"{type(exc).__name__}: {exc}")
        error, value = self._bcast((error, value))
        self._raise(error)
        return value

    def say(self, text: str) -> None:
        if self.print_rows:
            print(f"meicp sweep: {text}", file=sys.stderr, flush=True)

    # -- the output directory --------------------------------------------------------------------
    def start(self, resume: bool) -> dict:
        """Rank 0 reads what ``out`` holds and prepares sweep.csv; every rank gets the rows
        already done, by value."""
        if self.out is None:
            return {}
        done = self._on_root(lambda: self._prepare(resume))
        self.resumed = sum(v in done for v in self.values)
        if self.resumed:
            self.say(f"resuming: {self.resumed} of {self.total} value(s) already in {self.out / CSV}")
        return done

    def _prepare(self, resume: bool) -> dict:
        out = self.out
        if out.exists() and not out.is_dir():
            raise ProblemError(f"output path {str(out)!r} exists and is not a directory")
        out.mkdir(parents=True, exist_ok=True)
        rows, bad = read_rows(out / CSV)
        earlier = _read_json(out / JSON).get("fingerprint")
        if rows and not resume:
            self.say(f"starting over (--no-resume): {len(rows)} row(s) of {out / CSV} replaced")
            rows = []
        elif rows and earlier != self.fingerprint:
            log.warning(f"{out / CSV} was written for another scene, parameter or options: starting over")
            rows = []
        elif bad:
            log.warning(f"{out / CSV}: {bad} unreadable record(s) dropped (a run stopped mid-write); "
                        "their values are analysed again")
        write_csv(out / CSV, sorted(rows, key=lambda r: r.value))
        self._write_json({**self.metadata(), "state": "running"})
        self.file = open(out / CSV, "a", newline="", encoding="utf-8")
        return {r.value: r for r in rows}

    def _write_json(self, doc: dict) -> Path:
        path = self.out / JSON
        tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
        tmp.write_text(json.dumps(doc, indent=1, ensure_ascii=False, allow_nan=False) + "\n", encoding="utf-8")
        os.replace(tmp, path)
        return path

    def metadata(self) -> dict:
        """What sweep.json says of the run: format, version, fingerprint, scene, options."""
        scene = self.scene
        return {"format": "meicp-sweep", "format_version": FORMAT_VERSION, "meicp_version": __version__,
                "fingerprint": self.fingerprint,
                "scene": {"source": scene.source, "title": scene.title, "nx": scene.nx, "ny": scene.ny,
                          "dofs": scene.n_dofs},
                "parameter": self.key, "options": json.loads(json.dumps(self.options, default=repr)),
                "ranks": self.ranks, "per_point_comm": self.mode}

    # -- the analyses ----------------------------------------------------------------------------
    def _analyze(self, k: int, scene, comm):
        """``(row, None)`` or ``(None, (kind, text))`` for an error every rank must raise."""
        t = time.perf_counter()
        try:
            result = analyze(scene, comm, **self.options)
        except ProblemError as exc:
            return None, ("problem", f"{self.key} = {self.values[k]:g}: {exc}")
        except MeicpError as exc:  # a solver gave up: this value has no answer, the others may
            return SweepRow.failed(self.values[k], f"{type(exc).__name__}: {exc}", time.perf_counter() - t), None
        except Exception as exc:  # noqa: BLE001 - said on every rank, never a hang
            return None, ("internal", f"{self.key} = {self.values[k]:g}: {type(exc).__name__}: {exc}")
        return SweepRow.of(self.values[k], result, time.perf_counter() - t), None

    def split(self, todo: list, scenes: list) -> None:
        """Each rank its own values, in rounds of one value per rank; rank 0 writes each round."""
        # a rank that never analyses a value (fewer values than ranks) must start PETSc too:
        # its finalisation is collective, the job aborted at exit ("stack smashing detected")
        petsc.start()
        for start in range(0, len(todo), self.ranks):
            mine = todo[start + self.rank] if start + self.rank < len(todo) else None
            # this rank alone: None would be every rank (COMM_WORLD), each with another scene
            outcome = None if mine is None else (mine, *self._analyze(mine, scenes[mine], _alone()))
            gathered = [outcome] if self.comm is None else self.comm.gather(outcome, root=0)
            error = None
            if self.rank == 0:
                error = next((e for item in gathered if item is not None for e in [item[2]] if e), None)
                for item in gathered:
                    if item is not None and item[1] is not None:
                        self._record(item[1])
            self._raise(self._bcast(error))

    def world(self, todo: list, scenes: list) -> None:
        """Every value on all ranks together."""
        for k in todo:
            row, error = self._analyze(k, scenes[k], self.comm)
            self._raise(error)
            if self.rank == 0:
                self._record(row)

    def _raise(self, error) -> None:
        if error is None:
            return
        self._close()
        kind, text = error
        if kind == "problem":
            raise ProblemError(text)
        raise RuntimeError(text)

    def _record(self, row: SweepRow) -> None:
        self.new.append(row)
        if self.file is not None:
            append_csv(self.file, row)
        self.finished += 1
        count = self.finished + self.resumed
        elapsed = time.perf_counter() - self.t0
        left = elapsed / self.finished * (self.total - count)
        self.say(f"{count}/{self.total} {row.line(self.key)}"
                 + (f"; about {duration(left)} left" if count < self.total and left >= 1 else ""))

    def _close(self) -> None:
        if self.file is not None:
            self.file.close()
            self.file = None

    # -- the end ---------------------------------------------------------------------------------
    def finish(self, done: dict) -> SweepResult:
        """Rank 0 sorts every row, rewrites sweep.csv, draws the map, writes sweep.json; every
        rank returns the same result."""
        result = None
        if self.rank == 0:
            self._close()
            rows = {**done, **{r.value: r for r in self.new}}
            result = SweepResult(self.key, describe(self.scene, self.key),
                                 sorted(rows.values(), key=lambda r: r.value), self.name, self.resumed,
                                 is_friction(self.key), run=self.metadata())
            result.run["seconds"] = time.perf_counter() - self.t0
        if self.out is not None:
            return self._on_root(lambda: self._write(result))
        return self._bcast(result)

    def _write(self, result: SweepResult) -> SweepResult:
        out = self.out
        result.files = {"csv": write_csv(out / CSV, result.rows)}
        try:
            result.files["png"] = result.plot(out / PNG)
        except Exception as exc:  # noqa: BLE001 - a picture that fails leaves the table and summary
            log.warning(f"stability map not drawn: {type(exc).__name__}: {exc}")
        result.files["json"] = out / JSON
        self._write_json({**result.to_dict(), "state": "complete"})
        return result


def _read_json(path: Path) -> dict:
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return doc if isinstance(doc, dict) else {}


def _alone():
    """This process's own communicator (``MPI.COMM_SELF``)."""
    from mpi4py import MPI

    return MPI.COMM_SELF
