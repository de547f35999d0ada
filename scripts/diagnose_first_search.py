#!/usr/bin/env python3
"""How many Krylov–Schur restarts the divergence search's eigen-solves take (issue 14): for
two-layer scenes, the verdict, its test and, per search, (modes found, restarts) from the
INFO log — the evidence behind ``divergence.FIRST_EPS_MAX_IT``.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python scripts/diagnose_first_search.py

Prints one line per scene: nx, rows, state, shear, μ, divergence, test, [(modes, restarts) per
search], seconds."""
import io
import logging
import re
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_scenes import two_layer_scene  # noqa: E402

import meicp  # noqa: E402

buf = io.StringIO()
handler = logging.StreamHandler(buf)
handler.setLevel(logging.INFO)
log = logging.getLogger("meicp")
log.setLevel(logging.INFO)
log.addHandler(handler)
for nx, rows in [(200, (10, 10)), (400, (20, 20)), (300, (75, 75))]:
    for state in ("slip-", "slip+"):
        for shear in (0.5, -0.5):
            for mu in (0.6, 1.5, 3.0, 6.0):
                buf.truncate(0)
                buf.seek(0)
                t = time.perf_counter()
                r = meicp.analyze(two_layer_scene(nx, rows, mu=mu, states=state, shear=shear), flutter=False)
                t = time.perf_counter() - t
                found = re.findall(r"search from σ = \S+, (\d+) mode\(s\), (\S+) Krylov", buf.getvalue())
                print(nx, rows, state, shear, mu, r.divergence, r.proofs[0].get("test"), found, f"{t:.1f}s",
                      flush=True)
