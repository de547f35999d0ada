#!/usr/bin/env bash
# `make demo`: the main job on a shipped default.  Until the instability pipeline exists
# it shows the install report with a distributed SLEPc solve checked against SciPy (1 and
# 2 ranks), then seed 002's diagnostic workflow on its two worked contact examples:
# classify M (existence / uniqueness guarantees, game value), then solve the LCP.
set -euo pipefail
cd "$(dirname "$0")/.."
MEICP=.venv/bin/meicp
echo "== meicp info --check (1 rank)"
$MEICP info --check
echo
echo "== mpirun -n 2 meicp info --check"
timeout 300 mpirun -n 2 --oversubscribe $MEICP info --check | tail -n 1
for f in data/lcp/seed002_two_point.dat data/lcp/seed002_three_node.dat; do
    echo
    echo "== meicp classify $f"
    $MEICP classify "$f"
    echo
    echo "== meicp lcp $f"
    $MEICP lcp "$f"
done
