#!/usr/bin/env bash
# Prints a hash of L.mtx and M.mtx (Matrix Market, %.17g: the text determines every bit) for every
# method and main option on sphere1, h = 0.05, normals read from files, on 1 and 2 threads.
# Used to show that a refactoring leaves every operator bitwise unchanged:
#   bench/operator_hashes.sh BUILD_DIR [NORMALS_DIR] > hashes.txt   (then diff two such lists)
# NORMALS_DIR (default: a temporary folder) holds mesh.obj, fn.txt, vn.txt; it is created with
# BUILD_DIR's digitizer when absent, so two builds can be compared on the very same input files.
set -euo pipefail
build=${1:?usage: operator_hashes.sh BUILD_DIR [NORMALS_DIR]}
cli="$build/bin/corrlap"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
inputs=${2:-$work/inputs}
if [ ! -f "$inputs/mesh.obj" ]; then
  mkdir -p "$inputs"
  "$cli" digitize --shape sphere1 --h 0.05 --bbox -1.5 1.5 --out "$inputs/mesh.obj" \
    --face-normals "$inputs/fn.txt" --vertex-normals "$inputs/vn.txt" 2>/dev/null
fi
cases=(
  "polydec"
  "projected-polydec"
  "interpolated"
  "interpolated --assembly local"
  "fem"
  "fem --mass lumped"
  "vrm"
  "corrected-vrm"
  "corrected-vrm --param mass=lumped"
  "heat-kernel"
  "cotan"
)
for threads in 1 2; do
  for c in "${cases[@]}"; do
    out="$work/ops"
    rm -rf "$out"
    # shellcheck disable=SC2086
    "$cli" --threads "$threads" operators --mesh "$inputs/mesh.obj" --face-normals "$inputs/fn.txt" \
      --vertex-normals "$inputs/vn.txt" --method $c --out "$out" 2>/dev/null
    printf '%-36s threads=%s L %s M %s\n' "$c" "$threads" \
      "$(sha256sum <"$out/L.mtx" | cut -c1-16)" "$(sha256sum <"$out/M.mtx" | cut -c1-16)"
  done
done
