#!/usr/bin/env bash
# `make demo`: the main job on the shipped default scene, then the diagnostics around it.
#  1. the install report, with a distributed SLEPc solve checked against SciPy;
#  2. `mpirun -n 2 meicp solve data/scenes/two_layers.toml`: two layers on a rough base,
#     all base nodes sliding at μ = 3 — the divergence modes, their certificates, the
#     critical friction, and results.h5 / lattice.xdmf / PNGs in out/two_layers;
#  3. the same lattice at μ = 1.5 (below μ_c): stable, with the enumeration's proof;
#  4. seed 002's workflow on its worked LCP examples: classify M, then solve.
set -euo pipefail
cd "$(dirname "$0")/.."
MEICP=.venv/bin/meicp
MPIRUN="timeout 600 mpirun -n 2 --oversubscribe"
echo "== meicp info --check"
$MEICP info --check | tail -n 12
echo
echo "== mpirun -n 2 meicp solve data/scenes/two_layers.toml --critical-friction -o out/two_layers"
$MPIRUN $MEICP solve data/scenes/two_layers.toml --critical-friction -o out/two_layers
echo
echo "== mpirun -n 2 meicp solve data/scenes/two_layers_below_mu_c.toml --no-output -q"
$MPIRUN $MEICP solve data/scenes/two_layers_below_mu_c.toml --no-output -q
echo
echo "== seed 002: classify, then solve, the three-node contact LCP"
$MEICP classify data/lcp/seed002_three_node.dat | tail -n 12
$MEICP lcp data/lcp/seed002_three_node.dat
