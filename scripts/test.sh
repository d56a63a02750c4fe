#!/usr/bin/env bash
# The project's test command (the README shows it): the whole test suite, including a quick
# `pf-viz report` whose PNGs are decoded and whose `.rrd` recordings are verified by the
# official Rerun tools of the same version as the rerun crate.
#
# The Rerun tools are the PyPI package `rerun-sdk`, installed once into a virtual environment
# under ~/.cache/pf-tools (override with PF_TOOLS). cargo's target directory is cargo's own
# (`target/`, or CARGO_TARGET_DIR), the same one the README's report command builds into, so
# the tests compile only the workspace's test code on top of that build.
set -euo pipefail
cd "$(dirname "$0")/.."

# The rerun crate's version, as Cargo.lock pins it.
version="$(awk '$0 == "name = \"rerun\"" { getline; gsub(/[^0-9.]/, ""); print; exit }' Cargo.lock)"
if [ -z "$version" ]; then
  echo "scripts/test.sh: cannot find the rerun crate's version in Cargo.lock" >&2
  exit 1
fi
venv="${PF_TOOLS:-$HOME/.cache/pf-tools}/rerun-$version"
if [ ! -x "$venv/bin/rerun" ]; then
  echo "scripts/test.sh: installing rerun-sdk==$version into $venv" >&2
  python3 -m venv "$venv"
  "$venv/bin/pip" install --quiet --disable-pip-version-check "rerun-sdk==$version"
fi
# pf-viz's report tests run `$PF_RERUN rrd verify` and `rrd print` on its recordings.
export PF_RERUN="$venv/bin/rerun"
"$PF_RERUN" --version >&2

# pf-core's AVX-512 kernels are tested against the portable ones only on a CPU that runs
# them; elsewhere those tests return early, so say which case this run is.
if [ -r /proc/cpuinfo ] && grep -q -w avx512f /proc/cpuinfo && grep -q -w avx512dq /proc/cpuinfo \
  && grep -q -w avx512bw /proc/cpuinfo && grep -q -w avx512vl /proc/cpuinfo; then
  echo "scripts/test.sh: this CPU has AVX-512: pf-core's AVX-512 kernels are tested" >&2
else
  echo "scripts/test.sh: this CPU lacks AVX-512 (or it cannot tell): pf-core's AVX-512 kernels are NOT tested by this run" >&2
fi

# The tests that need the Rerun CLI are #[ignore]d by a plain `cargo test`; here they run
# with the rest, in one pass, so the quick report they check is rendered once.
cargo test --workspace -- --include-ignored
