#!/usr/bin/python3
"""`corrlap regularize --volume F` on voxelized CAD-like parts with thin features, per II radius
(docs/regularization.md, "Default radii"): whether the run succeeds and the mean / largest distance
of the result to the part the voxels were made from, in voxels.

    python3 bench/thin_parts.py [--cli build/bin/corrlap]

The parts (voxel k inside iff its centre k is inside; outputs read back in voxel units):
- "bracket": an L of two boxes (a 56x40x10 base and a 6-voxel thick, 24-voxel high wall);
- "fin": a 64x48x12 block with a 3-voxel thick, 20-voxel high fin on top;
  (box faces 0.2 voxel off the voxel centres' half-way planes, as a part placed anywhere would be);
- "two balls": two balls of radius 7 voxels in a 40x20x20 volume.
"""
import argparse
import os
import subprocess
import tempfile
import time

import numpy as np

try:  # for the staircase's distance (input.ply); PYTHONPATH=build/python
    import corrlap
except ImportError:
    corrlap = None


def box_sdf(p, lo, hi):
    c, e = (np.array(lo) + np.array(hi)) / 2, (np.array(hi) - np.array(lo)) / 2
    q = np.abs(p - c) - e
    return np.linalg.norm(np.maximum(q, 0), axis=1) + np.minimum(q.max(axis=1), 0)


def ball_sdf(p, c, r):
    return np.linalg.norm(p - np.array(c), axis=1) - r


PARTS = {
    "bracket": ((72, 56, 44), lambda p: np.minimum(box_sdf(p, (8.2, 8.2, 8.2), (63.8, 47.8, 17.8)),
                                                   box_sdf(p, (8.2, 8.2, 17.8), (63.8, 14.2, 41.8)))),
    "fin": ((80, 64, 44), lambda p: np.minimum(box_sdf(p, (8.2, 8.2, 8.2), (71.8, 55.8, 19.8)),
                                               box_sdf(p, (8.2, 30.3, 19.8), (71.8, 33.3, 39.8)))),
    "two balls": ((40, 20, 20), lambda p: np.minimum(ball_sdf(p, (9.5, 9.5, 9.5), 7), ball_sdf(p, (29.5, 9.5, 9.5), 7))),
}
RADII = ["2", "3", "4", "6", "8", "paper"]


def write_vol(path, inside):
    nx, ny, nz = inside.shape
    header = "Center-X: 0\nCenter-Y: 0\nCenter-Z: 0\nX: %d\nY: %d\nZ: %d\nVoxel-Size: 1\nAlpha-Color: 0\n" \
             "Voxel-Endian: 0\nInt-Endian: 0123\nVersion: 2\n.\n" % (nx, ny, nz)
    with open(path, "wb") as f:
        f.write(header.encode())
        f.write((inside.transpose(2, 1, 0) * 255).astype(np.uint8).tobytes())  # x fastest


def read_obj_vertices(path):
    with open(path) as f:
        return np.array([[float(t) for t in l.split()[1:4]] for l in f if l.startswith("v ")])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cli", default=os.path.join(os.path.dirname(__file__), "..", "build", "bin", "corrlap"))
    ap.add_argument("--radii", default=",".join(RADII))
    args = ap.parse_args()
    radii = args.radii.split(",")
    print("| part | before | " + " | ".join("r = " + r for r in radii) + " |")
    print("|---|---|" + "---|" * len(radii))
    with tempfile.TemporaryDirectory() as tmp:
        for name, (size, sdf) in PARTS.items():
            grid = np.stack(np.meshgrid(*[np.arange(n, dtype=float) for n in size], indexing="ij"), -1)
            inside = (sdf(grid.reshape(-1, 3)) <= 0).reshape(size)
            vol = os.path.join(tmp, "part.vol")
            write_vol(vol, inside)
            cells, before = [], ""
            for r in radii:
                ii = ["--ii-radius", "3", "--ii-alpha", "0.33"] if r == "paper" else ["--ii-radius", r, "--ii-alpha", "1"]
                out = os.path.join(tmp, "out")
                t0 = time.time()
                p = subprocess.run([args.cli, "regularize", "--volume", vol, "--threshold", "127", *ii, "--output-units", "voxels", "--no-render", "--no-view", "--out", out],
                                   capture_output=True, text=True)
                seconds = time.time() - t0
                if p.returncode != 0:
                    lines = [l for l in p.stderr.splitlines() if l.strip()]
                    cells.append("fails: " + (lines[-1][:70] if lines else ""))
                    continue
                if corrlap is not None:
                    before = "%.3f / %.2f" % tuple(
                        (lambda d: (d.mean(), d.max()))(np.abs(sdf(corrlap.read_mesh(os.path.join(out, "input.ply"))[0]))))
                d = np.abs(sdf(read_obj_vertices(os.path.join(out, "regularized.obj"))))
                cells.append("%.3f / %.2f (%.0f s)" % (d.mean(), d.max(), seconds))
            print("| %s | %s | %s |" % (name, before, " | ".join(cells)), flush=True)


if __name__ == "__main__":
    main()
