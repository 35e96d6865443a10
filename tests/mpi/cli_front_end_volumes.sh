#!/usr/bin/env bash
# The distributed front end of the CLI on volume files and with II normals (ctest
# petsc_mpi_front_end_volumes, docs/distributed.md): under `mpirun -np P` (P = 1, 2, 4),
# `corrlap solve --volume ... --solver petsc` and `--shape torus --normals ii` take the distributed
# front end and equal the serial CHOLMOD solution to 1e-10, and `corrlap eigs --solver slepc` on a
# volume with a physical spacing the serial eigenvalues to 1e-8. The default II (smaller balls on
# thin parts) and anisotropic voxels (resampled to cubes per slab) take the distributed front end
# too, with the serial result.
# Usage: cli_front_end_volumes.sh CORRLAP MPIEXEC WORK_DIR
set -euo pipefail
cli=$1 mpiexec=$2 work=$3
rm -rf "$work" && mkdir -p "$work"

# A grey-level torus (0 .. 255, falling off with the distance to the tube's core circle) as .npy
# and as NRRD with an isotropic and an anisotropic spacing. Plain Python (no numpy).
python3 - "$work" <<'PY'
import math, struct, sys
work = sys.argv[1]
nx, ny, nz = 44, 40, 18
values = bytearray(nx * ny * nz)
for z in range(nz):
    for y in range(ny):
        for x in range(nx):
            d = math.hypot(math.hypot(x - 21.7, y - 19.4) - 12.5, z - 8.6)
            values[x + nx * (y + ny * z)] = round(min(255.0, max(0.0, 255.0 * (1.0 - d / 10.4))))
# .npy in C order, shape (nz, ny, nx): the last index (x) varies fastest, as written above.
header = "{'descr': '|u1', 'fortran_order': False, 'shape': (%d, %d, %d), }" % (nz, ny, nx)
header += " " * ((64 - (10 + len(header) + 1) % 64) % 64) + "\n"
with open(f"{work}/torus.npy", "wb") as f:
    f.write(b"\x93NUMPY\x01\x00" + struct.pack("<H", len(header)) + header.encode() + bytes(values))
for name, spacings in (("torus.nrrd", "0.75 0.75 0.75"), ("torus_anisotropic.nrrd", "0.75 0.75 1.5"),
                       ("torus_coarse_x.nrrd", "2.25 0.75 0.75")):
    with open(f"{work}/{name}", "wb") as f:
        f.write(f"NRRD0004\ntype: uint8\ndimension: 3\nsizes: {nx} {ny} {nz}\nspacings: {spacings}\n"
                "encoding: raw\n\n".encode() + bytes(values))
PY

run() {  # run P ARGS...: corrlap under mpirun with P ranks
  local np=$1
  shift
  local extra=()
  [ "$np" -gt 2 ] && extra=(--oversubscribe)
  "$mpiexec" -n "$np" "${extra[@]}" "$cli" "$@"
}
distributed() {  # distributed FILE: the JSON says the distributed front end ran
  grep -q '"front_end": "distributed"' "$1" || { echo "$1: not the distributed front end"; cat "$1"; exit 1; }
}

volume=(--volume "$work/torus.npy" --threshold 127 --method fem)
shape=(--shape torus --h 0.35 --method fem --normals ii)
"$cli" solve "${volume[@]}" --ii-thin-parts keep --rhs expx --out "$work/volume_serial.txt" > /dev/null
"$cli" solve "${shape[@]}" --ii-thin-parts keep --rhs x2 --out "$work/shape_serial.txt" > /dev/null
for np in 1 2 4; do
  run "$np" solve "${volume[@]}" --ii-thin-parts keep --rhs expx --solver petsc --json \
    --out "$work/volume_np$np.txt" > "$work/volume_np$np.json"
  distributed "$work/volume_np$np.json"
  grep -q '"normals": "ii"' "$work/volume_np$np.json" || { echo "volume: not the II normals"; exit 1; }
  run "$np" solve "${shape[@]}" --ii-thin-parts keep --rhs x2 --solver petsc --json \
    --out "$work/shape_np$np.txt" > "$work/shape_np$np.json"
  distributed "$work/shape_np$np.json"
done

# eigs on a volume with a physical spacing: the values in 1/length^2 of its physical units.
nrrd=(--volume "$work/torus.nrrd" --threshold 127 --method fem --ii-thin-parts keep -k 12)
"$cli" eigs "${nrrd[@]}" > "$work/eigs_serial.txt" 2> /dev/null
run 2 eigs "${nrrd[@]}" --solver slepc > "$work/eigs_np2.txt" 2> "$work/eigs_np2.err"
grep -q "on the distributed front end over 2 ranks" "$work/eigs_np2.err" || { echo "eigs: not distributed"; cat "$work/eigs_np2.err"; exit 1; }
# The same on the coarse-x volume: its values are in the physical units of the resampled frame.
coarse=(--volume "$work/torus_coarse_x.nrrd" --threshold 127 --method fem --ii-thin-parts keep -k 12)
"$cli" eigs "${coarse[@]}" > "$work/eigs_coarse_x_serial.txt" 2> /dev/null
run 2 eigs "${coarse[@]}" --solver slepc > "$work/eigs_coarse_x_np2.txt" 2> "$work/eigs_coarse_x_np2.err"
grep -q "on the distributed front end over 2 ranks" "$work/eigs_coarse_x_np2.err" || { echo "eigs coarse x: not distributed"; cat "$work/eigs_coarse_x_np2.err"; exit 1; }

# The default II (smaller balls on thin parts): distributed too.
"$cli" solve "${volume[@]}" --rhs expx --out "$work/shrink_serial.txt" > /dev/null
run 2 solve "${volume[@]}" --rhs expx --solver petsc --json --out "$work/shrink_np2.txt" > "$work/shrink_np2.json"
distributed "$work/shrink_np2.json"
# Anisotropic voxels, a coarse z and a coarse x (x resampled, so slabs cut between resampled columns
# of one file column): resampled to cubes per slab, on the distributed front end, without a note.
for name in anisotropic coarse_x; do
  anisotropic=(--volume "$work/torus_$name.nrrd" --threshold 127 --method fem --ii-thin-parts keep)
  "$cli" solve "${anisotropic[@]}" --rhs expx --out "$work/${name}_serial.txt" > /dev/null
  for np in 2 4; do
    run "$np" solve "${anisotropic[@]}" --rhs expx --solver petsc --json --out "$work/${name}_np$np.txt" \
      > "$work/${name}_np$np.json" 2> "$work/${name}_np$np.err"
    distributed "$work/${name}_np$np.json"
    if grep -q "serial front end" "$work/${name}_np$np.err"; then
      echo "$name np $np: a note about the serial front end"
      cat "$work/${name}_np$np.err"
      exit 1
    fi
  done
done

python3 - "$work" "$(dirname "$0")" <<'PY'
import os, sys
work = sys.argv[1]
sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, sys.argv[2])
from solution_files import load as load_path, relative_difference as rel
def load(name):
    return load_path(os.path.join(work, name))
worst = {}
for case in ("volume", "shape"):
    for np in (1, 2, 4):
        worst[f"{case} np {np}"] = rel(load(f"{case}_np{np}.txt"), load(f"{case}_serial.txt"))
worst["shrink np 2"] = rel(load("shrink_np2.txt"), load("shrink_serial.txt"))
for name in ("anisotropic", "coarse_x"):
    for np in (2, 4):
        worst[f"{name} np {np}"] = rel(load(f"{name}_np{np}.txt"), load(f"{name}_serial.txt"))
for name, error in worst.items():
    print(f"{name}: largest relative difference to the serial CHOLMOD solution {error:.3g}")
    assert error < 1e-10, (name, error)
for case in ("eigs", "eigs_coarse_x"):
    e0, e = load(f"{case}_serial.txt"), load(f"{case}_np2.txt")
    assert len(e) == 12, len(e)
    print(f"{case} np 2: largest relative eigenvalue difference {rel(e, e0):.3g}")
    assert rel(e, e0) < 1e-8, rel(e, e0)
PY
