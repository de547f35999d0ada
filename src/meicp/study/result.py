"""What a sweep returns (:class:`SweepResult`): one :class:`SweepRow` per value, the onsets
the grid brackets (:class:`Onset`), and the files — ``sweep.csv`` (one row per value, the
format :func:`read_rows` reads back to resume), ``sweep.json`` (the summary) and the
stability map PNG (:func:`meicp.plotting.stability_map.plot_stability_map`)."""

from __future__ import annotations

import csv
import io
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

from ..contact.result import seconds
from ..plotting.stability_map import plot_stability_map

#: the columns of sweep.csv, in order
COLUMNS = ("value", "verdict", "stable", "divergence", "sigma", "growth", "flutter", "flutter_growth",
           "flutter_growth_bound", "flutter_frequency", "status", "seconds", "evidence")
#: the longest evidence kept in a row (the whole text is in `meicp solve`'s results)
EVIDENCE_CHARS = 160


@dataclass(frozen=True)
class SweepRow:
    """The verdicts of one value of a sweep (``meicp.analyze`` of the changed scene).

    value: the parameter's value.  divergence, flutter, stable: True / False / None
    (undecided) as in :class:`~meicp.contact.result.InstabilityResult`.  sigma: σ = λ² of
    the fastest divergence mode found (None without one; the fastest only where every support
    was enumerated, a search finds some); growth: λ = √σ.  flutter_growth: Re λ of
    the fastest flutter mode *found* — a lower bound on the fastest; flutter_growth_bound:
    an upper bound on every flutter mode's Re λ when the whole spectrum proves one (0 when
    flutter is excluded), else None (the search's Bendixson bound, proved but loose, is in
    the analysis' ``flutter_growth``, not here: the chart would read it as the fastest);
    flutter_frequency: |Im λ| of the mode found.  status:
    the analysis' (``solved``, ``inconclusive``, ``failed`` when it raised).  seconds: its
    wall time.  evidence: what decided each verdict, shortened."""

    value: float
    verdict: str
    stable: bool | None
    divergence: bool | None
    sigma: float | None
    flutter: bool | None
    flutter_growth: float | None
    flutter_growth_bound: float | None
    flutter_frequency: float | None
    status: str
    seconds: float
    evidence: str

    @property
    def growth(self) -> float | None:
        return None if self.sigma is None else math.sqrt(max(self.sigma, 0.0))

    @classmethod
    def of(cls, value: float, result, elapsed: float) -> SweepRow:
        """The row of an :class:`~meicp.contact.result.InstabilityResult`."""
        fast = result.flutter_modes[0] if result.flutter_modes else None
        tests = "+".join(sorted({p.test for p in result.proofs if p.test})) or "no proof"
        evidence = f"divergence: {tests}; flutter: {_flutter_evidence(result)}"
        return cls(value=float(value), verdict=result.verdict, stable=result.stable, divergence=result.divergence,
                   sigma=float(result.modes[0].sigma) if result.modes else None, flutter=result.flutter,
                   flutter_growth=fast.growth_rate if fast else None,
                   flutter_growth_bound=(None if result.flutter_growth is None or result.flutter_growth.loose
                                         else result.flutter_growth.upper),
                   flutter_frequency=fast.frequency if fast else None, status=result.status,
                   seconds=float(elapsed), evidence=evidence[:EVIDENCE_CHARS])

    @classmethod
    def failed(cls, value: float, message: str, elapsed: float) -> SweepRow:
        """The row of an analysis that raised (a solver failure, not bad input)."""
        return cls(float(value), "FAILED", None, None, None, None, None, None, None, "failed", float(elapsed),
                   message[:EVIDENCE_CHARS])

    def csv_fields(self) -> dict:
        out = {}
        for name in COLUMNS:
            v = getattr(self, name)
            out[name] = "" if v is None else repr(float(v)) if isinstance(v, float) else str(v)
        return out

    @classmethod
    def from_csv(cls, record: dict) -> SweepRow:
        """The row of a CSV record (:meth:`csv_fields`); ValueError when it is not one."""
        def flag(name):
            return {"True": True, "False": False, "": None}[record[name]]

        def number(name):
            return None if record[name] == "" else float(record[name])

        return cls(value=float(record["value"]), verdict=record["verdict"], stable=flag("stable"),
                   divergence=flag("divergence"), sigma=number("sigma"), flutter=flag("flutter"),
                   flutter_growth=number("flutter_growth"), flutter_growth_bound=number("flutter_growth_bound"),
                   flutter_frequency=number("flutter_frequency"), status=record["status"],
                   seconds=float(record["seconds"]), evidence=record["evidence"])

    def line(self, key: str) -> str:
        """One line for a person: the verdicts of this value."""
        div = {True: f"divergence σ = {self.sigma:.6g}" if self.sigma is not None else "divergence",
               False: "no divergence"}.get(self.divergence, "divergence undecided")
        flu = {True: "flutter", False: "no flutter"}.get(self.flutter, "flutter undecided")
        if self.flutter and self.flutter_growth is not None:
            flu += f" growth ≥ {self.flutter_growth:.6g}"
            if self.flutter_growth_bound is not None:
                flu += f", ≤ {self.flutter_growth_bound:.6g}"
        return f"{key} = {self.value:g}: {self.verdict} ({div}, {flu}) in {seconds(self.seconds)}"


def _flutter_evidence(result) -> str:
    text = result.flutter_evidence
    if text.startswith("not analysed"):
        return "not analysed"
    if "symmetric" in text and "a proof" in text and not result.flutter_modes:
        return "symmetry (a proof)"
    path = "dense spectrum" if "dense" in text else "shift-invert search" if "shift-and-invert" in text else "?"
    return path + (" (a proof)" if result.flutter is not None and "a proof" in text else
                   " (certified mode)" if result.flutter else " (undecided)")


def write_csv(path, rows) -> Path:
    """``rows`` to the CSV ``path`` in one piece (a temporary file renamed over it)."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        with open(tmp, "w", newline="", encoding="utf-8") as f:
            writer = csv.DictWriter(f, fieldnames=COLUMNS)
            writer.writeheader()
            writer.writerows(row.csv_fields() for row in rows)
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
    return path


def append_csv(f, row: SweepRow) -> None:
    """One row onto an open CSV file, flushed: a run that ends here keeps it."""
    buffer = io.StringIO()
    csv.DictWriter(buffer, fieldnames=COLUMNS).writerow(row.csv_fields())
    f.write(buffer.getvalue())
    f.flush()


def read_rows(path) -> tuple[list[SweepRow], int]:
    """``(rows, unreadable)``: the rows of a sweep.csv and how many records were not rows (a
    line cut short when a run was killed mid-write); ``([], 0)`` without the file."""
    path = Path(path)
    if not path.is_file():
        return [], 0
    rows, bad = [], 0
    with open(path, newline="", encoding="utf-8") as f:
        reader = csv.DictReader(f)
        if tuple(reader.fieldnames or ()) != COLUMNS:
            return [], 1
        for record in reader:
            try:
                if None in record or any(v is None for v in record.values()):
                    raise ValueError("short record")
                rows.append(SweepRow.from_csv(record))
            except (ValueError, KeyError):
                bad += 1
    return rows, bad


@dataclass(frozen=True)
class Onset:
    """Where one instability starts along a sweep's grid.

    kind: ``"divergence"`` or ``"flutter"``.  upper: the first value at which it is
    certified (None: nowhere on the grid).  lower: the last value below ``upper`` at which
    its absence is proved (None: none — it is certified at the grid's first value, or
    undecided everywhere below).  A bracket from the grid, not a proof that nothing happens
    between grid points (an instability may come and go between two values)."""

    kind: str
    lower: float | None
    upper: float | None
    symbol: str = ""

    @classmethod
    def of(cls, kind: str, rows, symbol: str = "") -> Onset:
        rows = sorted(rows, key=lambda r: r.value)
        flags = [getattr(r, kind) for r in rows]
        first = next((k for k, f in enumerate(flags) if f is True), None)
        if first is None:
            return cls(kind, None, None, symbol)
        lower = next((rows[k].value for k in range(first - 1, -1, -1) if flags[k] is False), None)
        return cls(kind, lower, rows[first].value, symbol)

    @property
    def name(self) -> str:
        return self.symbol or f"{self.kind} onset"

    def describe(self) -> str:
        if self.upper is None:
            return f"{self.name}: no {self.kind} certified on the grid"
        if self.lower is None:
            return (f"{self.name} ≤ {self.upper:g}: {self.kind} certified at {self.upper:g}, not proved absent at "
                    "any grid value below it")
        return (f"{self.name} ∈ ({self.lower:g}, {self.upper:g}]: {self.kind} proved absent at {self.lower:g}, "
                f"certified at {self.upper:g} (a bracket from the sweep grid: not a proof that nothing happens "
                "between grid points)")

    def to_dict(self) -> dict:
        return {"lower": self.lower, "upper": self.upper, "statement": self.describe()}


@dataclass
class SweepResult:
    """What :func:`meicp.sweep` returns.

    parameter: the key swept (:func:`~meicp.study.parameters.parameter_keys`); description:
    what it changes.  rows: one :class:`SweepRow` per value, sorted by value — the values
    asked for and, when ``out`` held an earlier run of the same scene and options, that
    run's other values too (sweep.csv keeps every value computed).  resumed: how many rows
    came from that earlier run.  scene_name: for titles.  run: the run's record (format,
    meicp version, fingerprint, scene, options, ranks, seconds).  files: the paths written
    (``csv``, ``json``, ``png``), empty without ``out``.  divergence_onset, flutter_onset:
    :class:`Onset` brackets from the grid (μ_c and μ_f when the parameter is a friction).
    """

    parameter: str
    description: str
    rows: list = field(default_factory=list)
    scene_name: str = "scene"
    resumed: int = 0
    friction: bool = False
    run: dict = field(default_factory=dict)
    files: dict = field(default_factory=dict)

    @property
    def values(self) -> list[float]:
        return [r.value for r in self.rows]

    @property
    def divergence_onset(self) -> Onset:
        return Onset.of("divergence", self.rows, "μ_c" if self.friction else "")

    @property
    def flutter_onset(self) -> Onset:
        return Onset.of("flutter", self.rows, "μ_f" if self.friction else "")

    @property
    def counts(self) -> dict:
        """Rows per verdict: stable, unstable, undecided, failed."""
        out = {"stable": 0, "unstable": 0, "undecided": 0, "failed": 0}
        for r in self.rows:
            key = "failed" if r.status == "failed" else {True: "stable", False: "unstable"}.get(r.stable, "undecided")
            out[key] += 1
        return out

    def to_csv(self, path) -> Path:
        """Write the rows to the CSV ``path`` (the columns of :data:`COLUMNS`)."""
        return write_csv(path, self.rows)

    def plot(self, path, *, title: str | None = None, marks=()) -> Path:
        """Draw the stability map to the PNG ``path``: growth rates against the parameter, the
        onsets shaded as grid brackets; ``marks``: extra ``(value, label)`` vertical lines."""
        onsets = [o for o in (self.divergence_onset, self.flutter_onset) if o.upper is not None]
        return plot_stability_map(
            path, [r.value for r in self.rows], divergence=[r.divergence for r in self.rows],
            growth=[r.growth for r in self.rows], flutter=[r.flutter for r in self.rows],
            flutter_growth=[r.flutter_growth for r in self.rows],
            flutter_bound=[r.flutter_growth_bound for r in self.rows],
            onsets=[(o.kind, o.lower, o.upper, o.name) for o in onsets],
            xlabel=self.description, title=title or f"{self.scene_name}: stability against {self.parameter}",
            marks=marks)

    def to_dict(self) -> dict:
        """The summary as JSON-ready values (sweep.json, ``meicp sweep --json``): the run's
        record, parameter, counts, onsets, rows, files."""
        return {**self.run, "parameter": self.parameter, "description": self.description, "values": len(self.rows),
                "resumed": self.resumed, "counts": self.counts,
                "onsets": {"divergence": self.divergence_onset.to_dict(), "flutter": self.flutter_onset.to_dict()},
                "rows": [_json_row(r) for r in self.rows],
                "files": {k: str(v) for k, v in self.files.items()}}

    def summary(self) -> str:
        """The rows and onsets as lines for a person."""
        lines = [f"{self.scene_name}: {len(self.rows)} value(s) of {self.parameter} ({self.description})"]
        lines += ["  " + r.line(self.parameter) for r in self.rows]
        lines += ["  " + self.divergence_onset.describe(), "  " + self.flutter_onset.describe()]
        return "\n".join(lines)

    def __repr__(self) -> str:
        c = self.counts
        span = f"{self.rows[0].value:g}…{self.rows[-1].value:g}" if self.rows else "no values"
        onsets = "; ".join(_short(o) for o in (self.divergence_onset, self.flutter_onset))
        return (f"SweepResult({self.parameter} {span}, {len(self.rows)} values: {c['stable']} stable, "
                f"{c['unstable']} unstable, {c['undecided']} undecided, {c['failed']} failed; {onsets})")


def _short(onset: Onset) -> str:
    if onset.upper is None:
        return f"{onset.name}: none"
    return f"{onset.name} ∈ ({'?' if onset.lower is None else f'{onset.lower:g}'}, {onset.upper:g}]"


def _json_row(row: SweepRow) -> dict:
    out = {name: getattr(row, name) for name in COLUMNS}
    out["growth"] = row.growth
    return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in out.items()}
