#!/usr/bin/env python3
"""Time of ``meicp.classify`` with its exact (exponential) tests, n = 2 … 12, and of the
sufficient tests above the limit.  Medians of 5 runs after one warm-up.

    .venv/bin/python scripts/bench_classes.py     # -> docs/benchmarks/classes.csv
"""

from __future__ import annotations

import csv
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from meicp.lcp.classes import CLASS_NAMES, classify  # noqa: E402

FAMILIES = {
    # every class true: no early exit, the slowest case for the exact tests
    "all_true": lambda n, rng: np.diag(np.arange(1, n + 1.0)) - 0.1 * np.ones((n, n)),
    "random": lambda n, rng: rng.standard_normal((n, n)),
    "laplacian": lambda n, rng: 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1),
    "rank_one": lambda n, rng: np.outer(rng.standard_normal(n), rng.uniform(0.5, 1.5, n)),
}


def main():
    out = ROOT / "docs" / "benchmarks" / "classes.csv"
    rng = np.random.default_rng(0)
    rows = []
    for n in list(range(2, 13)) + [20, 100, 1000]:
        for family, make in FAMILIES.items():
            M = make(n, rng)
            classify(M)
            times = []
            for _ in range(5):
                t0 = time.perf_counter()
                c = classify(M)
                times.append(time.perf_counter() - t0)
            undecided = sum(getattr(c, k) is None for k in CLASS_NAMES)
            rows.append(dict(n=n, family=family, exact=n <= 12, median_s=f"{statistics.median(times):.4g}",
                             max_s=f"{max(times):.4g}", undecided=undecided))
            print(rows[-1], flush=True)
    tmp = out.with_name(out.name + ".part")
    with tmp.open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    os.replace(tmp, out)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
