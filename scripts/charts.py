#!/usr/bin/env python3
"""Charts from the benchmark CSVs (docs/benchmarks.md).  One function ``chart_NAME`` per benchmark
``scripts/bench_NAME.py`` (in ``charts_solvers.py`` or ``charts_lattice.py``, by family); it reads
``NAME.csv`` and writes its PNGs beside it:

    .venv/bin/python scripts/charts.py lcp docs/benchmarks/lcp.csv
"""

import sys

import charts_lattice
import charts_solvers

#: benchmark name → its chart function (``chart_NAME`` in either family's module)
CHARTS = dict(sorted((name[len("chart_"):], f) for module in (charts_solvers, charts_lattice)
                     for name, f in vars(module).items() if name.startswith("chart_")))


if __name__ == "__main__":
    if len(sys.argv) != 3 or sys.argv[1] not in CHARTS:
        sys.exit(f"usage: charts.py {{{','.join(CHARTS)}}} CSV")
    CHARTS[sys.argv[1]](sys.argv[2])
