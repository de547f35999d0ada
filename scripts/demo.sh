#!/usr/bin/env bash
# `make demo`: the main job on a shipped default.  Until the instability pipeline exists
# this shows the install report and a distributed SLEPc solve checked against SciPy,
# on 1 and on 2 ranks.
set -euo pipefail
cd "$(dirname "$0")/.."
echo "== meicp info --check (1 rank)"
.venv/bin/meicp info --check
echo
echo "== mpirun -n 2 meicp info --check"
timeout 300 mpirun -n 2 --oversubscribe .venv/bin/meicp info --check
