#!/usr/bin/python3
"""corrlap regularize's settings on the inputs of bench/compare_surfaces.py (its voxelization,
grid shifts and measures): the mean distance to the truth, in voxels, averaged over the shifts.

    /usr/bin/python3 bench/setting_sweep.py --resolution 64 --radii 0 4 5 6.5 8
    /usr/bin/python3 bench/setting_sweep.py --resolution 64 --flags "" "--alpha0 3" "--ii-radius 5"

--radii gives the curvature ball in voxels (0: corrlap's default); each becomes
--curvature-radius in the volume's world units (the longest side spans 2). --flags gives whole
flag sets; --grid runs every flag set with every radius. The bunny (--bunny) is voxelized once, the
analytic shapes --shifts times."""
import argparse
import os
import shlex
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import compare_surfaces as cs  # noqa: E402
import surface_truth as st  # noqa: E402

cs.st = st


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--resolution", type=int, default=64, help="voxels across (default 64)")
    ap.add_argument("--shapes", nargs="*", default=list(st.SHAPES), choices=list(st.SHAPES))
    ap.add_argument("--bunny", default="", help="closed triangle mesh voxelized as the model input ('' for none)")
    ap.add_argument("--radii", nargs="*", type=float, default=[], help="curvature radii in voxels (0: the default)")
    ap.add_argument("--flags", nargs="*", default=[], help="flag sets of corrlap regularize, each one string")
    ap.add_argument("--shifts", type=int, default=3)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--corrlap", default=cs.default_cli())
    ap.add_argument("--work", default="setting_sweep_work", help="directory of the volumes and outputs")
    ap.add_argument("--grid", action="store_true",
                    help="every flag set with every radius (--flags x --radii) instead of each on its own")
    args = ap.parse_args()
    args.shift = None
    if args.grid and not (args.radii and args.flags):
        ap.error("--grid runs every flag set with every radius: give both --flags and --radii")
    if args.grid:
        variants = [("[%s] r=%s" % (f, "%g" % r if r else "default"), r, shlex.split(f))
                    for f in args.flags for r in args.radii]
    else:
        variants = [("r=%g" % r if r else "default", r, []) for r in args.radii]
        variants += [("[%s]" % f, 0.0, shlex.split(f)) for f in args.flags]
    if not variants:
        ap.error("give --radii or --flags")
    inputs = [(name, k, shift) for name in args.shapes for k, shift in enumerate(cs.grid_shifts(args))]
    if args.bunny:
        inputs.append(("bunny", 0, None))
    results = {}
    for name, k, shift in inputs:
        work = os.path.join(args.work, "%s_%d_s%d" % (name, args.resolution, k))
        os.makedirs(work, exist_ok=True)
        volume = os.path.join(work, "volume.npy")
        h, origin, measure = cs.prepare_input(name, args.resolution, shift, volume, args.bunny)
        world_step = 2.0 / max(np.load(volume, mmap_mode="r").shape)
        for i, (label, radius, flags) in enumerate(variants):
            if radius:
                flags = flags + ["--curvature-radius", repr(radius * world_step)]
            mesh, _, info = cs.run_corrlap(args.corrlap, volume, "v%d" % i, flags, work)
            value = float("nan") if mesh is None else measure(*cs.to_world(mesh, h, origin))["mean_dist_vox"]
            results.setdefault((name, label), []).append(value)
    print("| input | " + " | ".join(v[0] for v in variants) + " |")
    print("|---" * (len(variants) + 1) + "|")
    for name in dict.fromkeys(n for n, _, _ in inputs):
        print("| %s | " % name + " | ".join("%.4f" % np.mean(results[(name, v[0])]) for v in variants) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
