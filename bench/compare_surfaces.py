#!/usr/bin/python3
"""corrlap regularize against what people run today, on the same voxel volumes (docs/comparison.md).

Tools, each run as its own process that reads the volume (.npy) and writes a mesh (.ply):
  vtk      VTK discrete flying edges + vtkWindowedSincPolyDataFilter with 3D Slicer's
           parameterization of the smoothing factor f (f = 0: flying edges alone);
  skimage  scikit-image marching_cubes + Open3D filter_smooth_taubin (0 iterations: plain marching
           cubes);
  corrlap  `corrlap regularize` (defaults, --method polydec, --baseline alignment).
Inputs: corrlap's analytic shapes (sphere1, ellipsoid, torus, goursat) voxelized at N voxels across,
measured against the exact surface (closest points by projection), and a voxelized triangle mesh
(the bunny of scripts/fetch_bunny.sh) measured against the source mesh both ways (Open3D).

    /usr/bin/python3 bench/compare_surfaces.py --out DIR [--quick] [--resolutions 64 128 256]
        [--shapes sphere1 ellipsoid torus goursat] [--bunny data/bunny/bunny.obj] [--corrlap PATH]

Writes DIR/results.csv (one row per tool x setting x input x resolution), DIR/summary.md (the
tables of docs/comparison.md) and DIR/comparison_*.png. Wall time and peak memory are those of the
whole tool process (start, read, compute, write; the peak from GNU time); core_s is the compute alone as the
tool reports it (Python tools: after the imports and the read, before the write; corrlap: the
stages of metrics.json's time_s except write_s).
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
# The ground truth (bench/surface_truth.py) is imported by main() after the tool processes have
# branched off, so that their wall time holds only what the tool itself needs.
st = None

ROOT = os.path.dirname(HERE)
PAD = 3  # empty voxels around the shape's box, so that every surface is closed

VTK_FACTORS = [0.0, 0.25, 0.5, 0.75, 1.0]
TAUBIN_ITERATIONS = [0, 10, 50, 100]
CORRLAP_SETTINGS = [("defaults", []), ("polydec", ["--method", "polydec"]),
                    ("alignment", ["--baseline", "alignment"])]
QUICK = {"vtk": [0.0, 0.5], "skimage": [0, 10], "corrlap": CORRLAP_SETTINGS[:2]}

COLUMNS = ["tool", "setting", "input", "voxels", "shift", "h", "vertices", "triangles", "mean_dist", "max_dist",
           "mean_dist_vox", "max_dist_vox", "normal_angle_deg", "h_err_rel", "area_change",
           "volume_change", "wall_s", "core_s", "peak_mb", "staircase_max_vox", "status"]


# ---------------------------------------------------------------------------------------------
# Tool processes (this file run with --child): read the volume, compute, write the mesh, print the
# compute time as JSON.


def child_vtk(volume_path, factor, out_path):
    import vtk
    from vtk.util import numpy_support

    vol = np.load(volume_path)
    t0 = time.perf_counter()
    image = vtk.vtkImageData()
    image.SetDimensions(*vol.shape)
    # VTK's x index varies fastest: Fortran order keeps voxel (i, j, k) = vol[i, j, k].
    scalars = numpy_support.numpy_to_vtk(np.ascontiguousarray(vol.ravel(order="F")), deep=True)
    image.GetPointData().SetScalars(scalars)
    surface = vtk.vtkDiscreteFlyingEdges3D()
    surface.SetInputData(image)
    surface.SetValue(0, 1)
    surface.ComputeNormalsOff()
    surface.ComputeGradientsOff()
    surface.ComputeScalarsOff()
    surface.Update()
    result = surface.GetOutput()
    if factor > 0:
        # 3D Slicer's closed-surface smoothing (vtkBinaryLabelmapToClosedSurfaceConversionRule).
        smoother = vtk.vtkWindowedSincPolyDataFilter()
        smoother.SetInputData(result)
        smoother.SetNumberOfIterations(int(round(20 + 40 * factor)))
        smoother.SetPassBand(10.0 ** (-4.0 * factor))
        smoother.BoundarySmoothingOff()
        smoother.FeatureEdgeSmoothingOff()
        smoother.NonManifoldSmoothingOn()
        smoother.NormalizeCoordinatesOn()
        smoother.Update()
        result = smoother.GetOutput()
    core = time.perf_counter() - t0
    writer = vtk.vtkPLYWriter()
    writer.SetFileName(out_path)
    writer.SetFileTypeToBinary()
    writer.SetInputData(result)
    writer.Write()
    print(json.dumps({"core_s": core}))


def child_skimage(volume_path, iterations, out_path):
    import open3d as o3d
    from skimage import measure

    vol = np.load(volume_path)
    t0 = time.perf_counter()
    verts, faces, _, _ = measure.marching_cubes(vol, level=0.5)
    mesh = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(verts.astype(np.float64)),
                                     o3d.utility.Vector3iVector(faces.astype(np.int32)))
    if iterations > 0:
        mesh = mesh.filter_smooth_taubin(number_of_iterations=int(iterations))
    core = time.perf_counter() - t0
    o3d.io.write_triangle_mesh(out_path, mesh, write_ascii=False)
    print(json.dumps({"core_s": core}))


# ---------------------------------------------------------------------------------------------
# Running a tool


GNU_TIME = "/usr/bin/time"


def run_tool(cmd):
    """Runs cmd; returns its exit code, stdout, stderr, wall seconds and peak resident MB.
    The peak comes from GNU time around the tool: a process's own rusage (os.wait4) would not do,
    since Linux carries the high-water mark of the process that forked it (this script, holding the
    measured meshes) across exec into the child's. Without GNU time the peak is NaN."""
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        out_path, err_path, rss_path = (os.path.join(tmp, n) for n in ("out", "err", "rss"))
        wrapped = [GNU_TIME, "-f", "%M", "-o", rss_path] + cmd if os.path.exists(GNU_TIME) else cmd
        with open(out_path, "w") as out, open(err_path, "w") as err:
            t0 = time.perf_counter()
            rc = subprocess.call(wrapped, stdout=out, stderr=err)
            wall = time.perf_counter() - t0
        peak = float("nan")
        if os.path.exists(rss_path):
            lines = [ln for ln in open(rss_path).read().splitlines() if ln.strip()]
            peak = float(lines[-1]) / 1024.0  # KB; an exit status line, if any, comes before
        with open(out_path) as fo, open(err_path) as fe:
            return rc, fo.read(), fe.read(), wall, peak


def last_line(text):
    lines = [ln for ln in text.splitlines() if ln.strip()]
    return lines[-1] if lines else ""


def run_vtk(volume, factor, workdir):
    out = os.path.join(workdir, "vtk_f%g.ply" % factor)
    rc, so, se, wall, mb = run_tool([sys.executable, __file__, "--child", "vtk", volume, str(factor), out])
    if rc != 0:
        return None, {"status": "vtk exit %d: %s" % (rc, last_line(se))}
    return out, {"wall_s": wall, "peak_mb": mb, "core_s": json.loads(last_line(so))["core_s"]}


def run_skimage(volume, iterations, workdir):
    out = os.path.join(workdir, "skimage_taubin%d.ply" % iterations)
    rc, so, se, wall, mb = run_tool([sys.executable, __file__, "--child", "skimage", volume,
                                     str(iterations), out])
    if rc != 0:
        return None, {"status": "skimage exit %d: %s" % (rc, last_line(se))}
    return out, {"wall_s": wall, "peak_mb": mb, "core_s": json.loads(last_line(so))["core_s"]}


def run_corrlap(cli, volume, name, flags, workdir):
    out = os.path.join(workdir, "corrlap_" + name)
    # --allow-nonmanifold: a voxelized model can touch itself along an edge; it permits such a
    # surface and changes no parameter.
    cmd = [cli, "regularize", "--volume", volume, "--threshold", "0", "--allow-nonmanifold", "--no-render", "--no-view",
           "--out", out] + flags
    rc, so, se, wall, mb = run_tool(cmd)
    if rc != 0:
        return None, None, {"status": "corrlap exit %d: %s" % (rc, last_line(se))}
    with open(os.path.join(out, "metrics.json")) as fh:
        metrics = json.load(fh)
    core = sum(v for k, v in metrics.get("time_s", {}).items() if k != "write_s")
    return (os.path.join(out, "regularized.ply"), os.path.join(out, "input.ply"),
            {"wall_s": wall, "peak_mb": mb, "core_s": core})


# ---------------------------------------------------------------------------------------------
# Inputs: a voxel volume (.npy, voxel (i, j, k) = array[i, j, k], 1 inside) and the map from voxel
# indices to the truth's coordinates, x = origin + h * index.


def voxelize_shape(shape, voxels, path, shift=(0.0, 0.0, 0.0)):
    """The shape's voxels at N = `voxels` across; `shift` (in voxels, each within [-0.5, 0.5]) moves
    the grid against the shape. With no shift the grid is centred on the shape's centre, so points
    of the shapes' extremes fall on voxel centres (the sphere's poles, the torus's tube top), where
    inside and outside are decided by a tie. The studies draw the centre at random (docs/math.md
    §10.1); so does the harness by default (--shifts)."""
    h = shape.grid_step(voxels)
    n = int(math.ceil(2.0 * shape.half_extent / h)) + 1 + 2 * PAD
    origin = np.array([-(n - 1) / 2.0 * h + s * h for s in shift])
    axes = [origin[j] + h * np.arange(n) for j in range(3)]
    inside = np.zeros((n, n, n), dtype=np.uint8)
    for i in range(n):  # slab by slab: a 256-voxel shape would need GBs at once
        yy, zz = np.meshgrid(axes[1], axes[2], indexing="ij")
        pts = np.stack([np.full(yy.size, axes[0][i]), yy.ravel(), zz.ravel()], axis=1)
        inside[i] = (shape.f(pts) <= 0.0).reshape(n, n)
    np.save(path, inside)
    return h, origin


def voxelize_mesh(mesh_path, voxels, path):
    """Voxel centres inside the closed triangle mesh, by VTK's vtkPolyDataToImageStencil (what 3D
    Slicer uses to turn a model into a labelmap)."""
    import vtk
    from vtk.util import numpy_support

    verts, tris = st.read_mesh(mesh_path)
    lo, hi = verts.min(0), verts.max(0)
    h = float((hi - lo).max()) / voxels
    dims = np.ceil((hi - lo) / h).astype(int) + 1 + 2 * PAD
    origin = (lo + hi) / 2.0 - (dims - 1) / 2.0 * h
    poly = vtk.vtkPolyData()
    points = vtk.vtkPoints()
    points.SetData(numpy_support.numpy_to_vtk(verts, deep=True))
    poly.SetPoints(points)
    cells = vtk.vtkCellArray()
    cells.SetCells(len(tris), numpy_support.numpy_to_vtkIdTypeArray(
        np.hstack([np.full((len(tris), 1), 3), tris]).astype(np.int64).ravel(), deep=True))
    poly.SetPolys(cells)
    stencil = vtk.vtkPolyDataToImageStencil()
    stencil.SetInputData(poly)
    stencil.SetOutputOrigin(*origin)
    stencil.SetOutputSpacing(h, h, h)
    stencil.SetOutputWholeExtent(0, dims[0] - 1, 0, dims[1] - 1, 0, dims[2] - 1)
    ones = vtk.vtkImageData()
    ones.SetOrigin(*origin)
    ones.SetSpacing(h, h, h)
    ones.SetDimensions(*dims)
    ones.AllocateScalars(vtk.VTK_UNSIGNED_CHAR, 1)
    ones.GetPointData().GetScalars().Fill(1)
    cut = vtk.vtkImageStencil()
    cut.SetInputData(ones)
    cut.SetStencilConnection(stencil.GetOutputPort())
    cut.ReverseStencilOff()
    cut.SetBackgroundValue(0)
    cut.Update()
    flat = numpy_support.vtk_to_numpy(cut.GetOutput().GetPointData().GetScalars())
    inside = np.ascontiguousarray(flat.reshape(tuple(dims), order="F")).astype(np.uint8)
    if not inside.any():
        raise SystemExit("compare_surfaces: %s: no voxel inside the mesh (is it closed?)" % mesh_path)
    np.save(path, inside)
    return h, origin, verts, tris


def mesh_measures(src_verts, src_tris, verts, tris, h, samples=200000):
    """Distances sampled both ways between a mesh and the source mesh (Open3D), the normal angle
    to the source triangle nearest each sample, area and volume change against the source."""
    import open3d as o3d

    def scene_of(v, t):
        s = o3d.t.geometry.RaycastingScene()
        s.add_triangles(o3d.core.Tensor(v.astype(np.float32)), o3d.core.Tensor(t.astype(np.uint32)))
        return s

    def sample(v, t, n, rng):
        cross, area, _ = st.triangle_geometry(v, t)
        pick = rng.choice(len(t), size=n, p=area / area.sum())
        r1, r2 = rng.random(n), rng.random(n)
        s = np.sqrt(r1)
        a, b, c = v[t[pick, 0]], v[t[pick, 1]], v[t[pick, 2]]
        pts = (1 - s)[:, None] * a + (s * (1 - r2))[:, None] * b + (s * r2)[:, None] * c
        return pts, cross[pick] / np.maximum(area[pick], 1e-300)[:, None]

    rng = np.random.default_rng(0)
    tris = st.orient_outwards(verts, tris)
    src_tris = st.orient_outwards(src_verts, src_tris)
    src_scene, out_scene = scene_of(src_verts, src_tris), scene_of(verts, tris)
    pts, nrm = sample(verts, tris, samples, rng)
    closest = src_scene.compute_closest_points(o3d.core.Tensor(pts.astype(np.float32)))
    d_out = np.linalg.norm(closest["points"].numpy() - pts, axis=1)
    src_cross, src_area, _ = st.triangle_geometry(src_verts, src_tris)
    src_n = src_cross / np.maximum(src_area, 1e-300)[:, None]
    cosang = np.clip((nrm * src_n[closest["primitive_ids"].numpy()]).sum(1), -1, 1)
    spts, _ = sample(src_verts, src_tris, samples, rng)
    d_src = out_scene.compute_distance(o3d.core.Tensor(spts.astype(np.float32))).numpy()
    mean = 0.5 * (float(d_out.mean()) + float(d_src.mean()))
    mx = max(float(d_out.max()), float(d_src.max()))
    area = float(st.triangle_geometry(verts, tris)[1].sum())
    return {"mean_dist": mean, "max_dist": mx, "mean_dist_vox": mean / h, "max_dist_vox": mx / h,
            "max_dist_to_truth_vox": float(d_out.max()) / h,
            "normal_angle_deg": float(np.degrees(np.arccos(cosang)).mean()), "h_err_rel": float("nan"),
            "area_change": area / float(src_area.sum()) - 1.0,
            "volume_change": st.signed_volume(verts, tris) / st.signed_volume(src_verts, src_tris) - 1.0}


# ---------------------------------------------------------------------------------------------
# The benchmark


def to_world(mesh_path, h, origin):
    verts, tris = st.read_mesh(mesh_path)
    return origin + h * verts, tris


def staircase_error(measure, path, h, origin):
    """Largest distance, in voxels, from a tool's unsmoothed mesh to the truth: below one voxel when
    the tool's coordinates are mapped correctly (a wrong axis order or half-voxel shift shows). One
    way only: a model's details thinner than a voxel are missing from every voxelization."""
    verts, tris = to_world(path, h, origin)
    m = measure(verts, tris)
    return m.get("max_dist_to_truth_vox", m["max_dist_vox"])


def settings_for(quick):
    if quick:
        return QUICK["vtk"], QUICK["skimage"], QUICK["corrlap"]
    return VTK_FACTORS, TAUBIN_ITERATIONS, CORRLAP_SETTINGS


def bench_input(name, voxels, shift, volume, h, origin, measure, args, writer):
    vtk_f, taubin, corr = settings_for(args.quick)
    workdir = os.path.dirname(volume)
    rows = []

    def record(tool, setting, mesh, info, staircase):
        row = {"tool": tool, "setting": setting, "input": name, "voxels": voxels, "shift": shift, "h": h,
               "staircase_max_vox": staircase, "status": "ok"}
        row.update(info)
        if mesh is not None:
            verts, tris = to_world(mesh, h, origin)
            row["vertices"], row["triangles"] = len(verts), len(tris)
            row.update(measure(verts, tris))
        rows.append(row)
        writer.writerow({k: row.get(k, "") for k in COLUMNS})
        print("  %-8s %-10s mean %.3g voxels, angle %.2f deg, wall %.2f s %s" %
              (tool, setting, row.get("mean_dist_vox", float("nan")), row.get("normal_angle_deg", float("nan")),
               row.get("wall_s", float("nan")), "" if row["status"] == "ok" else row["status"]), flush=True)

    vtk_stair = float("nan")
    for f in vtk_f:
        mesh, info = run_vtk(volume, f, workdir)
        if f == 0.0 and mesh is not None:
            vtk_stair = staircase_error(measure, mesh, h, origin)
            check_alignment("vtk", vtk_stair)
        record("vtk", "f=%g" % f, mesh, info, vtk_stair)
    sk_stair = float("nan")
    for n in taubin:
        mesh, info = run_skimage(volume, n, workdir)
        if n == 0 and mesh is not None:
            sk_stair = staircase_error(measure, mesh, h, origin)
            check_alignment("skimage", sk_stair)
        record("skimage", "taubin=%d" % n, mesh, info, sk_stair)
    for setting, flags in corr:
        result = run_corrlap(args.corrlap, volume, setting, flags, workdir)
        if result[0] is None:
            record("corrlap", setting, None, result[2], float("nan"))
            continue
        mesh, staircase_mesh, info = result
        stair = staircase_error(measure, staircase_mesh, h, origin)
        check_alignment("corrlap", stair)
        record("corrlap", setting, mesh, info, stair)
    return rows


def check_alignment(tool, staircase_max_vox):
    if not staircase_max_vox < 1.0:
        raise SystemExit("compare_surfaces: %s's unsmoothed surface is %.3g voxels from the truth (at most 1 "
                         "expected): its coordinates are not mapped to the truth's" % (tool, staircase_max_vox))


def grid_shifts(args):
    """The grid shifts of the analytic shapes, in voxels: the one given by --shift, none for
    --shifts 0, else --shifts K draws in [-0.5, 0.5]^3 from --seed (the same draws on every run)."""
    if args.shift is not None:
        return [tuple(args.shift)]
    if args.shifts == 0:
        return [(0.0, 0.0, 0.0)]
    rng = np.random.default_rng(args.seed)
    return [tuple(float(x) for x in rng.uniform(-0.5, 0.5, 3)) for _ in range(args.shifts)]


def shift_label(shift):
    return " ".join("%.3f" % x for x in shift)


def prepare_input(name, voxels, shift, volume, bunny):
    """Voxelizes input `name` (an analytic shape moved by `shift`, or "bunny": the mesh `bunny`)
    into `volume`. Returns h, the origin of voxel (0, 0, 0) and the measure of a mesh (V, T)
    against that input's truth."""
    if name == "bunny":
        h, origin, sv, stri = voxelize_mesh(bunny, voxels, volume)
        return h, origin, lambda v, t: mesh_measures(sv, stri, v, t, h)
    shape = st.SHAPES[name]
    h, origin = voxelize_shape(shape, voxels, volume, shift)
    return h, origin, lambda v, t: st.analytic_measures(shape, v, t, h)


def run_all(args):
    os.makedirs(args.out, exist_ok=True)
    csv_path = os.path.join(args.out, "results.csv")
    rows = []
    shifts = grid_shifts(args)
    with open(csv_path, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=COLUMNS)
        writer.writeheader()
        for voxels in args.resolutions:
            for shape_name in args.shapes:
                for k, shift in enumerate(shifts):
                    workdir = os.path.join(args.out, "work", "%s_%d_s%d" % (shape_name, voxels, k))
                    os.makedirs(workdir, exist_ok=True)
                    volume = os.path.join(workdir, "volume.npy")
                    h, origin, measure = prepare_input(shape_name, voxels, shift, volume, None)
                    print("%s, %d voxels across (h = %g), grid shift %s voxels" % (shape_name, voxels, h,
                                                                                   shift_label(shift)), flush=True)
                    rows += bench_input(shape_name, voxels, shift_label(shift), volume, h, origin, measure, args,
                                        writer)
                    fh.flush()
            if args.bunny:
                workdir = os.path.join(args.out, "work", "bunny_%d" % voxels)
                os.makedirs(workdir, exist_ok=True)
                volume = os.path.join(workdir, "volume.npy")
                h, origin, measure = prepare_input("bunny", voxels, None, volume, args.bunny)
                print("bunny, %d voxels across (h = %g)" % (voxels, h), flush=True)
                rows += bench_input("bunny", voxels, "", volume, h, origin, measure, args, writer)
                fh.flush()
    return rows


# ---------------------------------------------------------------------------------------------
# Report: tables and plots from the CSV


def load_rows(csv_path):
    rows = []
    with open(csv_path) as fh:
        for r in csv.DictReader(fh):
            for k in COLUMNS:
                if k not in ("tool", "setting", "input", "shift", "status"):
                    r[k] = float(r[k]) if r[k] not in ("", None) else float("nan")
            rows.append(r)
    return rows


# Over the grid shifts of one (tool, setting, input, N): the largest of the maxima, the mean of the
# rest; a run that failed at any shift makes the whole entry fail, named by its first failure.
MAX_OVER_SHIFTS = ("max_dist", "max_dist_vox", "staircase_max_vox", "peak_mb")


def averaged(rows):
    groups = {}
    for r in rows:
        groups.setdefault((r["tool"], r["setting"], r["input"], r["voxels"]), []).append(r)
    out = []
    for key, group in groups.items():
        failed = [r for r in group if r["status"] != "ok"]
        row = dict(failed[0] if failed else group[0])
        row["shifts"] = len(group)
        if not failed:
            for k in COLUMNS:
                if k in ("tool", "setting", "input", "voxels", "shift", "status"):
                    continue
                values = [r[k] for r in group]
                row[k] = max(values) if k in MAX_OVER_SHIFTS else sum(values) / len(values)
        out.append(row)
    return out


def best_of(rows, tool, inp, voxels):
    cands = [r for r in rows if r["tool"] == tool and r["input"] == inp and r["voxels"] == voxels
             and r["status"] == "ok"]
    return min(cands, key=lambda r: r["mean_dist"]) if cands else None


def find(rows, tool, setting, inp, voxels):
    for r in rows:
        if (r["tool"], r["setting"], r["input"], r["voxels"]) == (tool, setting, inp, voxels) and r["status"] == "ok":
            return r
    return None


def fmt(x, spec=".3g"):
    return "—" if x is None or (isinstance(x, float) and math.isnan(x)) else format(x, spec)


def summary(rows):
    inputs = list(dict.fromkeys(r["input"] for r in rows))
    res = sorted(set(r["voxels"] for r in rows))
    out = ["## Best of each tool and corrlap's settings", "",
           "Mean distance to the truth in voxels / mean normal angle in degrees / whole-process wall time in "
           "seconds; for VTK and scikit-image the setting of smallest mean distance.", "",
           "| input | N | best VTK | best skimage | corrlap defaults | corrlap polydec | corrlap alignment |",
           "|---|---|---|---|---|---|---|"]

    def cell(r, with_setting=False):
        if r is None:
            return "—"
        text = "%s / %.2f / %.2f" % (fmt(r["mean_dist_vox"]), r["normal_angle_deg"], r["wall_s"])
        return ("%s: " % r["setting"] + text) if with_setting else text

    for inp in inputs:
        for n in res:
            if not any(r["input"] == inp and r["voxels"] == n for r in rows):
                continue
            out.append("| %s | %d | %s | %s | %s | %s | %s |" % (
                inp, n, cell(best_of(rows, "vtk", inp, n), True), cell(best_of(rows, "skimage", inp, n), True),
                cell(find(rows, "corrlap", "defaults", inp, n)), cell(find(rows, "corrlap", "polydec", inp, n)),
                cell(find(rows, "corrlap", "alignment", inp, n))))
    out += ["", "## All runs", "",
            "| input | N | tool | setting | mean dist (vox) | max dist (vox) | normal angle (°) | H error | "
            "area change | volume change | wall (s) | core (s) | peak MB |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for inp in inputs:
        for n in res:
            for r in rows:
                if r["input"] != inp or r["voxels"] != n:
                    continue
                if r["status"] != "ok":
                    out.append("| %s | %d | %s | %s | %s |  |  |  |  |  |  |  |  |" %
                               (inp, n, r["tool"], r["setting"], r["status"]))
                    continue
                out.append("| %s | %d | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |" % (
                    inp, n, r["tool"], r["setting"], fmt(r["mean_dist_vox"]), fmt(r["max_dist_vox"]),
                    fmt(r["normal_angle_deg"], ".2f"), fmt(r["h_err_rel"], ".2f"), fmt(r["area_change"], "+.2%"),
                    fmt(r["volume_change"], "+.2%"), fmt(r["wall_s"], ".2f"), fmt(r["core_s"], ".2f"),
                    fmt(r["peak_mb"], ".0f")))
    out += ["", "## corrlap (defaults) against the best setting of each tool", "",
            "Ratios corrlap / tool: mean distance and normal angle (the goal: at most 0.5 and below 1 on "
            "the analytic shapes, at most 1 on a voxelized model), time against "
            "Slicer's default f = 0.5 (whole process, and compute alone), whole-process time against the "
            "best setting of each tool.", "",
            "| input | N | best VTK | best skimage | mean dist ratio vs VTK | vs skimage | goal met | "
            "angle ratio vs VTK | vs skimage | wall ratio vs VTK f=0.5 | core ratio vs VTK f=0.5 | "
            "wall ratio vs best VTK | vs best skimage |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for inp in inputs:
        for n in res:
            c = find(rows, "corrlap", "defaults", inp, n)
            bv, bs = best_of(rows, "vtk", inp, n), best_of(rows, "skimage", inp, n)
            v05 = find(rows, "vtk", "f=0.5", inp, n)
            if c is None or bv is None or bs is None:
                continue
            qv, qs = c["mean_dist"] / bv["mean_dist"], c["mean_dist"] / bs["mean_dist"]
            av, ask = c["normal_angle_deg"] / bv["normal_angle_deg"], c["normal_angle_deg"] / bs["normal_angle_deg"]
            # The goal: half the distance and a smaller angle on the analytic shapes; on a voxelized
            # model, at least as close to the source mesh.
            limit = 0.5 if inp in st.SHAPES else 1.0
            goal = "yes" if qv <= limit and qs <= limit and (limit == 1.0 or (av < 1 and ask < 1)) else "no"
            out.append("| %s | %d | %s | %s | %.2f | %.2f | %s | %.2f | %.2f | %s | %s | %.1f | %.1f |" % (
                inp, n, bv["setting"], bs["setting"], qv, qs, goal,
                av, ask, fmt(c["wall_s"] / v05["wall_s"], ".1f") if v05 else "—",
                fmt(c["core_s"] / v05["core_s"], ".1f") if v05 else "—",
                c["wall_s"] / bv["wall_s"], c["wall_s"] / bs["wall_s"]))
    return "\n".join(out) + "\n"


TOOL_COLOURS = {"vtk": "tab:blue", "skimage": "tab:green", "corrlap": "tab:red"}
LINESTYLES = ["-", "--", ":", "-.", (0, (5, 1))]
MARKERS = ["o", "s", "^", "v", "D"]


def panels(plt, count):
    """One panel per input, three to a row; returns the figure and the flat list of axes."""
    cols = min(3, count)
    rows = (count + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(4.6 * cols, 3.9 * rows), squeeze=False)
    return fig, list(axes.ravel())


def plots(rows, out_dir):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    inputs = list(dict.fromkeys(r["input"] for r in rows))
    ok = [r for r in rows if r["status"] == "ok"]
    paths = []
    fig, axes = panels(plt, len(inputs))
    for ax, inp in zip(axes, inputs):
        series = list(dict.fromkeys((r["tool"], r["setting"]) for r in ok if r["input"] == inp))
        rank = {}
        for tool, setting in series:
            pts = sorted((r["voxels"], r["mean_dist_vox"]) for r in ok
                         if (r["input"], r["tool"], r["setting"]) == (inp, tool, setting))
            k = rank[tool] = rank.get(tool, -1) + 1
            ax.plot([p[0] for p in pts], [p[1] for p in pts], linestyle=LINESTYLES[k % len(LINESTYLES)],
                    marker=MARKERS[k % len(MARKERS)], color=TOOL_COLOURS[tool], ms=4,
                    lw=1.6 if tool == "corrlap" else 1.0, label="%s %s" % (tool, setting))
        ax.set_xscale("log", base=2)
        ax.set_yscale("log")
        ax.set_title(inp)
        ax.set_xlabel("voxels across")
        ax.set_ylabel("mean distance to the truth (voxels)")
    axes[0].legend(fontsize=6, loc="best")
    for ax in axes[len(inputs):]:
        ax.set_visible(False)
    fig.tight_layout()
    p = os.path.join(out_dir, "comparison_error_vs_voxels.png")
    fig.savefig(p, dpi=110)
    plt.close(fig)
    paths.append(p)

    top = max(r["voxels"] for r in ok)
    for key, label, name in (("wall_s", "wall time, whole process (s)", "comparison_pareto.png"),
                             ("core_s", "compute time, in the process (s)", "comparison_pareto_compute.png")):
        fig, axes = panels(plt, len(inputs))
        for ax, inp in zip(axes, inputs):
            sel = [r for r in ok if r["input"] == inp and r["voxels"] == top]
            for r in sel:
                ax.scatter(r[key], r["mean_dist_vox"], color=TOOL_COLOURS[r["tool"]], s=18)
                ax.annotate("%s %s" % (r["tool"], r["setting"]), (r[key], r["mean_dist_vox"]), fontsize=5)
            # Pareto front: no other run both faster and closer.
            best, fx, fy = float("inf"), [], []
            for x, y in sorted((r[key], r["mean_dist_vox"]) for r in sel):
                if y < best:
                    best = y
                    fx.append(x)
                    fy.append(y)
            ax.step(fx, fy, where="post", color="grey", lw=0.8)
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_title("%s, %d voxels across" % (inp, top))
            ax.set_xlabel(label)
            ax.set_ylabel("mean distance (voxels)")
        for ax in axes[len(inputs):]:
            ax.set_visible(False)
        fig.tight_layout()
        p = os.path.join(out_dir, name)
        fig.savefig(p, dpi=110)
        plt.close(fig)
        paths.append(p)
    return paths


def default_cli():
    for cand in (os.path.join(ROOT, "build", "bin", "corrlap"), os.path.join(ROOT, "build", "apps", "corrlap", "corrlap")):
        if os.path.exists(cand):
            return cand
    return os.path.join(ROOT, "build", "bin", "corrlap")


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    if argv and argv[0] == "--child":
        tool, volume, setting, out = argv[1:5]
        if tool == "vtk":
            child_vtk(volume, float(setting), out)
        else:
            child_skimage(volume, int(setting), out)
        return 0
    global st
    sys.path.insert(0, HERE)
    import surface_truth as st

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", required=True, help="output directory (results.csv, summary.md, plots, work/)")
    ap.add_argument("--quick", action="store_true",
                    help="sphere1 at 64 voxels across, two settings per tool (under a minute)")
    ap.add_argument("--shapes", nargs="*", default=list(st.SHAPES), choices=list(st.SHAPES))
    ap.add_argument("--resolutions", nargs="+", type=int, default=None, metavar="N",
                    help="voxels across the longest side of each shape (default 64 128 256; --quick: 64)")
    bunny = os.path.join(ROOT, "data", "bunny", "bunny.obj")
    ap.add_argument("--bunny", default=bunny if os.path.exists(bunny) else "",
                    help="closed triangle mesh voxelized as the model input (default: data/bunny/bunny.obj "
                         "when scripts/fetch_bunny.sh has fetched it; '' for none)")
    ap.add_argument("--corrlap", default=default_cli(), help="corrlap binary (default: build/bin/corrlap)")
    ap.add_argument("--shifts", type=int, default=None, metavar="K",
                    help="voxelize each analytic shape K times, the grid moved by a random shift in "
                         "[-0.5, 0.5]^3 voxels each time; the tables average over them (default 3; --quick: 1; "
                         "0: the grid centred on the shape, whose extreme points then fall on voxel centres)")
    ap.add_argument("--seed", type=int, default=1, help="seed of the --shifts draws (default 1)")
    ap.add_argument("--shift", nargs=3, type=float, default=None, metavar=("SX", "SY", "SZ"),
                    help="one given grid shift instead of --shifts, in voxels (each within [-0.5, 0.5])")
    ap.add_argument("--report-only", action="store_true", help="redo summary.md and the plots from results.csv")
    args = ap.parse_args(argv)
    if args.quick:
        args.shapes, args.bunny = ["sphere1"], ""
    if args.resolutions is None:
        args.resolutions = [64] if args.quick else [64, 128, 256]
    if args.shifts is None:
        args.shifts = 1 if args.quick else 3
    if args.shifts < 0:
        ap.error("--shifts: the number of grid shifts must be 0 or more, got %d" % args.shifts)
    if args.shift is not None and not all(-0.5 <= x <= 0.5 for x in args.shift):
        ap.error("--shift: each component must be within [-0.5, 0.5] voxels, got %s" % args.shift)
    if min(args.resolutions) < 8:
        ap.error("--resolutions: %d voxels across is too coarse for any of the tools (at least 8)"
                 % min(args.resolutions))
    if not args.report_only:
        if not os.path.exists(args.corrlap):
            ap.error("--corrlap: %s not found (build it with `make build`, or pass the binary)" % args.corrlap)
        missing = [m for m in ("vtk", "skimage", "open3d") if not _importable(m)]
        if missing:
            ap.error("Python modules missing: %s (bash scripts/install_deps.sh --bench installs them)"
                     % ", ".join(missing))
        run_all(args)
    rows = averaged(load_rows(os.path.join(args.out, "results.csv")))
    with open(os.path.join(args.out, "summary.md"), "w") as fh:
        fh.write(summary(rows))
    for p in plots(rows, args.out):
        print("wrote", p)
    print("wrote", os.path.join(args.out, "results.csv"), "and", os.path.join(args.out, "summary.md"))
    return 0


def _importable(name):
    import importlib.util
    return importlib.util.find_spec(name) is not None


if __name__ == "__main__":
    sys.exit(main())
