#!/usr/bin/env bash
# Run every peer on one data set at N = 10^3 … 10^6 and write JSON lines to results.jsonl.
# Each runs REPEAT times from the same seed (the same estimate) and reports the fastest run
# and the median.
set -euo pipefail
cd "$(dirname "$0")"
PY=${PY:-.venv/bin/python}
PFVIZ=${PFVIZ:-../../target/release/pf-viz}
STEPS=${STEPS:-500}
REPEAT=${REPEAT:-3}
"$PY" simulate.py data.csv "$STEPS" 1
: > results.jsonl
for n in 1000 10000 100000 1000000; do
  "$PFVIZ" bench bootstrap --data data.csv --particles "$n" --threads 1 --repeat "$REPEAT" --json | tee -a results.jsonl
  "$PFVIZ" bench bootstrap --data data.csv --particles "$n" --threads 2 --repeat "$REPEAT" --json | tee -a results.jsonl
  "$PY" numpy_bootstrap.py data.csv "$n" 1 "$REPEAT" | tee -a results.jsonl
  "$PY" particles_bootstrap.py data.csv "$n" 1 "$REPEAT" | tee -a results.jsonl
done
