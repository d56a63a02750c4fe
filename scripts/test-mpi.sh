#!/usr/bin/env bash
# The MPI test: pf-viz built with `--features mpi` (without Rerun) runs small studies under
# `mpirun -np 1`, `-np 2` and `-np 3 --oversubscribe`, and each result must be byte for byte
# the one-process run's (summary.json: apart from its `timing_dependent` numbers). Then a
# failure injected into replication 5, which rank 1 runs, must end a 2-rank run within
# seconds with one line on stderr naming that replication.
#
# It needs an MPI library and mpirun (Debian: openmpi-bin libopenmpi-dev libclang-dev) and
# fails, never skips, without them. .ci/run calls it after scripts/test.sh.
set -euo pipefail
cd "$(dirname "$0")/.."

if ! command -v mpirun >/dev/null; then
  echo "scripts/test-mpi.sh: mpirun not found; install openmpi-bin libopenmpi-dev libclang-dev" >&2
  exit 1
fi
# Open MPI refuses to start as root unless told twice.
if [ "$(id -u)" = 0 ]; then
  export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
fi

cargo build -p pf-viz --no-default-features --features mpi
bin="${CARGO_TARGET_DIR:-target}/debug/pf-viz"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
# -q: no launcher banners, so stderr holds pf-viz's own lines.
run() { local np="$1"; shift; mpirun -q --oversubscribe -np "$np" "$bin" "$@"; }
fail=0
same() { # name, file A, file B
  if cmp -s "$2" "$3"; then
    echo "ok: $1"
  else
    echo "FAILED: $1 differs from the one-process run" >&2
    fail=1
  fi
}

# Observations for the smoothing studies: Y_0..Y_100, a fixed sequence.
awk 'BEGIN { print "y"; for (k = 0; k <= 100; k++) printf "%.6f\n", 2 * sin(0.7 * k) + cos(1.9 * k) }' \
  >"$work/y.csv"
"$bin" dredge simulate --out "$work/dredge.csv" --seed 2 >/dev/null

# name|arguments: each a replicating subcommand with a JSON result free of timings.
studies=(
  "smooth score, R = 7 (uneven shares)|smooth score --data $work/y.csv --phi 0.8 --sigma 0.6 --rho 1 --particles 60 --replications 7 --seed 3 --json"
  "smooth score, R = 2 (more ranks than replications at 3)|smooth score --data $work/y.csv --phi 0.8 --sigma 0.6 --rho 1 --particles 60 --replications 2 --seed 4 --json"
  "smooth em, R = 5, fixed-lag and forward|smooth em --data $work/y.csv --phi 0.8 --sigma 0.6 --rho 1 --particles 40 --replications 5 --lag 5 --forward --seed 5 --json"
  "dredge estimate, 5 runs|dredge estimate --data $work/dredge.csv --particles 100 --runs 5 --seed 6 --json"
)
for s in "${studies[@]}"; do
  name="${s%%|*}"
  read -r -a args <<<"${s#*|}"
  "$bin" "${args[@]}" >"$work/one.json"
  for np in 1 2 3; do
    run "$np" "${args[@]}" >"$work/np$np.json"
    same "$name, mpirun -np $np" "$work/one.json" "$work/np$np.json"
  done
done

# Every report section's studies, at quick scale.
"$bin" report --scale quick --out "$work/report-one" >/dev/null
for np in 1 2 3; do
  run "$np" report --scale quick --out "$work/report-np$np" >/dev/null
  if scripts/compare-summaries.py "$work/report-one/summary.json" "$work/report-np$np/summary.json"; then
    echo "ok: report --scale quick, mpirun -np $np"
  else
    echo "FAILED: report --scale quick under mpirun -np $np" >&2
    fail=1
  fi
done

# A failure in replication 5 of 7, on rank 1 (rank 0 runs 0-3, rank 1 runs 4-6).
start=$(date +%s)
set +e
PF_MPI_FAIL_REPLICATION=5 timeout 120 mpirun -q -x PF_MPI_FAIL_REPLICATION -np 2 "$bin" \
  smooth score --data "$work/y.csv" --phi 0.8 --sigma 0.6 --rho 1 --particles 60 \
  --replications 7 --seed 3 --json >"$work/fail.out" 2>"$work/fail.err"
status=$?
set -e
took=$(($(date +%s) - start))
lines=$(wc -l <"$work/fail.err")
if [ "$status" -ne 0 ] && [ "$status" -ne 124 ] && [ "$lines" -eq 1 ] \
  && grep -q '^error: .*replication 5: .*PF_MPI_FAIL_REPLICATION on rank 1$' "$work/fail.err" \
  && [ ! -s "$work/fail.out" ] && [ "$took" -le 30 ]; then
  echo "ok: injected failure ends the run in ${took} s: $(cat "$work/fail.err")"
else
  echo "FAILED: injected failure: status $status after ${took} s, stderr:" >&2
  cat "$work/fail.err" >&2
  fail=1
fi

exit "$fail"
