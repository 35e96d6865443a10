#!/usr/bin/env bash
# The paper's §4 figures and tables reproduced (docs/paper.md): each part runs corrlap's commands,
# writes its tables as Markdown and its pictures under OUT, and copies what the docs show into
# docs/images/paper/ (with --docs).
#
#   scripts/paper_figures.sh [--docs] [OUT_DIR]        (default OUT_DIR corrlap-paper-figures)
#
# Parts:
#   fig11  no attachment (alpha0 = 0) against the default (10): the study's distances and curvature
#          errors on the three shapes, and the torus coloured by its signed distance to the truth.
#   fig12  the bunny at 256^3 (scripts/fetch_bunny.sh; network the first time): the staircase,
#          the baseline [17], corrected (fem) and uncorrected (polydec), drawn alike, with the
#          enclosed volume of each against the staircase's (a voxel count: no shrinkage).
#   fig16  reconstruction from a normal map (the bunny as its own normal map): at the paper's setting
#          (64 voxels, 3 subdivisions) and a finer one (128, 2), with the default curvature radius
#          (2 coarse voxels) and the paper's (0.2 s), corrected (fem) against uncorrected (polydec);
#          distances and normal angles to the model, and the three surfaces drawn at 64.
#   fig13  the attachment weight alpha0 swept, corrected (fem) against uncorrected (polydec) and the
#          baseline [17], on sphere1, torus and goursat at 32 and 64 voxels across: the study's CSV,
#          its plots against alpha0, a table, and goursat drawn at alpha0 = 0.1 and 1000.
#   fig14  a CAD-like part with sharp edges (scripts/cad_part.py, standing in for the fandisk) at
#          256 voxels across: [17] (with II and with convolved normals), corrected (fem) with the
#          default curvature radius and with 4 voxels, uncorrected (polydec); exact distances and
#          normal angles on the flats and at the edges, and the part drawn.
#   fig15  the regularization study (sphere1, torus, goursat at 24, 48 and 96 voxels across): the
#          distance and curvature error of each method, and goursat's plots against h.
#   fig17  the curvature-editing gallery (scripts/curvature_editing_gallery.sh) at alpha0 = 10 and
#          0.1: how far each edit moves the bunny, and the gallery at 0.1.
# Needs a built corrlap (make build, with its Python module), python3-matplotlib and python3-scipy.
# PARTS="fig11 fig13" selects parts (default all).
set -euo pipefail
cd "$(dirname "$0")/.."
CORRLAP=${CORRLAP:-build/bin/corrlap}
DOCS=0
if [ "${1:-}" = "--docs" ]; then
  DOCS=1
  shift
fi
OUT=${1:-corrlap-paper-figures}
PARTS=${PARTS:-fig11 fig12 fig13 fig14 fig15 fig16 fig17}
export PYTHONPATH="$PWD/build/python${PYTHONPATH:+:$PYTHONPATH}"
mkdir -p "$OUT"
IMAGES=docs/images/paper

# montage OUT.png ROWS COLS "picture.png|title" ...: the pictures side by side, titled.
montage() {
  /usr/bin/python3 - "$@" <<'PY'
import sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.image as mpimg
import matplotlib.pyplot as plt

out, rows, cols = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
panels = [entry.split("|", 1) for entry in sys.argv[4:]]
fig, axes = plt.subplots(rows, cols, figsize=(4 * cols, 4.2 * rows), squeeze=False)
for ax, (path, title) in zip(axes.flat, panels):
    ax.imshow(mpimg.imread(path))
    ax.set_title(title, fontsize=10)
    ax.axis("off")
fig.tight_layout()
fig.savefig(out, dpi=90)
PY
}

# publish PICTURE NAME: with --docs, copies the picture to docs/images/paper/NAME.
publish() {
  if [ "$DOCS" = 1 ]; then
    mkdir -p "$IMAGES"
    cp "$1" "$IMAGES/$2"
  fi
}

fig11() {
  local dir="$OUT/fig11"
  mkdir -p "$dir"
  "$CORRLAP" study regularization --shapes sphere1,torus,goursat --resolutions 32,64 --alpha0 0,10 \
    --methods fem,polydec --overwrite --no-plots --out "$dir/study" 2>"$dir/study.log" >/dev/null
  /usr/bin/python3 - "$dir/study/regularization.csv" >"$dir/table.md" <<'PY'
import csv
import sys

rows = list(csv.DictReader(open(sys.argv[1])))
print("| shape | N | staircase distance | fem α₀ = 0 | fem α₀ = 10 | polydec α₀ = 0 | polydec α₀ = 10 |"
      " fem \\|ΔH\\| α₀ = 0 | fem \\|ΔH\\| α₀ = 10 |")
print("|---|---|---|---|---|---|---|---|---|")
for shape in ("sphere1", "torus", "goursat"):
    for n in ("32", "64"):
        by = {(r["method"], float(r["alpha0"])): r for r in rows if r["shape"] == shape and r["resolution"] == n}
        if not by:
            continue
        d = lambda m, a: f"{float(by[(m, a)]['distance_after']):.3g}"
        e = lambda m, a: f"{float(by[(m, a)]['curvature_error_after']):.3g}"
        first = by[("fem", 0.0)]
        print(f"| {shape} | {n} | {float(first['distance_before']):.3g} | {d('fem', 0.0)} | {d('fem', 10.0)} | "
              f"{d('polydec', 0.0)} | {d('polydec', 10.0)} | {e('fem', 0.0)} | {e('fem', 10.0)} |")
PY
  # The torus (R = 6, r = 2, about the z axis) at 64 voxels across, coloured by the signed distance.
  for a in 0 10; do
    "$CORRLAP" regularize --shape torus --h 0.25 --bbox -10 10 --alpha0 "$a" --no-render --no-view --out "$dir/torus_$a" \
      >/dev/null 2>"$dir/torus_$a.log"
  done
  /usr/bin/python3 - "$dir" <<'PY'
import sys
import numpy as np
import corrlap

d = sys.argv[1]
def signed_distance(V):
    ring = np.hypot(V[:, 0], V[:, 1]) - 6.0
    return np.hypot(ring, V[:, 2]) - 2.0
for name, path in (("staircase", f"{d}/torus_0/input.ply"), ("alpha0_0", f"{d}/torus_0/regularized.ply"),
                   ("alpha0_10", f"{d}/torus_10/regularized.ply")):
    V, F = corrlap.read_mesh(path)
    distance = signed_distance(V)
    corrlap.write_mesh(f"{d}/torus_{name}_distance.ply", V, F, vertex_scalars={"distance": distance})
    print(f"{name}: mean |distance| {np.abs(distance).mean():.4g}, max {np.abs(distance).max():.4g}")
PY
  local view=(--view 0.2,-1,1.1 --size 500 --scalar distance --range -0.12,0.12 --colormap diverging)
  for name in staircase alpha0_0 alpha0_10; do
    "$CORRLAP" render "$dir/torus_${name}_distance.ply" "${view[@]}" --out "$dir/torus_$name.png" \
      >/dev/null 2>>"$dir/render.log"
  done
  montage "$dir/fig11_torus.png" 1 3 "$dir/torus_staircase.png|staircase: signed distance to the torus" \
    "$dir/torus_alpha0_0.png|no attachment (α₀ = 0)" "$dir/torus_alpha0_10.png|α₀ = 10 (default)"
  publish "$dir/fig11_torus.png" fig11_torus.png
  echo "fig11: $dir/table.md, $dir/fig11_torus.png"
}

fig12() {
  local dir="$OUT/fig12"
  mkdir -p "$dir"
  [ -s "$OUT/bunny.obj" ] || scripts/fetch_bunny.sh "$OUT/bunny.obj"
  "$CORRLAP" digitize --mesh-file "$OUT/bunny.obj" --resolution 256 --volume-out "$dir/bunny256.vol" >/dev/null
  # The paper's protocol: alpha0 = 10 (regularize's default is now chosen from the data).
  local runs=("fem:--method fem --alpha0 10" "polydec:--method polydec --alpha0 10" "alignment:--baseline alignment")
  for entry in "${runs[@]}"; do
    local name=${entry%%:*} flags=${entry#*:}
    # shellcheck disable=SC2086  # the run's flags are words
    "$CORRLAP" regularize --volume "$dir/bunny256.vol" --threshold 127 $flags --no-render --no-view --output-units world \
      --out "$dir/$name" >/dev/null 2>"$dir/$name.log"
  done
  local view=(--view 0.4,0.3,1 --up 0,1,0 --size 500 --scalar none --no-legend)
  "$CORRLAP" render "$dir/fem/input.ply" "${view[@]}" --out "$dir/staircase.png" >/dev/null 2>>"$dir/render.log"
  for entry in "${runs[@]}"; do
    local name=${entry%%:*}
    "$CORRLAP" render "$dir/$name/regularized.ply" "${view[@]}" --out "$dir/$name.png" >/dev/null 2>>"$dir/render.log"
  done
  /usr/bin/python3 - "$dir" >"$dir/table.md" <<'PY'
import json
import sys
import numpy as np
import corrlap

d = sys.argv[1]
def volume(V, F):
    a, b, c, e = (V[F[:, k]] for k in range(4))
    dot = lambda x, y, z: np.einsum("ij,ij->i", x, np.cross(y, z))
    return float((dot(a, b, c) + dot(a, c, e) + dot(b, c, e) + dot(b, e, a)).sum() / 12.0)
V, F = corrlap.read_mesh(f"{d}/fem/input.ply")
staircase = volume(V, F)
print("| surface | enclosed volume / staircase's | area / staircase's | largest displacement (voxels) |")
print("|---|---|---|---|")
print("| staircase | 1 | 1 | 0 |")
for name, label in (("alignment", "[17] (alignment)"), ("fem", "corrected (fem)"), ("polydec", "uncorrected (polydec)")):
    V, F = corrlap.read_mesh(f"{d}/{name}/regularized.ply")
    m = json.load(open(f"{d}/{name}/metrics.json"))
    area = m["area_after"] / m["area_before"] if "area_after" in m else float("nan")
    shift = m.get("displacement_max", float("nan")) / m["h"]
    print(f"| {label} | {volume(V, F) / staircase:.5f} | {area:.4f} | {shift:.3g} |")
PY
  montage "$dir/fig12_bunny.png" 1 4 "$dir/staircase.png|voxels (256³)" "$dir/alignment.png|[17] (alignment)" \
    "$dir/fem.png|corrected (fem)" "$dir/polydec.png|uncorrected (polydec)"
  publish "$dir/fig12_bunny.png" fig12_bunny.png
  echo "fig12: $dir/table.md, $dir/fig12_bunny.png"
}

fig16() {
  local dir="$OUT/fig16"
  mkdir -p "$dir"
  [ -s "$OUT/bunny.obj" ] || scripts/fetch_bunny.sh "$OUT/bunny.obj"
  local setting n k size
  for setting in 64:3 128:2; do
    n=${setting%%:*}
    k=${setting#*:}
    "$CORRLAP" reconstruct --mesh-file "$OUT/bunny.obj" --resolution "$n" --subdivide "$k" --no-render --no-view \
      --out "$dir/r${n}_default" >/dev/null 2>"$dir/r${n}_default.log"
    size=$(/usr/bin/python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['size'])" \
      "$dir/r${n}_default/metrics.json")
    "$CORRLAP" reconstruct --mesh-file "$OUT/bunny.obj" --resolution "$n" --subdivide "$k" --no-render --no-view \
      --curvature-radius "$(/usr/bin/python3 -c "print(0.2 * $size)")" --out "$dir/r${n}_paper" >/dev/null \
      2>"$dir/r${n}_paper.log"
  done
  /usr/bin/python3 - "$dir" >"$dir/table.md" <<'PY'
import json
import sys

d = sys.argv[1]
print("| N, subdivisions | curvature radius | staircase: distance / angle | fem: distance / angle | polydec: distance / angle |")
print("|---|---|---|---|---|")
for n, k in ((64, 3), (128, 2)):
    for run, label in (("paper", "0.2 s (the paper's)"), ("default", "2 coarse voxels (default)")):
        m = json.load(open(f"{d}/r{n}_{run}/metrics.json"))
        f, p = m["methods"]["fem"], m["methods"]["polydec"]
        print(f"| {n}, {k} | {label}: {m['curvature_radius']:.3g} | {m['distance_mean_before']:.3g} / "
              f"{m['normal_angle_before_deg']:.3g}° | {f['distance_mean_after']:.3g} / {f['normal_angle_after_deg']:.3g}° | "
              f"{p['distance_mean_after']:.3g} / {p['normal_angle_after_deg']:.3g}° |")
PY
  local view=(--view 0.4,0.3,1 --up 0,1,0 --size 500 --scalar none --no-legend)
  "$CORRLAP" render "$dir/r64_default/input.ply" "${view[@]}" --out "$dir/input.png" >/dev/null 2>>"$dir/render.log"
  for run in default paper; do
    for m in fem polydec; do
      "$CORRLAP" render "$dir/r64_$run/reconstructed_$m.ply" "${view[@]}" --out "$dir/${run}_$m.png" >/dev/null \
        2>>"$dir/render.log"
    done
  done
  montage "$dir/fig16_bunny.png" 1 5 "$dir/input.png|subdivided staircase (64, 3)" \
    "$dir/default_fem.png|corrected (fem), radius 2 voxels" "$dir/default_polydec.png|uncorrected (polydec), 2 voxels" \
    "$dir/paper_fem.png|fem, the paper's radius 0.2 s" "$dir/paper_polydec.png|polydec, the paper's 0.2 s"
  publish "$dir/fig16_bunny.png" fig16_bunny.png
  echo "fig16: $dir/table.md, $dir/fig16_bunny.png"
}

fig13() {
  local dir="$OUT/fig13"
  mkdir -p "$dir"
  "$CORRLAP" study regularization --shapes sphere1,torus,goursat --resolutions 32,64 \
    --alpha0 0.01,0.1,1,10,100,1000 --methods fem,polydec,alignment --overwrite --out "$dir/study" \
    2>"$dir/study.log" >/dev/null
  /usr/bin/python3 - "$dir/study/regularization.csv" >"$dir/table.md" <<'PY'
import csv
import sys

rows = list(csv.DictReader(open(sys.argv[1])))
# The true areas and volumes where they are known (sphere1: unit sphere; torus: R = 6, r = 2).
truth = {"sphere1": ("12.57", "4.189"), "torus": ("473.7", "473.7"), "goursat": ("–", "–")}
print("| shape | N | α₀ | area fem | area polydec | volume fem | volume polydec | distance fem | distance polydec |")
print("|---|---|---|---|---|---|---|---|---|")
for shape in ("sphere1", "torus", "goursat"):
    for n in ("32", "64"):
        picked = [r for r in rows if r["shape"] == shape and r["resolution"] == n]
        if not picked:
            continue
        first = picked[0]
        area, volume = truth[shape]
        print(f"| {shape} | {n} | staircase | {float(first['area_before']):.4g} (true {area}) | | "
              f"{float(first['volume_before']):.4g} (true {volume}) | | {float(first['distance_before']):.3g} | |")
        weights = sorted({float(r["alpha0"]) for r in picked if r["alpha0"]})
        for a in weights:
            by = {r["method"]: r for r in picked if r["alpha0"] and float(r["alpha0"]) == a}
            f, p = by["fem"], by["polydec"]
            print(f"| | | {a:g} | {float(f['area_after']):.4g} | {float(p['area_after']):.4g} | "
                  f"{float(f['volume_after']):.4g} | {float(p['volume_after']):.4g} | "
                  f"{float(f['distance_after']):.3g} | {float(p['distance_after']):.3g} |")
        b = [r for r in picked if r["method"] == "alignment"]
        if b:
            print(f"| | | [17] | {float(b[0]['area_after']):.4g} | | {float(b[0]['volume_after']):.4g} | | "
                  f"{float(b[0]['distance_after']):.3g} | |")
PY
  # goursat at 64 voxels across (h = 0.4 in the box [-10, 10]), as the paper's rows: alpha0 = 0.1, 1000.
  local view=(--view 1,-1.4,0.9 --size 500 --scalar none --no-legend)
  for a in 0.1 1000; do
    for m in fem polydec; do
      "$CORRLAP" regularize --shape goursat --h 0.4 --bbox -10 10 --method "$m" --alpha0 "$a" --no-render --no-view \
        --out "$dir/goursat_${m}_$a" >/dev/null 2>"$dir/goursat_${m}_$a.log"
      "$CORRLAP" render "$dir/goursat_${m}_$a/regularized.ply" "${view[@]}" --out "$dir/goursat_${m}_$a.png" \
        >/dev/null 2>>"$dir/render.log"
    done
  done
  montage "$dir/fig13_goursat.png" 2 2 "$dir/goursat_fem_0.1.png|corrected (fem), α₀ = 0.1" \
    "$dir/goursat_polydec_0.1.png|uncorrected (polydec), α₀ = 0.1" "$dir/goursat_fem_1000.png|corrected (fem), α₀ = 1000" \
    "$dir/goursat_polydec_1000.png|uncorrected (polydec), α₀ = 1000"
  publish "$dir/fig13_goursat.png" fig13_goursat.png
  # The plots at the finer step (64 voxels across) of sphere1 and the torus.
  local shape q finest
  for shape in sphere1 torus; do
    for q in area distance; do
      finest=$(ls "$dir/study/plots/alpha0_${shape}_h"*"_$q.png" | sed 's/.*_h\([0-9.e-]*\)_.*/\1 &/' | sort -g |
        head -1 | cut -d' ' -f2)
      publish "$finest" "fig13_${shape}_64_$q.png"
    done
  done
  echo "fig13: $dir/table.md, $dir/fig13_goursat.png, $dir/study/plots/"
}

fig14() {
  local dir="$OUT/fig14"
  mkdir -p "$dir"
  /usr/bin/python3 scripts/cad_part.py write "$dir/part.obj"
  local common=(--mesh-file "$dir/part.obj" --resolution 256 --no-render --no-view)
  # The paper's protocol: alpha0 = 10; fem_auto is regularize's default, alpha0 chosen from the data.
  "$CORRLAP" regularize "${common[@]}" --method fem --alpha0 10 --out "$dir/fem" >/dev/null 2>"$dir/fem.log"
  local h r4
  h=$(/usr/bin/python3 -c "import json,sys; print(repr(json.load(open(sys.argv[1]))['h']))" "$dir/fem/metrics.json")
  r4=$(/usr/bin/python3 -c "print(repr(4 * $h))")
  local runs=("fem_r4:--method fem --alpha0 10 --curvature-radius $r4" "polydec:--method polydec --alpha0 10"
    "fem_auto:--method fem"
    "alignment:--baseline alignment" "alignment_convolved:--baseline alignment --normals convolved")
  for entry in "${runs[@]}"; do
    local name=${entry%%:*} flags=${entry#*:}
    # shellcheck disable=SC2086  # the run's flags are words
    "$CORRLAP" regularize "${common[@]}" $flags --out "$dir/$name" >/dev/null 2>"$dir/$name.log"
  done
  local names=(staircase:fem/input.ply alignment_convolved:alignment_convolved/regularized.ply
    alignment:alignment/regularized.ply fem:fem/regularized.ply fem_r4:fem_r4/regularized.ply
    polydec:polydec/regularized.ply fem_auto:fem_auto/regularized.ply)
  for entry in "${names[@]}"; do
    /usr/bin/python3 scripts/cad_part.py measure "$dir/${entry#*:}" "$h" >"$dir/${entry%%:*}.json"
  done
  /usr/bin/python3 - "$dir" "$h" >"$dir/table.md" <<'PY'
import json
import sys

d, h = sys.argv[1], float(sys.argv[2])
curvature = json.load(open(f"{d}/fem/metrics.json"))["curvature_radius"]
rows = (("staircase", "staircase"), ("alignment_convolved", "[17], convolved normals (the reference's test)"),
        ("alignment", "[17], II normals"), ("fem", f"corrected (fem), curvature radius {curvature / h:.3g} voxels (default)"),
        ("fem_r4", "corrected (fem), curvature radius 4 voxels"), ("polydec", "uncorrected (polydec), default radius"),
        ("fem_auto", "corrected (fem), default radius, alpha0 chosen from the data (regularize's default)"))
print("| surface | mean / max distance (voxels) | normal angle: edges (< 4 voxels) | near (4–16) | flats (≥ 16) |"
      " area / part's | volume / part's |")
print("|---|---|---|---|---|---|---|")
for name, label in rows:
    m = json.load(open(f"{d}/{name}.json"))
    a = m["angle_deg"]
    print(f"| {label} | {m['distance_mean_vox']:.3g} / {m['distance_max_vox']:.3g} | {a['edges']:.3g}° | "
          f"{a['near']:.3g}° | {a['flats']:.3g}° | {m['area_ratio']:.4f} | {m['volume_ratio']:.4f} |")
PY
  local view=(--view 1,-0.8,1.2 --size 500 --scalar none --no-legend)
  "$CORRLAP" render "$dir/fem/input.ply" "${view[@]}" --out "$dir/staircase.png" >/dev/null 2>>"$dir/render.log"
  for name in alignment_convolved fem fem_r4 polydec; do
    "$CORRLAP" render "$dir/$name/regularized.ply" "${view[@]}" --out "$dir/$name.png" >/dev/null \
      2>>"$dir/render.log"
  done
  montage "$dir/fig14_part.png" 1 5 "$dir/staircase.png|voxels (256 across)" \
    "$dir/alignment_convolved.png|[17] (convolved normals)" "$dir/fem.png|corrected (fem), default" \
    "$dir/fem_r4.png|fem, curvature radius 4 voxels" "$dir/polydec.png|uncorrected (polydec)"
  publish "$dir/fig14_part.png" fig14_part.png
  echo "fig14: $dir/table.md, $dir/fig14_part.png"
}

fig15() {
  local dir="$OUT/fig15"
  mkdir -p "$dir"
  "$CORRLAP" study regularization --shapes sphere1,torus,goursat --resolutions 24,48,96 \
    --methods fem,polydec,alignment --overwrite --out "$dir/study" 2>"$dir/study.log" >/dev/null
  /usr/bin/python3 - "$dir/study/regularization.csv" >"$dir/table.md" <<'PY'
import csv
import sys

rows = list(csv.DictReader(open(sys.argv[1])))
print("| shape | N | h | vertices | distance: staircase → fem | polydec | [17] | curvature error: staircase → fem |"
      " polydec | [17] |")
print("|---|---|---|---|---|---|---|---|---|---|")
for shape in ("sphere1", "torus", "goursat"):
    for n in ("24", "48", "96"):
        by = {r["method"]: r for r in rows if r["shape"] == shape and r["resolution"] == n}
        if not by:
            continue
        f, p, b = by["fem"], by["polydec"], by["alignment"]
        g = lambda r, k: f"{float(r[k]):.3g}"
        print(f"| {shape} | {n} | {float(f['h']):.3g} | {f['vertices']} | {g(f, 'distance_before')} → "
              f"{g(f, 'distance_after')} | {g(p, 'distance_after')} | {g(b, 'distance_after')} | "
              f"{g(f, 'curvature_error_before')} → {g(f, 'curvature_error_after')} | "
              f"{g(p, 'curvature_error_after')} | {g(b, 'curvature_error_after')} |")
PY
  local q
  for q in distance curvature; do
    publish "$dir/study/plots/regularization_goursat_$q.png" "fig15_goursat_$q.png"
  done
  echo "fig15: $dir/table.md, $dir/study/plots/"
}

fig17() {
  local dir="$OUT/fig17"
  mkdir -p "$dir"
  [ -s "$OUT/bunny.obj" ] || scripts/fetch_bunny.sh "$OUT/bunny.obj"
  local a
  for a in 10 0.1; do
    mkdir -p "$dir/alpha0_$a"
    cp "$OUT/bunny.obj" "$dir/alpha0_$a/bunny.obj"
    ALPHA0=$a CORRLAP=$CORRLAP scripts/curvature_editing_gallery.sh "$dir/alpha0_$a" >"$dir/alpha0_$a.log" 2>&1
  done
  # How far each edit moves the surface from the unedited result (the same vertices), in voxels.
  /usr/bin/python3 - "$dir" >"$dir/table.md" <<'PY'
import json
import sys
import numpy as np
import corrlap

d = sys.argv[1]
edits = (("h_scale_2", "H × 2"), ("h_clamp_5", "H clamped to [−5, 5]"), ("k2_scale_2", "larger principal curvature × 2"),
         ("k1_set_0", "smaller principal curvature = 0"))
print("| edit | mean / max move at α₀ = 10 (voxels) | at α₀ = 0.1 |")
print("|---|---|---|")
for name, label in edits:
    cells = []
    for a in ("10", "0.1"):
        plain, _ = corrlap.read_mesh(f"{d}/alpha0_{a}/plain/regularized.ply")
        edited, _ = corrlap.read_mesh(f"{d}/alpha0_{a}/{name}/regularized.ply")
        h = json.load(open(f"{d}/alpha0_{a}/plain/metrics.json"))["h"]
        move = np.linalg.norm(edited - plain, axis=1) / h
        cells.append(f"{move.mean():.3g} / {move.max():.3g}")
    print(f"| {label} | {cells[0]} | {cells[1]} |")
PY
  publish "$dir/alpha0_10/curvature_editing_bunny.png" fig17_bunny_alpha0_10.png
  publish "$dir/alpha0_0.1/curvature_editing_bunny.png" fig17_bunny.png
  echo "fig17: $dir/table.md, $dir/alpha0_*/curvature_editing_bunny.png"
}

for part in $PARTS; do
  case "$part" in
    fig11) fig11 ;;
    fig12) fig12 ;;
    fig13) fig13 ;;
    fig14) fig14 ;;
    fig15) fig15 ;;
    fig16) fig16 ;;
    fig17) fig17 ;;
    *)
      echo "paper_figures: unknown part '$part' (known: fig11 fig12 fig13 fig14 fig15 fig16 fig17)" >&2
      exit 2
      ;;
  esac
done
