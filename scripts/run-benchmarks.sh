#!/usr/bin/env bash
# Runs every Google Benchmark program of a build.  scripts/run-benchmarks.sh BUILD_DIR
set -euo pipefail
build_dir=${1:-build}
shopt -s nullglob
found=0
for b in "$build_dir"/benchmarks/*_benchmark; do
  found=1
  echo "==> $b"
  "$b" --benchmark_counters_tabular=true
done
[[ $found -eq 1 ]] || { echo "no benchmarks built in $build_dir/benchmarks" >&2; exit 1; }
