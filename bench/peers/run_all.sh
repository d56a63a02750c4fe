#!/usr/bin/env bash
# Run every peer at N = 10^3 … 10^6 and write JSON lines to results.jsonl: the AR(1)+noise
# bootstrap filter on data.csv, then the radar standard PF (model (13), PPPPPP) on radar.csv.
# Each runs from the same seed (the same estimate) several times and reports the fastest run
# and the median: pf-viz PF_REPEAT times (its runs are short, and a few of them can land on
# a busy moment of a shared machine), the Python peers REPEAT times. MODELS="ar1" or
# MODELS="radar" runs one block; `particles` runs the radar filter up to
# N = RADAR_PARTICLES_MAX (default 10^5: at 10^6 one run took 65 s here).
set -euo pipefail
cd "$(dirname "$0")"
PY=${PY:-.venv/bin/python}
PFVIZ=${PFVIZ:-../../target/release/pf-viz}
STEPS=${STEPS:-500}
RADAR_STEPS=${RADAR_STEPS:-100}
RADAR_PARTICLES_MAX=${RADAR_PARTICLES_MAX:-100000}
REPEAT=${REPEAT:-3}
PF_REPEAT=${PF_REPEAT:-20}
MODELS=${MODELS:-ar1 radar}
# The Python filters on one thread, as pf-viz's --threads 1.
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1
: > results.jsonl
if [[ " $MODELS " == *" ar1 "* ]]; then
  "$PY" simulate.py data.csv "$STEPS" 1
  for n in 1000 10000 100000 1000000; do
    "$PFVIZ" bench bootstrap --data data.csv --particles "$n" --threads 1 --repeat "$PF_REPEAT" --json | tee -a results.jsonl
    "$PFVIZ" bench bootstrap --data data.csv --particles "$n" --threads 2 --repeat "$PF_REPEAT" --json | tee -a results.jsonl
    "$PY" numpy_bootstrap.py data.csv "$n" 1 "$REPEAT" | tee -a results.jsonl
    "$PY" particles_bootstrap.py data.csv "$n" 1 "$REPEAT" | tee -a results.jsonl
  done
fi
if [[ " $MODELS " == *" radar "* ]]; then
  "$PY" simulate_radar.py radar.csv "$RADAR_STEPS" 1
  for n in 1000 10000 100000 1000000; do
    for t in 1 2; do
      "$PFVIZ" bench filter --model radar --data radar.csv --particles "$n" --threads "$t" --repeat "$PF_REPEAT" --json | tee -a results.jsonl
    done
    "$PY" numpy_radar.py radar.csv "$n" 1 "$REPEAT" | tee -a results.jsonl
    if (( n <= RADAR_PARTICLES_MAX )); then
      "$PY" particles_radar.py radar.csv "$n" 1 "$REPEAT" | tee -a results.jsonl
    fi
  done
fi
