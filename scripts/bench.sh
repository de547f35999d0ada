#!/usr/bin/env bash
# make bench [MODE=quick|full]: every benchmark, then its charts (docs/benchmarks.md).
#   quick  small sizes, one repeat, < 10 min; CSVs and PNGs in build/benchmarks/ (not committed)
#   full   the sizes quoted in docs/benchmarks.md; CSVs and PNGs in docs/benchmarks/ (committed)
# MEICP_BENCH_DIR overrides the output directory; BENCH_ONLY="tradeoff scaling" runs a subset.
set -euo pipefail
cd "$(dirname "$0")/.."
mode=${1:-quick}
case "$mode" in quick|full) ;; *) echo "usage: scripts/bench.sh quick|full" >&2; exit 2 ;; esac
PY=.venv/bin/python
MPI=(mpirun -n 2 --oversubscribe)
# one BLAS thread per rank: the ranks are the parallelism, and threaded BLAS slows the batched solves
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
if [[ $mode == quick ]]; then
    export MEICP_BENCH_DIR=${MEICP_BENCH_DIR:-build/benchmarks}
    mkdir -p "$MEICP_BENCH_DIR"
else
    export MEICP_BENCH_DIR=${MEICP_BENCH_DIR:-docs/benchmarks}
fi
DIR=$MEICP_BENCH_DIR
declare -a SUMMARY=()
start_all=$SECONDS

wanted() { [[ -z ${BENCH_ONLY:-} || " $BENCH_ONLY " == *" $1 "* ]]; }
run() { echo "+ $*"; "$@"; }
chart() { run "$PY" scripts/charts.py "$1" "$DIR/$1.csv"; }
# a quick run starts each of its benchmarks from nothing (and leaves the others' results)
begin() {
    echo; echo "=== $1 ($mode) ==="; t0=$SECONDS
    if [[ $mode == quick ]]; then rm -f "$DIR/$1.csv" "$DIR/$1"*.png; fi
}
end() { SUMMARY+=("$(printf '%-11s %5d s' "$1" $((SECONDS - t0)))"); }

if wanted assembly; then begin assembly
    if [[ $mode == quick ]]; then sizes=(--dofs 10000 100000 --repeats 2); else sizes=(); fi
    run "$PY" scripts/bench_assembly.py "${sizes[@]}"
    run "${MPI[@]}" "$PY" scripts/bench_assembly.py "${sizes[@]}"
    chart assembly; end assembly; fi

if wanted lcp; then begin lcp
    if [[ $mode == quick ]]; then q=(--quick); else q=(); fi
    run "$PY" scripts/bench_lcp.py "${q[@]}"
    run "${MPI[@]}" "$PY" scripts/bench_lcp.py "${q[@]}" --append
    chart lcp; end lcp; fi

if wanted classes; then begin classes
    if [[ $mode == quick ]]; then run "$PY" scripts/bench_classes.py --sizes 2 6 10 20 100
    else run "$PY" scripts/bench_classes.py; fi
    end classes; fi

if wanted eicp; then begin eicp
    if [[ $mode == quick ]]; then
        run "$PY" scripts/bench_eicp.py enumerate --sizes 10 12
        run "${MPI[@]}" "$PY" scripts/bench_eicp.py enumerate --sizes 12
        run "$PY" scripts/bench_eicp.py lattice --nx 200
        run "${MPI[@]}" "$PY" scripts/bench_eicp.py lattice --nx 200
        run "$PY" scripts/bench_eicp.py accuracy --cases 10
    else
        run "$PY" scripts/bench_eicp.py enumerate --sizes 12 14 16
        run "${MPI[@]}" "$PY" scripts/bench_eicp.py enumerate --sizes 16 18 20
        for J in y xy; do
            run "$PY" scripts/bench_eicp.py lattice --nx 1000 --dofs $J
            run "${MPI[@]}" "$PY" scripts/bench_eicp.py lattice --nx 1000 --dofs $J
        done
        run "$PY" scripts/bench_eicp.py accuracy
    fi
    chart eicp; end eicp; fi

# === tradeoff: speed against accuracy, every LCP and EiCP method (issue 7 §2) ===
if wanted tradeoff; then begin tradeoff
    if [[ $mode == quick ]]; then run "$PY" scripts/bench_tradeoff.py --quick
    else run "$PY" scripts/bench_tradeoff.py; fi
    chart tradeoff; end tradeoff; fi

# === scaling: 10^4 to 10^6 DOFs, 1 and 2 ranks, peers in the same run (issue 7 §3) ===
if wanted scaling; then begin scaling
    # serial run: meicp stages on 1 rank + the peers (ARPACK+SuperLU, Siconos, enumeration);
    # then 2 ranks, appended (keeps the 1-rank rows)
    # (each also runs the multi-support family J = xy); MUMPS orderings into scaling_ordering.csv:
    # quick 10^4 DOFs; full only with SCALING_ORDERINGS=1 (7 more minutes: 3·10^5 and 10^6)
    if [[ $mode == quick ]]; then q=(--quick); else q=(); fi
    run "$PY" scripts/bench_scaling.py "${q[@]}"
    run "${MPI[@]}" "$PY" scripts/bench_scaling.py "${q[@]}"
    if [[ $mode == quick || ${SCALING_ORDERINGS:-0} == 1 ]]; then
        run "$PY" scripts/bench_scaling.py --orderings "${q[@]}"
        run "${MPI[@]}" "$PY" scripts/bench_scaling.py --orderings "${q[@]}"
    fi
    chart scaling; end scaling; fi

# === failure: where each method fails (issue 7 §4) ===
if wanted failure; then begin failure
    if [[ $mode == quick ]]; then run "$PY" scripts/bench_failure.py --quick
    else run "$PY" scripts/bench_failure.py; fi
    chart failure; end failure; fi

# === resolution: convergence of λ and μ_c, cost of scene features (issue 7 §5) ===
if wanted resolution; then begin resolution
    if [[ $mode == quick ]]; then run "$PY" scripts/bench_resolution.py --quick
    else run "$PY" scripts/bench_resolution.py; fi
    chart resolution; end resolution; fi

# === flutter: accuracy against dense QZ, cost against one eigen-solve, stability map (issue 15) ===
if wanted flutter; then begin flutter
    if [[ $mode == quick ]]; then
        run "$PY" scripts/bench_flutter.py accuracy --dofs 300 1000
        run "${MPI[@]}" "$PY" scripts/bench_flutter.py cost --dofs 10000 --repeats 1 --check
    else
        run "$PY" scripts/bench_flutter.py accuracy
        run "${MPI[@]}" "$PY" scripts/bench_flutter.py cost --dofs 100000 300000 --repeats 3 --check
    fi
    run "$PY" scripts/bench_flutter.py chart
    run "$PY" scripts/stability_map.py
    end flutter; fi

# === critical_friction: the certified bracket past 20 contacts (issue 14 §4) ===
if wanted critical_friction; then begin critical_friction
    if [[ $mode == quick ]]; then
        run "$PY" scripts/bench_critical_friction.py --nx 30 --rows 8 7 --repeats 1
        run "$PY" scripts/bench_critical_friction.py --nx 100 --rows 25 25 --repeats 1
    else
        run "$PY" scripts/bench_critical_friction.py --nx 30 --rows 8 7 --repeats 5
        run "$PY" scripts/bench_critical_friction.py --nx 100 --rows 25 25 --repeats 5
        run "${MPI[@]}" "$PY" scripts/bench_critical_friction.py --nx 100 --rows 25 25 --repeats 5
        run "$PY" scripts/bench_critical_friction.py --nx 300 --rows 75 75 --repeats 3
        # 10⁶ DOFs (on a shared machine, one such run at a time: docs/benchmarks.md)
        run "${MPI[@]}" "$PY" scripts/bench_critical_friction.py \
            --nx 1000 --rows 250 250 --repeats 1
    fi
    chart critical_friction; end critical_friction; fi

# === verdicts: decided fraction, agreement with enumeration, cost at 10⁶ DOFs (issue 14) ===
if wanted verdicts; then begin verdicts
    if [[ $mode == quick ]]; then
        rm -f "$DIR"/verdicts_*.csv
        run "$PY" scripts/bench_verdicts.py family --sizes 20:2+2 60:2+2
        run "$PY" scripts/bench_verdicts.py check --count 10
        run "${MPI[@]}" "$PY" scripts/bench_verdicts.py cost --nx 100 --rows 25 25 --mu 3 1
    else
        run "$PY" scripts/bench_verdicts.py family
        run "$PY" scripts/bench_verdicts.py family --sizes 2000:10+10
        run "$PY" scripts/bench_verdicts.py check --count 80
        # 10⁶ DOFs, 1,000 sliding contacts (one such run at a time on a shared machine)
        run "${MPI[@]}" "$PY" scripts/bench_verdicts.py cost --nx 1000 --rows 250 250 --states slip- --mu 3
        run "${MPI[@]}" "$PY" scripts/bench_verdicts.py cost --nx 1000 --rows 250 250 --states slip+ --mu 0.1 1
    fi
    run "$PY" scripts/bench_verdicts.py chart
    end verdicts; fi

echo; echo "=== bench $mode: done in $((SECONDS - start_all)) s; results in $DIR ==="
printf '%s\n' "${SUMMARY[@]}"
