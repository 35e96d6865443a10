#!/usr/bin/env bash
# `corrlap regularize --solver petsc` under mpirun (ctest petsc_mpi_regularize): on an implicit
# shape with 1, 2 and 4 ranks, on a volume file with 2, and on two balls with 4 (a slab the surface
# does not cross), the distributed front end (each rank its slab: the curvature, the solve and the
# automatic alpha0's trials, then its part of every output) gives the serial CHOLMOD outputs: the
# surfaces to 1e-8 of the object's size, the same faces, normals, H and measures, the same
# automatic alpha0, pictures of the same size; rank 0 alone reports.
# Usage: cli_regularize_petsc.sh CORRLAP MPIEXEC WORK_DIR
set -euo pipefail
cli=$1 mpiexec=$2 work=$3
rm -rf "$work" && mkdir -p "$work"

"$cli" digitize --shape torus --h 0.4 --out "$work/torus.obj" --volume-out "$work/torus.vol" > /dev/null
# The shape with 1, 2 and 4 ranks (4 oversubscribed), the volume file with 2.
balls="(x^2+y^2+z^2-4)*((x-5)^2+y^2+z^2-4)"
for run in "2 --shape goursat --h 0.4" "1 --shape goursat --h 0.4" "4 --shape goursat --h 0.4" \
           "2 --volume $work/torus.vol" "4 --polynomial balls --h 0.25 --bbox -8 8"; do
  np=${run%% *} input=${run#* }
  name=$(echo "$input" | cut -d' ' -f2 | xargs basename)
  input=${input/balls/$balls}
  # The first run draws the pictures too.
  render=(--no-render)
  [ "$run" = "2 --shape goursat --h 0.4" ] && render=()
  [ -d "$work/$name-serial" ] ||
    # shellcheck disable=SC2086  # $input is a list of arguments
    "$cli" regularize $input "${render[@]}" --out "$work/$name-serial" 2> "$work/$name-serial.err"
  oversubscribe=()
  [ "$np" -gt 2 ] && oversubscribe=(--oversubscribe)
  # shellcheck disable=SC2086
  "$mpiexec" -n "$np" "${oversubscribe[@]}" "$cli" regularize $input "${render[@]}" --solver petsc \
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
import json, os, struct, sys

def ply(path):
    """Vertex properties (name -> list) and faces of a binary PLY with double properties and quad faces."""
    with open(path, "rb") as f:
        header = []
        while not header or header[-1] != "end_header":
            header.append(f.readline().decode().strip())
        vertices = int(next(line for line in header if line.startswith("element vertex")).split()[2])
        faces = int(next(line for line in header if line.startswith("element face")).split()[2])
        names = [line.split()[2] for line in header if line.startswith("property double")]
        row = struct.Struct("<" + "d" * len(names))
        rows = [row.unpack(f.read(row.size)) for _ in range(vertices)]
        quad = struct.Struct("<B4i")
        quads = [quad.unpack(f.read(quad.size)) for _ in range(faces)]
        assert f.read() == b"", f"{path}: trailing bytes"
    return {n: [r[k] for r in rows] for k, n in enumerate(names)}, quads

serial_dir, petsc_dir, np = sys.argv[1], sys.argv[2], sys.argv[3]
for name in ["input.ply", "regularized.ply"]:
    (a, fa), (b, fb) = ply(f"{serial_dir}/{name}"), ply(f"{petsc_dir}/{name}")
    assert sorted(a) == sorted(b), (name, sorted(a), sorted(b))
    assert fa == fb, f"{name}: the faces differ"
    size = max(max(a[k]) - min(a[k]) for k in "xyz")
    for prop in a:
        scale = {"x": size, "y": size, "z": size, "displacement": size}.get(prop, max(map(abs, a[prop])) or 1.0)
        worst = max(abs(u - v) for u, v in zip(a[prop], b[prop]))
        # Both solves stop at the same proven accuracy (a thousandth of a voxel, RMS); the MUMPS and
        # CHOLMOD factors differ by rounding only, so the iterates agree far below that. Normals and
        # H follow from positions equal to rounding.
        assert worst <= 1e-8 * scale, (name, prop, worst, scale)
    if name == "regularized.ply":
        print(f"{petsc_dir} ({np} ranks): positions within {max(abs(u - v) for k in 'xyz' for u, v in zip(a[k], b[k])) / size:.2e} of the size")
with open(f"{serial_dir}/regularized.obj") as f, open(f"{petsc_dir}/regularized.obj") as g:
    lines_a, lines_b = f.read().splitlines(), g.read().splitlines()
assert len(lines_a) == len(lines_b) and [l for l in lines_a if l[0] != "v"] == [l for l in lines_b if l[0] != "v"]

ma, mb = (json.load(open(f"{d}/metrics.json")) for d in (serial_dir, petsc_dir))
for key in ["vertices", "faces", "components", "normals", "output_units", "output_space", "method"]:
    assert ma[key] == mb[key], (key, ma[key], mb[key])
for key in ["h", "size", "curvature_radius", "alpha0", "alpha", "area_ratio", "extent_ratio", "displacement_max",
            "area_before", "area_after", "energy_initial", "energy_final", "distance_l1_before", "distance_l1_after",
            "normal_angle_deg_before", "normal_angle_deg_after", "mean_curvature_error_before",
            "mean_curvature_error_after"]:
    assert (key in ma) == (key in mb), key
    if key in ma:
        assert abs(ma[key] - mb[key]) <= 1e-6 * abs(ma[key]) + 1e-14, (key, ma[key], mb[key])
for picture in ["before.png", "after.png"]:
    if os.path.exists(f"{petsc_dir}/{picture}"):  # (the serial folder serves several runs)
        heads = [open(f"{d}/{picture}", "rb").read(24) for d in (serial_dir, petsc_dir)]
        assert heads[0][:8] == b"\x89PNG\r\n\x1a\n" and heads[0][16:24] == heads[1][16:24], picture
PY
done
