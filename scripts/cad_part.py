#!/usr/bin/python3
"""A CAD-like part with sharp edges, and the measures of a mesh against it (paper Fig. 14).

The paper's Fig. 14 regularizes the fandisk, a CAD model that is not redistributable here. This
part stands in for it: a profile with a chamfer, a rounded corner (a faceted arc) and a notch,
extruded, then turned off the grid axes so that no face lies on a voxel plane. The part is a
polyhedron; its signed distance is exact (an extrusion's: the profile's 2D distance combined with
the slab's), so the distance of a regularized surface to it is exact too.

    cad_part.py write OUT.obj                 the part as a closed, outward triangle mesh
    cad_part.py measure MESH.(ply|obj) H      JSON: distances (world and voxels of step H), mean
                                              normal angle by distance to the sharp edges, area and
                                              volume against the part's

Bands of the normal angle (face centroids, distance to the nearest sharp edge in voxels):
`edges` [0, 4), `near` [4, 16), `flats` 16 and more. A method that keeps the edges sharp wins in the
first band; one that leaves no stairs on the faces wins in the last.
"""
import json
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "bench"))
import surface_truth  # noqa: E402  (the mesh reader and the area/volume helpers)

HALF_THICKNESS = 0.4
ARC_SEGMENTS = 24
# An edge is sharp where the surface turns by more than this; the arc's facets turn by 90/24 degrees.
SHARP_TURN_DEG = 20.0
BANDS = (("edges", 0.0, 4.0), ("near", 4.0, 16.0), ("flats", 16.0, math.inf))


def profile():
    """The 2D profile, counter-clockwise (P by 2): a chamfer top right, a notch in the top edge and a
    rounded corner top left (a quarter circle of radius 0.3 as ARC_SEGMENTS facets)."""
    pts = [(-1.0, -0.6), (1.0, -0.6), (1.0, 0.2), (0.7, 0.5), (-0.2, 0.5), (-0.2, 0.25), (-0.45, 0.25),
           (-0.45, 0.5)]
    cx, cy, r = -0.7, 0.2, 0.3
    for k in range(ARC_SEGMENTS + 1):
        t = 0.5 * math.pi + 0.5 * math.pi * k / ARC_SEGMENTS
        pts.append((cx + r * math.cos(t), cy + r * math.sin(t)))
    return np.array(pts)


def rotation():
    """Turns the part off the grid: 30 degrees about x, -15 about y, 20 about z."""
    def axis(k, deg):
        c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
        i, j = [a for a in range(3) if a != k]
        m = np.eye(3)
        m[i, i], m[i, j], m[j, i], m[j, j] = c, -s, s, c
        return m
    return axis(2, 20.0) @ axis(1, -15.0) @ axis(0, 30.0)


def _triangulate(poly):
    """Ear clipping of a simple counter-clockwise polygon: triangles as index triples."""
    idx = list(range(len(poly)))
    tris = []

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    while len(idx) > 3:
        for n in range(len(idx)):
            i, j, k = idx[n - 1], idx[n], idx[(n + 1) % len(idx)]
            a, b, c = poly[i], poly[j], poly[k]
            if cross(a, b, c) <= 1e-12:
                continue  # reflex or flat: not an ear
            inside = any(cross(a, b, poly[m]) >= 0 and cross(b, c, poly[m]) >= 0 and cross(c, a, poly[m]) >= 0
                         for m in idx if m not in (i, j, k))
            if not inside:
                tris.append((i, j, k))
                del idx[n]
                break
        else:
            raise ValueError("cad_part: the profile is not a simple polygon")
    tris.append(tuple(idx))
    return tris


def mesh():
    """The part as (V by 3, F by 3), closed and facing outwards."""
    p = profile()
    n = len(p)
    bottom = np.column_stack([p, np.full(n, -HALF_THICKNESS)])
    top = np.column_stack([p, np.full(n, HALF_THICKNESS)])
    verts = np.vstack([bottom, top]) @ rotation().T
    faces = []
    for a, b, c in _triangulate(p):
        faces.append((n + a, n + b, n + c))  # top, facing +z
        faces.append((c, b, a))  # bottom, facing -z
    for i in range(n):
        j = (i + 1) % n
        faces += [(i, j, n + j), (i, n + j, n + i)]
    return verts, np.array(faces, dtype=np.int64)


def _profile_distance(q):
    """Signed distance of 2D points (N by 2) to the profile: negative inside."""
    p = profile()
    a, b = p, np.roll(p, -1, axis=0)
    best = np.full(len(q), np.inf)
    inside = np.zeros(len(q), dtype=bool)
    for s in range(len(p)):
        e = b[s] - a[s]
        w = q - a[s]
        t = np.clip((w @ e) / (e @ e), 0.0, 1.0)
        best = np.minimum(best, np.linalg.norm(w - t[:, None] * e, axis=1))
        # Even-odd crossing of a ray towards +x.
        crosses = (a[s, 1] > q[:, 1]) != (b[s, 1] > q[:, 1])
        with np.errstate(divide="ignore", invalid="ignore"):
            x = a[s, 0] + (q[:, 1] - a[s, 1]) * e[0] / e[1]
        inside ^= crosses & (q[:, 0] < x)
    return np.where(inside, -best, best)


def signed_distance(x):
    """Exact signed distance of points (N by 3) to the part: negative inside."""
    local = np.asarray(x, dtype=float) @ rotation()
    d2 = _profile_distance(local[:, :2])
    dz = np.abs(local[:, 2]) - HALF_THICKNESS
    outside = np.hypot(np.maximum(d2, 0.0), np.maximum(dz, 0.0))
    return outside + np.minimum(np.maximum(d2, dz), 0.0)


def true_normal(x, step):
    """The part's outward normal near points x: the gradient of the signed distance (central
    differences of width step; exact on the faces, away from the edges by more than step)."""
    g = np.zeros((len(x), 3))
    for k in range(3):
        e = np.zeros(3)
        e[k] = step
        g[:, k] = signed_distance(x + e) - signed_distance(x - e)
    return g / np.maximum(np.linalg.norm(g, axis=1), 1e-300)[:, None]


def sharp_edge_samples(spacing):
    """Points along the sharp edges, at most spacing apart: the two rims of the caps and the
    vertical edges at the profile's corners that turn by more than SHARP_TURN_DEG."""
    p = profile()
    samples = []
    for i in range(len(p)):
        a, b = p[i], p[(i + 1) % len(p)]
        k = max(2, int(math.ceil(np.linalg.norm(b - a) / spacing)) + 1)
        t = np.linspace(0.0, 1.0, k)[:, None]
        seg = a + t * (b - a)
        for z in (-HALF_THICKNESS, HALF_THICKNESS):
            samples.append(np.column_stack([seg, np.full(k, z)]))
        e0, e1 = p[i] - p[i - 1], b - a
        turn = math.degrees(math.atan2(e0[0] * e1[1] - e0[1] * e1[0], e0 @ e1))
        if abs(turn) > SHARP_TURN_DEG:
            m = int(math.ceil(2 * HALF_THICKNESS / spacing)) + 1
            samples.append(np.column_stack([np.tile(a, (m, 1)), np.linspace(-HALF_THICKNESS, HALF_THICKNESS, m)]))
    return np.vstack(samples) @ rotation().T


def edge_distance(points, h):
    """Distance of points (N by 3) to the nearest sharp edge, to within h / 8."""
    from scipy.spatial import cKDTree

    return cKDTree(sharp_edge_samples(0.25 * h)).query(points)[0]


def measure(verts, tris, h):
    """Distances, normal angles by band, area and volume of a mesh against the part (h the grid
    step, to report distances and bands in voxels)."""
    tris = surface_truth.orient_outwards(verts, tris)
    cross, area, centroid = surface_truth.triangle_geometry(verts, tris)
    va = surface_truth.vertex_areas(verts, tris, area)
    d = np.abs(signed_distance(verts))
    nz = area > 0
    fn = cross[nz] / area[nz][:, None]
    angle = np.degrees(np.arccos(np.clip((fn * true_normal(centroid[nz], 1e-4 * h)).sum(1), -1.0, 1.0)))
    to_edge = edge_distance(centroid[nz], h) / h
    bands = {}
    for name, lo, hi in BANDS:
        pick = (to_edge >= lo) & (to_edge < hi)
        w = area[nz][pick]
        bands[name] = float((w * angle[pick]).sum() / w.sum()) if w.sum() > 0 else float("nan")
    tv, tt = mesh()
    true_area = float(surface_truth.triangle_geometry(tv, tt)[1].sum())
    mean = float((va * d).sum() / va.sum())
    return {
        "h": h, "vertices": int(len(verts)), "faces": int(len(tris)),
        "distance_mean": mean, "distance_max": float(d.max()),
        "distance_mean_vox": mean / h, "distance_max_vox": float(d.max()) / h,
        "angle_deg": {name: bands[name] for name, _, _ in BANDS},
        "area_ratio": float(area.sum()) / true_area,
        "volume_ratio": surface_truth.signed_volume(verts, tris) / surface_truth.signed_volume(tv, tt),
    }


def write_obj(path):
    verts, faces = mesh()
    with open(path, "w") as out:
        out.write("# corrlap scripts/cad_part.py: a CAD-like part with sharp edges\n")
        for v in verts:
            out.write("v %.17g %.17g %.17g\n" % tuple(v))
        for f in faces:
            out.write("f %d %d %d\n" % tuple(f + 1))


def main(argv):
    if len(argv) == 3 and argv[1] == "write":
        try:
            write_obj(argv[2])
        except OSError as e:
            print("cad_part: cannot write %s: %s" % (argv[2], e.strerror or e), file=sys.stderr)
            return 2
        return 0
    if len(argv) == 4 and argv[1] == "measure":
        try:
            h = float(argv[3])
        except ValueError:
            h = float("nan")
        if not (h > 0 and math.isfinite(h)):
            print("cad_part: H must be a positive grid step, got '%s'" % argv[3], file=sys.stderr)
            return 2
        try:
            verts, tris = surface_truth.read_mesh(argv[2])
        except OSError as e:
            print("cad_part: cannot read %s: %s" % (argv[2], e.strerror or e), file=sys.stderr)
            return 2
        except ValueError as e:
            print("cad_part: %s" % e, file=sys.stderr)
            return 2
        if len(tris) == 0:
            print("cad_part: %s has no faces" % argv[2], file=sys.stderr)
            return 2
        print(json.dumps(measure(verts, tris, h), indent=1))
        return 0
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv))
