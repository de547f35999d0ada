"""The benchmark scripts' one way of writing results: CSV rows appended to what is kept
of the file, written under a temporary name and renamed (never half-written), in one
directory: ``$MEICP_BENCH_DIR`` if set (``make bench`` quick mode: ``build/benchmarks``),
else ``docs/benchmarks`` (the committed full-mode results)."""

from __future__ import annotations

import csv
import os
from pathlib import Path


ROOT = Path(__file__).resolve().parents[1]


def out_dir() -> Path:
    """Where CSVs and charts go (created if missing)."""
    d = Path(os.environ.get("MEICP_BENCH_DIR") or ROOT / "docs" / "benchmarks")
    d.mkdir(parents=True, exist_ok=True)
    return d


def csv_path(name: str) -> Path:
    """``out_dir() / f"{name}.csv"``: the CSV of benchmark ``name`` (also its chart's name)."""
    return out_dir() / f"{name}.csv"


def write_rows(path, rows: list, fields: list, keep=lambda row: True) -> None:
    """Write ``rows`` after the existing rows for which ``keep(row)`` is true."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    kept = []
    if path.exists():
        with path.open(newline="") as f:
            kept = [r for r in csv.DictReader(f) if keep(r)]
    tmp = path.with_name(path.name + ".part")
    with tmp.open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields)
        w.writeheader()
        w.writerows(kept + rows)
    os.replace(tmp, path)
