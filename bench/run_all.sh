#!/usr/bin/env bash
# Runs every benchmark executable and writes one CSV per benchmark into BUILD/bench-results/.
set -euo pipefail
build=${1:-build}
out="$build/bench-results"
mkdir -p "$out"
for exe in "$build"/bench/bench_*; do
  [ -x "$exe" ] || continue
  name=$(basename "$exe")
  echo "== $name"
  "$exe" --benchmark_out="$out/$name.csv" --benchmark_out_format=csv "${@:2}"
done
echo "CSV files in $out"
