#!/usr/bin/env bash
# `corrlap regularize --solver petsc` under mpirun (ctest petsc_mpi_regularize): on an implicit
# shape with 1, 2 and 4 ranks and on a volume file with 2, the distributed front end (each rank its
# slab: the curvature, the solve and the automatic alpha0's trials) gives the serial CHOLMOD
# surface to 1e-8 of the object's size with the same automatic alpha0, and rank 0 alone writes and
# reports.
# Usage: cli_regularize_petsc.sh CORRLAP MPIEXEC WORK_DIR
set -euo pipefail
cli=$1 mpiexec=$2 work=$3
rm -rf "$work" && mkdir -p "$work"

"$cli" digitize --shape torus --h 0.4 --out "$work/torus.obj" --volume-out "$work/torus.vol" > /dev/null
# The shape with 1, 2 and 4 ranks (4 oversubscribed), the volume file with 2.
for run in "2 --shape goursat --h 0.4" "1 --shape goursat --h 0.4" "4 --shape goursat --h 0.4" \
           "2 --volume $work/torus.vol"; do
  np=${run%% *} input=${run#* }
  name=$(echo "$input" | cut -d' ' -f2 | xargs basename)
  [ -d "$work/$name-serial" ] ||
    # shellcheck disable=SC2086  # $input is a list of arguments
    "$cli" regularize $input --no-render --out "$work/$name-serial" 2> "$work/$name-serial.err"
  oversubscribe=()
  [ "$np" -gt 2 ] && oversubscribe=(--oversubscribe)
  # shellcheck disable=SC2086
  "$mpiexec" -n "$np" "${oversubscribe[@]}" "$cli" regularize $input --no-render --solver petsc \
    --out "$work/$name-petsc-np$np" 2> "$work/$name-petsc-np$np.err"
  # One report (rank 0's), and no folder or temporary file from the other ranks.
  [ "$(grep -c '^regularize: ' "$work/$name-petsc-np$np.err")" = 2 ] ||
    { echo "expected rank 0's two report lines"; cat "$work/$name-petsc-np$np.err"; exit 1; }
  [ "$(grep -c 'wrote ' "$work/$name-petsc-np$np.err")" = 1 ] || { echo "expected one 'wrote'"; exit 1; }
  ls -a "$work" | grep -q corrlap-tmp && { echo "a temporary folder was left behind"; exit 1; }
  grep -q '"solver": "petsc"' "$work/$name-petsc-np$np/metrics.json" || { echo "metrics.json does not name petsc"; exit 1; }
  grep -q '"front_end": "distributed"' "$work/$name-petsc-np$np/metrics.json" ||
    { echo "metrics.json does not say the distributed front end"; cat "$work/$name-petsc-np$np.err"; exit 1; }

  # Plain Python (no numpy: whatever python3 is first on PATH).
  python3 - "$work/$name-serial" "$work/$name-petsc-np$np" "$np" <<'PY'
import json, struct, sys

def positions(folder):
    with open(f"{folder}/regularized.ply", "rb") as f:
        header = []
        while not header or header[-1] != "end_header":
            header.append(f.readline().decode().strip())
        count = int(next(line for line in header if line.startswith("element vertex")).split()[2])
        properties = [line.split()[2] for line in header if line.startswith("property double")]
        assert properties[:3] == ["x", "y", "z"], properties
        row = struct.Struct("<" + "d" * len(properties))
        return [row.unpack(f.read(row.size))[:3] for _ in range(count)]

serial, petsc = positions(sys.argv[1]), positions(sys.argv[2])
assert len(serial) == len(petsc), (len(serial), len(petsc))
size = max(max(p[k] for p in serial) - min(p[k] for p in serial) for k in range(3))
worst = max(abs(a - b) for p, q in zip(serial, petsc) for a, b in zip(p, q))
# Both solves stop at the same proven accuracy (a thousandth of a voxel, RMS); the MUMPS and CHOLMOD
# factors differ by rounding only, so the iterates agree far below that.
assert worst <= 1e-8 * size, (worst, size)
a0 = [json.load(open(f"{d}/metrics.json"))["alpha0"] for d in sys.argv[1:3]]
assert abs(a0[0] - a0[1]) <= 1e-10 * a0[0], a0
print(f"{sys.argv[2]} ({sys.argv[3]} ranks): max difference {worst / size:.2e} of the size, alpha0 {a0[1]:.6g}")
PY
done
