#!/usr/bin/env bash
# The CLI with the PETSc backends under `mpirun -np 2` (ctest petsc_mpi_cli): `solve --solver petsc`
# equals CHOLMOD's solution (on the distributed front end, docs/distributed.md, with the default
# options and with CG + GAMG) and `eigs --solver slepc` (distributed too) the serial eigenvalues;
# only rank 0 prints and writes; `corrlap backends` lists both.
# Usage: cli_petsc.sh CORRLAP MPIEXEC WORK_DIR
set -euo pipefail
cli=$1 mpiexec=$2 work=$3
rm -rf "$work" && mkdir -p "$work"
surface=(--shape sphere1 --h 0.1 --method fem --normals true)

"$cli" backends > "$work/backends.txt"
grep -q "^  petsc " "$work/backends.txt" || { echo "corrlap backends does not list petsc"; exit 1; }
grep -q "^  slepc " "$work/backends.txt" || { echo "corrlap backends does not list slepc"; exit 1; }

"$cli" solve "${surface[@]}" --rhs expx --solver cholmod --out "$work/cholmod.txt" > /dev/null
"$mpiexec" -n 2 "$cli" solve "${surface[@]}" --rhs expx --solver petsc --out "$work/petsc.txt" --json \
  > "$work/petsc.json"
"$mpiexec" -n 2 "$cli" solve "${surface[@]}" --rhs expx --solver petsc --solver-option ksp_type=cg \
  --solver-option pc_type=gamg --solver-option rtol=1e-10 --out "$work/gamg.txt" --json > "$work/gamg.json"
grep -q '"front_end": "distributed"' "$work/gamg.json" || { echo "solve with options did not take the distributed front end"; cat "$work/gamg.json"; exit 1; }
grep -q '"iterations": [1-9]' "$work/gamg.json" || { echo "CG + GAMG reported no iterations"; cat "$work/gamg.json"; exit 1; }
# A bad option fails on both ranks with the cause, and mpirun returns (no rank hangs).
if "$mpiexec" -n 2 "$cli" solve "${surface[@]}" --rhs expx --solver petsc --solver-option ksp_type=cg \
  --solver-option pc_type=none --solver-option max_it=3 > /dev/null 2> "$work/diverged.err"; then
  echo "a diverging solve succeeded"; exit 1
fi
[ "$(grep -c 'DIVERGED_ITS' "$work/diverged.err")" -ge 2 ] || { echo "expected DIVERGED_ITS from both ranks"; cat "$work/diverged.err"; exit 1; }
# One JSON object: rank 1 printed nothing.
[ "$(grep -c '"solver": "petsc"' "$work/petsc.json")" = 1 ] || { echo "expected one JSON object"; cat "$work/petsc.json"; exit 1; }
grep -q '"front_end": "distributed"' "$work/petsc.json" || { echo "solve did not take the distributed front end"; cat "$work/petsc.json"; exit 1; }
# A non-convex shape on the distributed front end.
goursat=(--shape goursat --h 0.3 --method fem --normals true)
"$cli" solve "${goursat[@]}" --rhs x2 --solver cholmod --out "$work/goursat_cholmod.txt" > /dev/null
"$mpiexec" -n 2 "$cli" solve "${goursat[@]}" --rhs x2 --solver petsc --out "$work/goursat_petsc.txt" > "$work/goursat.txt"
grep -q "front end   distributed over 2 ranks" "$work/goursat.txt" || { echo "goursat: not distributed"; cat "$work/goursat.txt"; exit 1; }
ls -a "$work" | grep -q corrlap-tmp && { echo "a temporary file was left behind"; exit 1; }

"$cli" eigs "${surface[@]}" -k 12 --solver cholmod > "$work/eigs_serial.txt" 2> /dev/null
"$mpiexec" -n 2 "$cli" eigs "${surface[@]}" -k 12 --solver slepc > "$work/eigs_slepc.txt" 2> "$work/eigs_slepc.err"
grep -q "slepc" "$work/eigs_slepc.err" || { echo "eigs did not report the slepc solver"; cat "$work/eigs_slepc.err"; exit 1; }
grep -q "on the distributed front end over 2 ranks" "$work/eigs_slepc.err" || { echo "eigs did not take the distributed front end"; cat "$work/eigs_slepc.err"; exit 1; }

# Plain Python (no numpy: whatever python3 is first on PATH), with solution_files.py beside this script.
python3 - "$work" "$(dirname "$0")" <<'PY'
import os, sys
work = sys.argv[1]
sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, sys.argv[2])
from solution_files import load as load_path, relative_difference as rel
def load(name):
    return load_path(os.path.join(work, name))
g0 = load("cholmod.txt")
for name, tol in (("petsc.txt", 1e-10), ("gamg.txt", 1e-6)):
    assert rel(load(name), g0) < tol, (name, rel(load(name), g0))
assert rel(load("goursat_petsc.txt"), load("goursat_cholmod.txt")) < 1e-10
e0, e = load("eigs_serial.txt"), load("eigs_slepc.txt")
assert len(e) == 12, len(e)  # printed by rank 0 only
assert rel(e, e0) < 1e-8, rel(e, e0)
print("petsc CLI: solve (distributed and serial front ends) and eigs under mpirun -np 2 equal the serial results")
PY
