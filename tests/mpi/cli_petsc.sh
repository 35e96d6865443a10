#!/usr/bin/env bash
# The CLI with the PETSc backends under `mpirun -np 2` (ctest petsc_mpi_cli): `solve --solver petsc`
# equals CHOLMOD's solution and `eigs --solver slepc` the serial eigenvalues; only rank 0 prints
# and writes; `corrlap backends` lists both.
# Usage: cli_petsc.sh CORRLAP MPIEXEC WORK_DIR
set -euo pipefail
cli=$1 mpiexec=$2 work=$3
rm -rf "$work" && mkdir -p "$work"
surface=(--shape sphere1 --h 0.1 --method fem --normals true)

"$cli" backends | grep -q "^  petsc " || { echo "corrlap backends does not list petsc"; exit 1; }
"$cli" backends | grep -q "^  slepc " || { echo "corrlap backends does not list slepc"; exit 1; }

"$cli" solve "${surface[@]}" --rhs expx --solver cholmod --out "$work/cholmod.txt" > /dev/null
"$mpiexec" -n 2 "$cli" solve "${surface[@]}" --rhs expx --solver petsc --out "$work/petsc.txt" --json \
  > "$work/petsc.json"
"$mpiexec" -n 2 "$cli" solve "${surface[@]}" --rhs expx --solver petsc --solver-option ksp_type=cg \
  --solver-option pc_type=gamg --solver-option rtol=1e-10 --out "$work/gamg.txt" > /dev/null
# One JSON object: rank 1 printed nothing.
[ "$(grep -c '"solver": "petsc"' "$work/petsc.json")" = 1 ] || { echo "expected one JSON object"; cat "$work/petsc.json"; exit 1; }
ls -a "$work" | grep -q corrlap-tmp && { echo "a temporary file was left behind"; exit 1; }

"$cli" eigs "${surface[@]}" -k 12 --solver cholmod > "$work/eigs_serial.txt" 2> /dev/null
"$mpiexec" -n 2 "$cli" eigs "${surface[@]}" -k 12 --solver slepc > "$work/eigs_slepc.txt" 2> "$work/eigs_slepc.err"
grep -q "slepc" "$work/eigs_slepc.err" || { echo "eigs did not report the slepc solver"; cat "$work/eigs_slepc.err"; exit 1; }

python3 - "$work" <<'PY'
import sys
import numpy as np
work = sys.argv[1]
def rel(a, b):
    return np.abs(a - b).max() / np.abs(b).max()
g0 = np.loadtxt(f"{work}/cholmod.txt", comments="#")
for name, tol in (("petsc", 1e-10), ("gamg", 1e-6)):
    g = np.loadtxt(f"{work}/{name}.txt", comments="#")
    assert g.shape == g0.shape, (name, g.shape, g0.shape)
    assert rel(g, g0) < tol, (name, rel(g, g0))
e0 = np.loadtxt(f"{work}/eigs_serial.txt")
e = np.loadtxt(f"{work}/eigs_slepc.txt")
assert e.shape == (12,), e.shape  # printed by rank 0 only
assert rel(e, e0) < 1e-8, rel(e, e0)
print("petsc CLI: solve and eigs under mpirun -np 2 equal the serial results")
PY
