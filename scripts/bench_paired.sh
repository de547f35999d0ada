#!/usr/bin/env bash
# Paired cost runs of two checkouts on the 10⁶-DOF benchmark, alternating (BEFORE first each
# round), so that a restructuring is measured against the code before it on the same machine
# state.  Each run is `bench_verdicts.py cost` under `mpirun -n 2`; its rows land in OUT/<label>-<round>/.
#
#   scripts/bench_paired.sh BEFORE_CHECKOUT AFTER_CHECKOUT OUT [ROUNDS]
#   e.g. git clone -q . /tmp/before && git -C /tmp/before checkout -q 3190fa2
#        scripts/bench_paired.sh /tmp/before . /tmp/paired 2
# ARGS (environment) overrides the cost arguments (default below).
set -u
[ $# -ge 3 ] || { echo "usage: $0 BEFORE_CHECKOUT AFTER_CHECKOUT OUT [ROUNDS]" >&2; exit 2; }
before=$(cd "$1" && pwd); after=$(cd "$2" && pwd); out=$3; rounds=${4:-2}
here=$(cd "$(dirname "$0")/.." && pwd)
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1
ARGS=${ARGS:-"--nx 1000 --rows 250 250 --states slip+ slip- --mu 1 3"}
for r in $(seq 1 "$rounds"); do
  for label in before after; do
    dir=$before; [ $label = after ] && dir=$after
    mkdir -p "$out/$label-$r"
    # shellcheck disable=SC2086
    ( cd "$dir" && MEICP_BENCH_DIR="$out/$label-$r" PYTHONPATH="$dir/src" \
        mpirun -n 2 "$here/.venv/bin/python" scripts/bench_verdicts.py cost $ARGS ) > "$out/$label-$r/log.txt" 2>&1
    echo "$label round $r: $(grep -c analyze_s "$out/$label-$r/log.txt") rows"
  done
done
