"""bench/compare_surfaces.py: its ground truth (projection onto the implicit shapes, true normals,
curvature, area and volume), its mesh reader, and its quick run when VTK, scikit-image and Open3D
are installed (scripts/install_deps.sh --bench) and the corrlap binary is built."""
import csv
import importlib.util
import math
import os
import struct
import subprocess
import sys

import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "bench"))
import surface_truth as st  # noqa: E402


def near_surface_points(shape, n, spread, seed):
    """Points within `spread` (world units) of the surface, from its radial function."""
    rng = np.random.default_rng(seed)
    u = rng.normal(size=(n, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    on = shape._radius(u)[:, None] * u
    normal = st.true_normal(shape, on)
    return on + rng.uniform(-spread, spread, (n, 1)) * normal


def test_projection_matches_the_sphere_distance():
    sphere = st.SHAPES["sphere1"]
    p = near_surface_points(sphere, 5000, 0.05, 1)
    foot, signed = st.project(sphere, p)
    r = np.linalg.norm(p, axis=1)
    assert np.allclose(signed, r - 1.0, atol=1e-12)
    assert np.allclose(foot, p / r[:, None], atol=1e-12)


def ellipsoid_distance(semi, p):
    """Reference distance to the ellipsoid sum (x_i/a_i)^2 = 1, independent of the projection:
    the closest point is x_i = a_i^2 p_i / (t + a_i^2) with t the root of
    sum (a_i p_i / (t + a_i^2))^2 = 1 on t > -min a_i^2, found by bisection."""
    a2 = semi ** 2

    def g(t):
        return ((semi * p / (t[:, None] + a2)) ** 2).sum(1) - 1.0

    lo = np.full(len(p), -a2.min() + 1e-12)
    hi = np.full(len(p), np.linalg.norm(p, axis=1) * semi.max())
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        pos = g(mid) > 0
        lo = np.where(pos, mid, lo)
        hi = np.where(pos, hi, mid)
    t = 0.5 * (lo + hi)
    x = a2 * p / (t[:, None] + a2)
    return np.linalg.norm(x - p, axis=1)


def test_projection_matches_the_ellipsoid_distance():
    ellipsoid = st.SHAPES["ellipsoid"]
    semi = np.sqrt(90.0 / np.array([3.0, 2.0, 1.0]))
    p = near_surface_points(ellipsoid, 5000, 0.3, 2)
    foot, signed = st.project(ellipsoid, p)
    assert np.allclose(np.abs(signed), ellipsoid_distance(semi, p), rtol=0, atol=1e-9)
    assert np.allclose(np.sign(signed), np.sign(ellipsoid.f(p)))
    assert np.abs(ellipsoid.f(foot)).max() < 1e-9


@pytest.mark.parametrize("name", ["torus", "goursat"])
def test_projection_lands_on_the_surface_along_the_normal(name):
    shape = st.SHAPES[name]
    h = shape.grid_step(64)
    rng = np.random.default_rng(3)
    if name == "torus":
        theta, phi = rng.uniform(0, 2 * math.pi, (2, 2000))
        on = np.stack([(6 + 2 * np.cos(phi)) * np.cos(theta), (6 + 2 * np.cos(phi)) * np.sin(theta),
                       2 * np.sin(phi)], axis=1)
    else:
        u = rng.normal(size=(2000, 3))
        u /= np.linalg.norm(u, axis=1)[:, None]
        on = shape._radius(u)[:, None] * u
    p = on + rng.uniform(-h, h, (len(on), 1)) * st.true_normal(shape, on)
    foot, signed = st.project(shape, p)
    assert np.abs(shape.f(foot) / np.linalg.norm(shape.grad(foot), axis=1)).max() < 1e-9
    # x - p is along the normal at the foot point, and no farther than the point it started from.
    n = st.true_normal(shape, foot)
    assert np.abs(np.cross(p - foot, n)).max() < 1e-9
    assert (np.abs(signed) <= np.linalg.norm(p - on, axis=1) + 1e-12).all()


def test_projection_refuses_a_point_it_cannot_settle():
    sphere = st.SHAPES["sphere1"]
    with np.errstate(all="ignore"), pytest.raises(RuntimeError, match="did not converge"):
        st.project(sphere, np.array([[0.0, 0.0, 0.0], [1.1, 0.0, 0.0]]))


def test_true_curvature_area_and_volume():
    sphere, torus = st.SHAPES["sphere1"], st.SHAPES["torus"]
    p = near_surface_points(sphere, 100, 0.0, 4)
    assert np.allclose(st.true_mean_curvature(sphere, p), 1.0)
    # Torus R = 6, r = 2: at the outer equator H = (1/r + 1/(R + r)) / 2.
    assert st.true_mean_curvature(torus, np.array([[8.0, 0.0, 0.0]]))[0] == pytest.approx(0.3125)
    # The quadrature against the closed forms.
    area, volume = st.star_area_volume(sphere)
    assert area == pytest.approx(4 * math.pi, rel=1e-12)
    assert volume == pytest.approx(4 * math.pi / 3, rel=1e-12)
    semi = np.sqrt(90.0 / np.array([3.0, 2.0, 1.0]))
    assert st.star_area_volume(st.SHAPES["ellipsoid"])[1] == pytest.approx(4 / 3 * math.pi * semi.prod(), rel=1e-10)


def write_quad_cube_ply(path):
    """The unit cube as 6 quads with a per-face scalar after the index list, binary."""
    v = np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], dtype=float)
    quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
    head = ("ply\nformat binary_little_endian 1.0\nelement vertex 8\nproperty double x\nproperty double y\n"
            "property double z\nelement face 6\nproperty list uchar int vertex_indices\nproperty double q\n"
            "end_header\n").encode()
    body = v.astype("<f8").tobytes() + b"".join(struct.pack("<B4id", 4, *q, 0.5) for q in quads)
    with open(path, "wb") as fh:
        fh.write(head + body)


def test_read_mesh_splits_quads_with_face_properties(tmp_path):
    path = str(tmp_path / "cube.ply")
    write_quad_cube_ply(path)
    verts, tris = st.read_mesh(path)
    assert verts.shape == (8, 3) and tris.shape == (12, 3)
    assert abs(st.signed_volume(verts, tris)) == pytest.approx(1.0)
    assert st.triangle_geometry(verts, tris)[1].sum() == pytest.approx(6.0)


def test_measures_of_a_fine_sphere_mesh():
    # A latitude-longitude sphere with its vertices on the surface: vertex distances vanish, the
    # normals and curvature are close, the area and volume a little short (chords).
    nt, nph = 60, 120
    theta = np.linspace(0, math.pi, nt + 1)[1:-1]
    phi = np.arange(nph) * 2 * math.pi / nph
    tt, pp = np.meshgrid(theta, phi, indexing="ij")
    verts = np.concatenate([[[0, 0, 1]], np.stack([np.sin(tt) * np.cos(pp), np.sin(tt) * np.sin(pp),
                                                     np.cos(tt)], -1).reshape(-1, 3), [[0, 0, -1]]])
    idx = lambda i, j: 1 + i * nph + (j % nph)  # noqa: E731
    tris = [[0, idx(0, j), idx(0, j + 1)] for j in range(nph)]
    for i in range(nt - 2):
        for j in range(nph):
            tris += [[idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)], [idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)]]
    south = len(verts) - 1
    tris += [[south, idx(nt - 2, j + 1), idx(nt - 2, j)] for j in range(nph)]
    m = st.analytic_measures(st.SHAPES["sphere1"], verts, np.array(tris), h=0.05)
    assert m["max_dist"] < 1e-12
    assert m["normal_angle_deg"] < 1.0
    assert m["h_err_rel"] < 0.05
    assert -0.01 < m["area_change"] < 0 and -0.01 < m["volume_change"] < 0


def _harness():
    import compare_surfaces
    compare_surfaces.st = st
    return compare_surfaces


def test_grid_shifts_are_seeded_draws_within_half_a_voxel():
    cs = _harness()

    def args(shifts, seed=1, shift=None):
        return type("Args", (), {"shifts": shifts, "seed": seed, "shift": shift})()

    three = cs.grid_shifts(args(3))
    assert len(three) == 3 and len(set(three)) == 3
    assert all(-0.5 <= x <= 0.5 for s in three for x in s)
    assert cs.grid_shifts(args(3)) == three
    assert cs.grid_shifts(args(3, seed=2)) != three
    assert cs.grid_shifts(args(0)) == [(0.0, 0.0, 0.0)]
    assert cs.grid_shifts(args(3, shift=[0.1, -0.2, 0.3])) == [(0.1, -0.2, 0.3)]


def test_rows_are_averaged_over_the_shifts():
    cs = _harness()
    base = {k: 1.0 for k in cs.COLUMNS}
    base.update(tool="vtk", setting="f=0.5", input="sphere1", voxels=64.0, status="ok")
    a = dict(base, shift="0 0 0", mean_dist=1.0, max_dist=5.0, wall_s=2.0)
    b = dict(base, shift="0.1 0 0", mean_dist=3.0, max_dist=4.0, wall_s=4.0)
    other = dict(base, voxels=128.0, mean_dist=7.0)
    failed = dict(base, tool="corrlap", setting="defaults", status="exit 1: radius")
    fine = dict(base, tool="corrlap", setting="defaults")
    out = {(r["tool"], r["voxels"]): r for r in cs.averaged([a, b, other, fine, failed])}
    assert out[("vtk", 64.0)]["mean_dist"] == 2.0
    assert out[("vtk", 64.0)]["max_dist"] == 5.0
    assert out[("vtk", 64.0)]["wall_s"] == 3.0
    assert out[("vtk", 64.0)]["shifts"] == 2
    assert out[("vtk", 128.0)]["mean_dist"] == 7.0 and out[("vtk", 128.0)]["shifts"] == 1
    # A failure at any shift fails the entry: a mean over the runs that worked would flatter it.
    assert out[("corrlap", 64.0)]["status"] == "exit 1: radius"


def _missing_bench_modules():
    return [m for m in ("vtk", "skimage", "open3d") if importlib.util.find_spec(m) is None]


def test_quick_run(tmp_path):
    missing = _missing_bench_modules()
    if missing:
        pytest.skip("the quick comparison needs %s (bash scripts/install_deps.sh --bench)" % ", ".join(missing))
    cli = os.environ.get("CORRLAP_CLI", os.path.join(ROOT, "build", "bin", "corrlap"))
    if not os.path.exists(cli):
        pytest.skip("the quick comparison needs the corrlap binary (CORRLAP_CLI or build/bin/corrlap): %s" % cli)
    out = str(tmp_path / "quick")
    # At 32 voxels across rather than the quick mode's 64: the same code paths in less time.
    subprocess.run([sys.executable, os.path.join(ROOT, "bench", "compare_surfaces.py"), "--quick",
                    "--resolutions", "32", "--out", out, "--corrlap", cli], check=True, capture_output=True, text=True)
    with open(os.path.join(out, "results.csv")) as fh:
        rows = list(csv.DictReader(fh))
    assert [(r["tool"], r["setting"]) for r in rows] == [
        ("vtk", "f=0"), ("vtk", "f=0.5"), ("skimage", "taubin=0"), ("skimage", "taubin=10"),
        ("corrlap", "defaults"), ("corrlap", "polydec")]
    assert all(r["status"] == "ok" for r in rows)
    # The quick run voxelizes once, with the grid off the sphere's centre.
    assert len(set(r["shift"] for r in rows)) == 1 and rows[0]["shift"] != "0.000 0.000 0.000"
    assert all(float(r["staircase_max_vox"]) < 1.0 for r in rows)
    by = {(r["tool"], r["setting"]): float(r["mean_dist_vox"]) for r in rows}
    # Flying edges and marching cubes of the same binary volume are the same surface up to the
    # triangulation of ambiguous cells (3e-4 apart relatively at this size); a wrong axis order or
    # a half-voxel offset between the tools would be more than 10 % apart.
    assert by[("vtk", "f=0")] == pytest.approx(by[("skimage", "taubin=0")], rel=5e-3)
    # Every smoothing brings the staircase closer to the sphere.
    for key in [("vtk", "f=0.5"), ("skimage", "taubin=10"), ("corrlap", "defaults")]:
        assert by[key] < by[("vtk", "f=0")]
    for name in ("summary.md", "comparison_error_vs_voxels.png", "comparison_pareto.png",
                 "comparison_pareto_compute.png"):
        assert os.path.getsize(os.path.join(out, name)) > 0
