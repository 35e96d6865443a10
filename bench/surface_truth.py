"""Ground truth and mesh measures for bench/compare_surfaces.py.

The analytic shapes are corrlap's named implicit shapes (surface/implicit_shape.cpp: the inside is
P(x, y, z) <= 0), written here with their gradient and Hessian so that a point can be projected
exactly onto the surface and the true normal and mean curvature read there. Only numpy (and scipy
for the curvature of a mesh) is needed: the test of the projection runs without VTK or Open3D.
"""
import math

import numpy as np


class Shape:
    """An implicit shape f <= 0 with its derivatives, its extent and its true area and volume."""

    def __init__(self, name, f, grad, hess, half_extent, radius=None, area=None, volume=None):
        self.name = name
        self.f = f
        self.grad = grad
        self.hess = hess
        # Half the longest side of the bounding box: N voxels across means h = 2 * half_extent / N.
        self.half_extent = half_extent
        self._radius = radius  # radial function r(u) of a star-shaped shape, u unit directions (N, 3)
        self._area = area
        self._volume = volume

    def grid_step(self, voxels_across):
        return 2.0 * self.half_extent / voxels_across

    def area_volume(self):
        """True area and volume: closed forms where known, else a quadrature over the directions."""
        if self._area is not None and self._volume is not None:
            return self._area, self._volume
        area, volume = star_area_volume(self)
        return (self._area if self._area is not None else area,
                self._volume if self._volume is not None else volume)


def _sphere():
    return Shape("sphere1",
                 f=lambda p: (p * p).sum(1) - 1.0,
                 grad=lambda p: 2.0 * p,
                 hess=lambda p: np.broadcast_to(2.0 * np.eye(3), (len(p), 3, 3)),
                 half_extent=1.0,
                 radius=lambda u: np.ones(len(u)),
                 area=4.0 * math.pi, volume=4.0 * math.pi / 3.0)


_ELLIPSOID_COEF = np.array([3.0, 2.0, 1.0])  # 3x^2 + 2y^2 + z^2 - 90


def _ellipsoid():
    c = _ELLIPSOID_COEF
    semi = np.sqrt(90.0 / c)
    return Shape("ellipsoid",
                 f=lambda p: (c * p * p).sum(1) - 90.0,
                 grad=lambda p: 2.0 * c * p,
                 hess=lambda p: np.broadcast_to(np.diag(2.0 * c), (len(p), 3, 3)),
                 half_extent=float(semi.max()),
                 radius=lambda u: np.sqrt(90.0 / (c * u * u).sum(1)),
                 volume=4.0 / 3.0 * math.pi * float(np.prod(semi)))


_TORUS_R, _TORUS_r = 6.0, 2.0  # (x^2+y^2+z^2 + R^2 - r^2)^2 - 4 R^2 (x^2+y^2)


def _torus():
    big, small = _TORUS_R, _TORUS_r
    k = big * big - small * small
    planar = np.array([1.0, 1.0, 0.0])

    def f(p):
        s = (p * p).sum(1) + k
        return s * s - 4.0 * big * big * (p[:, 0] ** 2 + p[:, 1] ** 2)

    def grad(p):
        s = (p * p).sum(1) + k
        return 4.0 * s[:, None] * p - 8.0 * big * big * p * planar

    def hess(p):
        s = (p * p).sum(1) + k
        return (4.0 * s[:, None, None] * np.eye(3) + 8.0 * p[:, :, None] * p[:, None, :]
                - 8.0 * big * big * np.diag(planar))

    return Shape("torus", f, grad, hess, half_extent=big + small,
                 area=4.0 * math.pi ** 2 * big * small, volume=2.0 * math.pi ** 2 * big * small ** 2)


_GOURSAT_C = 0.03  # -(8 - 0.03 (x^4+y^4+z^4) + 2 (x^2+y^2+z^2))


def _goursat():
    c = _GOURSAT_C

    def radius(u):
        # Along a ray: c a r^4 - 2 r^2 - 8 = 0, a = sum u_i^4, one positive root in r^2.
        a = (u ** 4).sum(1)
        return np.sqrt((2.0 + np.sqrt(4.0 + 32.0 * c * a)) / (2.0 * c * a))

    # The box is not reached along an axis but off it: the largest x over the directions
    # (1, a, b), |a|, |b| <= 1, on a grid fine enough for a relative error of 1e-6 at the maximum.
    a, b = np.meshgrid(np.linspace(0.0, 1.0, 801), np.linspace(0.0, 1.0, 801), indexing="ij")
    u = np.stack([np.ones(a.size), a.ravel(), b.ravel()], axis=1)
    u /= np.linalg.norm(u, axis=1)[:, None]
    half_extent = float((radius(u) * u[:, 0]).max())
    return Shape("goursat",
                 f=lambda p: c * (p ** 4).sum(1) - 2.0 * (p * p).sum(1) - 8.0,
                 grad=lambda p: 4.0 * c * p ** 3 - 4.0 * p,
                 hess=lambda p: np.einsum("ni,ij->nij", 12.0 * c * p * p - 4.0, np.eye(3)),
                 half_extent=half_extent, radius=radius)


SHAPES = {s.name: s for s in (_sphere(), _ellipsoid(), _torus(), _goursat())}


def star_area_volume(shape, n_theta=256, n_phi=512):
    """Area and volume of a shape star-shaped about the origin, from its radial function r(u):
    V = integral of r^3/3 and A = integral of r^2 / (n . u) over the unit sphere (Gauss-Legendre in
    cos(theta), the trapezoid rule in phi: both converge spectrally for a smooth closed shape)."""
    if shape._radius is None:
        raise ValueError("shape %s: no radial function, so no quadrature of its area" % shape.name)
    x, w = np.polynomial.legendre.leggauss(n_theta)
    phi = np.arange(n_phi) * (2.0 * math.pi / n_phi)
    ct, ph = np.meshgrid(x, phi, indexing="ij")
    st = np.sqrt(1.0 - ct * ct)
    u = np.stack([st * np.cos(ph), st * np.sin(ph), ct], axis=-1).reshape(-1, 3)
    weights = (w[:, None] * np.full(n_phi, 2.0 * math.pi / n_phi)).reshape(-1)
    r = shape._radius(u)
    g = shape.grad(r[:, None] * u)
    n = g / np.linalg.norm(g, axis=1)[:, None]
    volume = float((weights * r ** 3 / 3.0).sum())
    area = float((weights * r ** 2 / (n * u).sum(1)).sum())
    return area, volume


def project(shape, points, max_iterations=60):
    """Closest points of the implicit surface f = 0 to `points` (N, 3) and the signed distances
    (positive outside). Newton steps along the gradient first reach the surface; then Newton's
    method on the Lagrange conditions x - p + lambda grad f(x) = 0, f(x) = 0 moves the foot point
    to where x - p is normal to the surface. Meant for points near the surface (a voxel or so): a
    point whose iteration does not settle, or settles farther than the first surface point found,
    is an error rather than a silently wrong distance."""
    p = np.asarray(points, dtype=float)
    scale = shape.half_extent
    x = p.copy()
    for _ in range(max_iterations):
        fx, g = shape.f(x), shape.grad(x)
        step = (fx / (g * g).sum(1))[:, None] * g
        x = x - step
        if np.abs(step).max(initial=0.0) < 1e-14 * scale:
            break
    first = x.copy()
    g = shape.grad(x)
    lam = -((x - p) * g).sum(1) / (g * g).sum(1)
    for _ in range(max_iterations):
        g, hs = shape.grad(x), shape.hess(x)
        jac = np.zeros((len(x), 4, 4))
        jac[:, :3, :3] = np.eye(3) + lam[:, None, None] * hs
        jac[:, :3, 3] = g
        jac[:, 3, :3] = g
        res = np.concatenate([x - p + lam[:, None] * g, shape.f(x)[:, None]], axis=1)
        delta = np.linalg.solve(jac, -res[:, :, None])[:, :, 0]
        x = x + delta[:, :3]
        lam = lam + delta[:, 3]
        if np.abs(delta[:, :3]).max(initial=0.0) < 1e-13 * scale:
            break
    g = shape.grad(x)
    gn = np.linalg.norm(g, axis=1)
    off_surface = np.abs(shape.f(x)) / gn
    dist = np.linalg.norm(x - p, axis=1)
    # Written as 'not good' so that a NaN (a zero gradient on the way) counts as a failure.
    bad = ~((off_surface <= 1e-9 * scale) & (dist <= np.linalg.norm(first - p, axis=1) + 1e-9 * scale))
    if bad.any():
        raise RuntimeError("projection onto %s: %d of %d points did not converge (first: %s); "
                           "the points must lie near the surface" %
                           (shape.name, int(bad.sum()), len(p), p[np.argmax(bad)]))
    sign = np.where(shape.f(p) > 0.0, 1.0, -1.0)
    return x, sign * dist


def true_normal(shape, x):
    g = shape.grad(x)
    return g / np.linalg.norm(g, axis=1)[:, None]


def true_mean_curvature(shape, x):
    """H = (|g|^2 tr(Hf) - g^T Hf g) / (2 |g|^3): the mean of the principal curvatures, positive on
    a sphere (outward normal)."""
    g, hs = shape.grad(x), shape.hess(x)
    gg = (g * g).sum(1)
    ghg = np.einsum("ni,nij,nj->n", g, hs, g)
    return (gg * np.trace(hs, axis1=1, axis2=2) - ghg) / (2.0 * gg ** 1.5)


# ---------------------------------------------------------------------------------------------
# Meshes


def read_mesh(path):
    """Vertices (N, 3) and triangles (M, 3) of a .ply (ascii or binary) or .obj file; polygons are
    split into triangle fans."""
    if str(path).endswith(".obj"):
        return _read_obj(path)
    if str(path).endswith(".ply"):
        return _read_ply(path)
    raise ValueError("read_mesh: %s: unknown extension (expected .ply or .obj)" % path)


def _fan(polygons):
    tris = []
    for poly in polygons:
        for i in range(1, len(poly) - 1):
            tris.append((poly[0], poly[i], poly[i + 1]))
    return np.array(tris, dtype=np.int64).reshape(-1, 3)


def _read_obj(path):
    verts, polys = [], []
    with open(path) as fh:
        for line in fh:
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "v":
                verts.append([float(v) for v in parts[1:4]])
            elif parts[0] == "f":
                polys.append([int(t.split("/")[0]) - 1 for t in parts[1:]])
    return np.array(verts, dtype=float).reshape(-1, 3), _fan(polys)


_PLY_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
              "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4",
              "uint32": "u4", "float": "f4", "float32": "f4", "double": "f8", "float64": "f8"}


def _read_ply(path):
    with open(path, "rb") as fh:
        data = fh.read()
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        raise ValueError("read_mesh: %s: not a PLY file (no 'ply' magic or no end_header)" % path)
    body_start = data.index(b"\n", end) + 1
    header = data[:end].decode("ascii").splitlines()
    fmt, elements = None, []
    for line in header:
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "format":
            fmt = parts[1]
        elif parts[0] == "element":
            elements.append({"name": parts[1], "count": int(parts[2]), "props": []})
        elif parts[0] == "property":
            if parts[1] == "list":
                elements[-1]["props"].append((parts[4], "list", _PLY_TYPES[parts[2]], _PLY_TYPES[parts[3]]))
            else:
                elements[-1]["props"].append((parts[2], _PLY_TYPES[parts[1]]))
    if fmt == "ascii":
        tokens = data[body_start:].split()
        pos = 0
        out = {}
        for el in elements:
            rows = []
            for _ in range(el["count"]):
                row = []
                for prop in el["props"]:
                    if prop[1] == "list":
                        n = int(tokens[pos])
                        row.append([float(t) for t in tokens[pos + 1:pos + 1 + n]])
                        pos += 1 + n
                    else:
                        row.append(float(tokens[pos]))
                        pos += 1
                rows.append(row)
            out[el["name"]] = (el, rows)
        vel, vrows = out["vertex"]
        names = [p[0] for p in vel["props"]]
        ix = [names.index(c) for c in "xyz"]
        verts = np.array([[r[i] for i in ix] for r in vrows], dtype=float).reshape(-1, 3)
        fel, frows = out["face"]
        li = [i for i, p in enumerate(fel["props"]) if p[1] == "list"][0]
        return verts, _fan([[int(v) for v in r[li]] for r in frows])
    if fmt not in ("binary_little_endian", "binary_big_endian"):
        raise ValueError("read_mesh: %s: PLY format %s not read" % (path, fmt))
    order = "<" if fmt == "binary_little_endian" else ">"
    pos = body_start
    verts, tris = None, None
    for el in elements:
        if all(p[1] != "list" for p in el["props"]):
            dt = np.dtype([(p[0], order + p[1]) for p in el["props"]])
            arr = np.frombuffer(data, dtype=dt, count=el["count"], offset=pos)
            pos += dt.itemsize * el["count"]
            if el["name"] == "vertex":
                verts = np.stack([arr["x"], arr["y"], arr["z"]], axis=1).astype(float)
            continue
        # Elements with lists: read as fixed-size records when every list has the length of the
        # first record's (triangles or quads), else record by record.
        fields, lengths, off = [], [], pos
        for p in el["props"]:
            if p[1] == "list":
                ct, it = np.dtype(order + p[2]), np.dtype(order + p[3])
                n = int(np.frombuffer(data, dtype=ct, count=1, offset=off)[0]) if el["count"] else 0
                fields += [(p[0] + "#n", ct), (p[0], it, (n,))]
                lengths.append((p[0], n))
                off += ct.itemsize + it.itemsize * n
            else:
                dt = np.dtype(order + p[1])
                fields.append((p[0], dt))
                off += dt.itemsize
        row = np.dtype(fields)
        arr = np.frombuffer(data, dtype=row, count=el["count"], offset=pos)
        if all(np.all(arr[name + "#n"] == n) for name, n in lengths):
            pos += row.itemsize * el["count"]
            polys = arr[lengths[0][0]].astype(np.int64)
            k = lengths[0][1]
            faces = np.concatenate([polys[:, [0, i, i + 1]] for i in range(1, k - 1)]) \
                if k >= 3 else np.zeros((0, 3), np.int64)
        else:
            polys = []
            for _ in range(el["count"]):
                for p in el["props"]:
                    if p[1] == "list":
                        ct, it = np.dtype(order + p[2]), np.dtype(order + p[3])
                        n = int(np.frombuffer(data, dtype=ct, count=1, offset=pos)[0])
                        pos += ct.itemsize
                        if p[0] == lengths[0][0]:
                            polys.append(list(np.frombuffer(data, dtype=it, count=n, offset=pos)))
                        pos += it.itemsize * n
                    else:
                        pos += np.dtype(p[1]).itemsize
            faces = _fan(polys)
        if el["name"] == "face":
            tris = faces
    if verts is None or tris is None:
        raise ValueError("read_mesh: %s: no vertex or no face element" % path)
    return verts, tris


def triangle_geometry(verts, tris):
    """Per-triangle area-weighted normal (cross product / 2), area and centroid."""
    a, b, c = verts[tris[:, 0]], verts[tris[:, 1]], verts[tris[:, 2]]
    cross = 0.5 * np.cross(b - a, c - a)
    area = np.linalg.norm(cross, axis=1)
    return cross, area, (a + b + c) / 3.0


def signed_volume(verts, tris):
    a, b, c = verts[tris[:, 0]], verts[tris[:, 1]], verts[tris[:, 2]]
    return float((a * np.cross(b, c)).sum() / 6.0)


def orient_outwards(verts, tris):
    """The same triangles facing outwards (positive enclosed volume): tools differ in orientation
    conventions, which are no part of the quality measured."""
    return tris[:, ::-1].copy() if signed_volume(verts, tris) < 0 else tris


def vertex_areas(verts, tris, tri_area):
    """One third of the area of the incident triangles (barycentric cells)."""
    out = np.zeros(len(verts))
    for k in range(3):
        np.add.at(out, tris[:, k], tri_area / 3.0)
    return out


def cotan_mean_curvature(verts, tris, tri_normal):
    """Mean curvature H at every vertex from the cotangent Laplacian of the positions,
    Delta x = -2 H n (barycentric vertex areas; n the area-weighted vertex normal). The same
    estimator is applied to every tool's mesh: it measures how well the mesh's geometry carries
    curvature, not any tool's own curvature estimate."""
    import scipy.sparse as sp

    n = len(verts)
    cross, area, _ = triangle_geometry(verts, tris)
    keep = area > 1e-12 * max(float(area.max(initial=0.0)), 1e-300)
    t = tris[keep]
    rows, cols, vals = [], [], []
    for k in range(3):
        i, j, o = t[:, (k + 1) % 3], t[:, (k + 2) % 3], t[:, k]
        u, v = verts[i] - verts[o], verts[j] - verts[o]
        cot = (u * v).sum(1) / np.linalg.norm(np.cross(u, v), axis=1)
        rows += [i, j]
        cols += [j, i]
        vals += [0.5 * cot, 0.5 * cot]
    w = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))
    lap = w - sp.diags(np.asarray(w.sum(1)).ravel())
    va = vertex_areas(verts, t, area[keep])
    vn = np.zeros((n, 3))
    for k in range(3):
        np.add.at(vn, t[:, k], tri_normal[keep])
    vn /= np.maximum(np.linalg.norm(vn, axis=1), 1e-300)[:, None]
    delta = np.asarray(lap @ verts) / np.maximum(va, 1e-300)[:, None]
    return -0.5 * (delta * vn).sum(1), va


def analytic_measures(shape, verts, tris, h):
    """Distances (world units and voxels), normal angle, mean-curvature error, area and volume
    change of a triangle mesh in the shape's world coordinates."""
    tris = orient_outwards(verts, tris)
    cross, area, centroid = triangle_geometry(verts, tris)
    va = vertex_areas(verts, tris, area)
    _, dist = project(shape, verts)
    d = np.abs(dist)
    mean_dist = float((va * d).sum() / va.sum())
    foot, _ = project(shape, centroid)
    nz = area > 0
    fn = cross[nz] / area[nz][:, None]
    cosang = np.clip((fn * true_normal(shape, foot[nz])).sum(1), -1.0, 1.0)
    angle = float((area[nz] * np.degrees(np.arccos(cosang))).sum() / area[nz].sum())
    h_est, hva = cotan_mean_curvature(verts, tris, cross)
    vfoot, _ = project(shape, verts)
    h_true = true_mean_curvature(shape, vfoot)
    h_err = float((hva * np.abs(h_est - h_true)).sum() / (hva * np.abs(h_true)).sum())
    true_area, true_volume = shape.area_volume()
    return {
        "mean_dist": mean_dist, "max_dist": float(d.max()),
        "mean_dist_vox": mean_dist / h, "max_dist_vox": float(d.max()) / h,
        "normal_angle_deg": angle, "h_err_rel": h_err,
        "area_change": float(area.sum()) / true_area - 1.0,
        "volume_change": signed_volume(verts, tris) / true_volume - 1.0,
    }
