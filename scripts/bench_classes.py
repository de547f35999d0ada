#!/usr/bin/env python3
"""Time of ``meicp.classify`` with its exact (exponential) tests, n = 2 … 12, and of the
sufficient tests above the limit.  Medians of 5 runs after one warm-up.

    .venv/bin/python scripts/bench_classes.py     # -> docs/benchmarks/classes.csv
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from bench_common import csv_path, write_rows
from meicp.lcp.classes import CLASS_NAMES, classify

FAMILIES = {
    # every class true: no early exit, the slowest case for the exact tests
    "all_true": lambda n, rng: np.diag(np.arange(1, n + 1.0)) - 0.1 * np.ones((n, n)),
    "random": lambda n, rng: rng.standard_normal((n, n)),
    "laplacian": lambda n, rng: 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1),
    "rank_one": lambda n, rng: np.outer(rng.standard_normal(n), rng.uniform(0.5, 1.5, n)),
}


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", nargs="+", type=int, default=list(range(2, 13)) + [20, 100, 1000])
    args = p.parse_args()
    out = csv_path("classes")
    rng = np.random.default_rng(0)
    rows = []
    for n in args.sizes:
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
    write_rows(out, rows, list(rows[0]), keep=lambda r: False)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
