#!/usr/bin/env bash
# Paper Fig. 17/18 on a voxelized model: the Stanford bunny at 256^3 regularized as it is and with
# curvature edits (H scaled, H clamped, principal curvatures edited), each result drawn from the
# same view on one colour range, then put side by side in one picture (docs/regularization.md).
#
#   scripts/curvature_editing_gallery.sh [OUT_DIR] [OUT_PNG]
#
# ALPHA0 (default 10, the regularization's) is the attachment weight of every run: at 10 the edited
# shapes stay near the input and differ mostly in colour; at 0.1 the edits move the surface by
# voxels (docs/regularization.md, "Curvature editing"). RESOLUTION (default 256) is the bunny's.
#
# Needs a built corrlap (make build), network access for the bunny the first time
# (scripts/fetch_bunny.sh) and python3-matplotlib for the montage. Under a minute on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
CORRLAP=${CORRLAP:-build/bin/corrlap}
OUT=${1:-corrlap-curvature-editing}
PNG=${2:-$OUT/curvature_editing_bunny.png}
RESOLUTION=${RESOLUTION:-256}
ALPHA0=${ALPHA0:-10}
mkdir -p "$OUT"
[ -s "$OUT/bunny.obj" ] || scripts/fetch_bunny.sh "$OUT/bunny.obj"
"$CORRLAP" digitize --mesh-file "$OUT/bunny.obj" --resolution "$RESOLUTION" --volume-out "$OUT/bunny.vol" \
  --out "$OUT/bunny_voxels.obj"
# The bunny's ears are thinner than the default II radius 3 h^(1/3) (the regularization refuses
# it, naming the vertices where |H| > 1/h): radius 1 h^(1/3), 26 voxels at 256^3. Voxels touching
# along an edge at a few places of the voxelization: --allow-nonmanifold. World units (the longest
# side spans 2) for the outputs, the units the edits and the colour range are given in: in the
# volume's own units (voxels) H would be 128 times smaller.
common=(--volume "$OUT/bunny.vol" --threshold 127 --allow-nonmanifold --ii-radius 1 --alpha0 "$ALPHA0"
  --output-units world --no-render --no-view)
edits=("plain:" "h_scale_2:--h-scale 2" "h_clamp_5:--h-clamp 5" "k2_scale_2:--k2 scale:2" "k1_set_0:--k1 set:0")
for entry in "${edits[@]}"; do
  name=${entry%%:*}
  flags=${entry#*:}
  # shellcheck disable=SC2086  # the edit's flags are words
  "$CORRLAP" regularize "${common[@]}" $flags --out "$OUT/$name" 2>"$OUT/$name.log"
  echo "$name: $(grep -o '"vertices": [0-9]*' "$OUT/$name/metrics.json"), log $OUT/$name.log"
done
view=(--view 0.4,0.3,1 --up 0,1,0 --size 500 --range -10,10)
"$CORRLAP" render "$OUT/bunny_voxels.obj" "${view[@]}" --scalar none --out "$OUT/voxels.png"
for entry in "${edits[@]}"; do
  name=${entry%%:*}
  "$CORRLAP" render "$OUT/$name/regularized.ply" "${view[@]}" --out "$OUT/$name.png"
done
/usr/bin/python3 - "$OUT" "$PNG" "$RESOLUTION" "$ALPHA0" <<'PY'
import sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.image as mpimg
import matplotlib.pyplot as plt

out, png, resolution, alpha0 = sys.argv[1:5]
panels = [("voxels", f"voxels ({resolution}³)"), ("plain", "regularized"), ("h_scale_2", "H × 2"),
          ("h_clamp_5", "H clamped to [-5, 5]"), ("k2_scale_2", "larger principal curvature × 2"),
          ("k1_set_0", "smaller principal curvature = 0")]
fig, axes = plt.subplots(2, 3, figsize=(12, 8))
for ax, (name, title) in zip(axes.flat, panels):
    ax.imshow(mpimg.imread(f"{out}/{name}.png"))
    ax.set_title(title)
    ax.axis("off")
fig.suptitle(f"corrlap regularize with curvature edits (paper §4.3, Fig. 17/18), α₀ = {alpha0}; colour: H, one range")
fig.tight_layout()
fig.savefig(png, dpi=72)
print("wrote", png)
PY
