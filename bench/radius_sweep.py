#!/usr/bin/env python3
"""II radius sweep for `corrlap regularize` on digitized analytic shapes (docs/regularization.md,
"Default radii"). Each shape is digitized as an implicit input at the step h that puts N voxels
across it, so that the result can be measured against the true surface (metrics.json's
distance_l1_*), exactly as a volume of that shape with the same h would be regularized. The II
radius is given in voxels (--ii-alpha 1, R = k h); "paper" is the paper's 3 h^(1/3).

    python3 bench/radius_sweep.py [--cli build/bin/corrlap] [--quick]

Prints a markdown table: per shape and N, the mean distance to the true surface after
regularization in voxels (before: the staircase), or the error that stopped the run.
"""
import argparse
import json
import os
import subprocess
import tempfile
import time

# name, CLI input, extent across (world units) to divide into N voxels, digitization box
SHAPES = [
    ("sphere (r 1)", ["--shape", "sphere1"], 2.0, (-1.5, 1.5)),
    ("ellipsoid (1, 0.5, 0.33)", ["--polynomial", "x^2+4*y^2+9*z^2-1"], 2.0, (-1.5, 1.5)),
    ("torus (R 1, r 0.3)", ["--polynomial", "(x^2+y^2+z^2+1-0.09)^2-4*(x^2+y^2)"], 2.6, (-1.5, 1.5)),
]
RADII = ["2", "3", "4", "6", "8", "12", "paper"]


def run(cli, args, out):
    t0 = time.time()
    p = subprocess.run([cli, "regularize", *args, "--no-render", "--no-view", "--out", out], capture_output=True, text=True)
    seconds = time.time() - t0
    if p.returncode != 0:
        lines = [l for l in p.stderr.splitlines() if l.strip()]
        return None, seconds, (lines[-1] if lines else "exit %d" % p.returncode)
    with open(os.path.join(out, "metrics.json")) as f:
        return json.load(f), seconds, None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cli", default=os.path.join(os.path.dirname(__file__), "..", "build", "bin", "corrlap"))
    ap.add_argument("--sizes", default="64,128", help="voxels across, comma-separated")
    ap.add_argument("--large", default="256", help="voxels across for the sphere only, radii 3 4 6")
    args = ap.parse_args()
    sizes = [int(s) for s in args.sizes.split(",") if s]
    runs = [(shape, n, RADII) for shape in SHAPES for n in sizes]
    if args.large:
        runs += [(SHAPES[0], int(n), ["3", "4", "6"]) for n in args.large.split(",")]
    print("| shape | N | before | " + " | ".join("r = " + r for r in RADII) + " |")
    print("|---|---|---|" + "---|" * len(RADII))
    total = time.time()
    with tempfile.TemporaryDirectory() as tmp:
        for (name, source, extent, box), n, radii in runs:
            h = extent / n
            cells, before = {}, ""
            for r in radii:
                ii = ["--ii-radius", "3", "--ii-alpha", "0.33"] if r == "paper" else ["--ii-radius", r, "--ii-alpha", "1"]
                m, seconds, error = run(args.cli, [*source, "--h", repr(h), "--bbox", str(box[0]), str(box[1]),
                                                   "--normals", "ii", *ii], os.path.join(tmp, "out"))
                if m is None:
                    cells[r] = "fails: " + error[:60]
                else:
                    before = "%.3f" % (m["distance_l1_before"] / h)
                    cells[r] = "%.3f (%.0f s)" % (m["distance_l1_after"] / h, seconds)
            print("| %s | %d | %s | %s |" % (name, n, before, " | ".join(cells.get(r, "") for r in RADII)), flush=True)
    print("\ntotal %.0f s" % (time.time() - total))


if __name__ == "__main__":
    main()
