"""Volumes from Python (docs/python.md, docs/io.md "Coordinates"): read_volume / write_volume keep
the values in their dtype with the affine, and regularize_volume returns vertices in physical
coordinates, as `corrlap regularize --volume` writes them.

Run by ctest (python_volumes) with PYTHONPATH=<build>/python.
"""
import json
import os
import subprocess

import numpy as np
import pytest

import corrlap

CLI = os.environ.get("CORRLAP_CLI")
needs_cli = pytest.mark.skipif(not CLI, reason="CORRLAP_CLI is not set (the CLI is not built)")


def run_cli(*args):
    r = subprocess.run([CLI, *map(str, args)], capture_output=True, text=True)
    assert r.returncode == 0, f"corrlap {' '.join(map(str, args))} failed:\n{r.stderr}"
    return r


def ellipsoid(spacing, axes=(16.0, 12.0, 10.0)):
    """An ellipsoid sampled at voxel centres origin + spacing * index (uint8 0/1) and its affine."""
    spacing = np.asarray(spacing, dtype=float)
    axes = np.asarray(axes)
    n = 2 * np.ceil((axes + 2 * spacing) / spacing).astype(int) + 1
    origin = -spacing * (n // 2)
    i, j, k = np.meshgrid(*(np.arange(m) for m in n), indexing="ij")
    p = np.stack([i, j, k], axis=-1) * spacing + origin
    inside = ((p / axes) ** 2).sum(axis=-1) <= 1.0
    affine = np.eye(4)
    affine[:3, :3] = np.diag(spacing)
    affine[:3, 3] = origin
    return inside.astype(np.uint8), affine


def test_write_then_read_keeps_values_shape_and_order(tmp_path):
    values = np.zeros((5, 4, 3), dtype=np.uint8)
    values[1, 2, 0] = 7
    values[4, 0, 2] = 200
    path = tmp_path / "v.nrrd"
    corrlap.write_volume(path, values)
    back, affine = corrlap.read_volume(path)
    assert back.shape == (5, 4, 3)
    assert back.dtype == np.uint8
    np.testing.assert_array_equal(back, values)
    np.testing.assert_array_equal(affine, np.eye(4))
    # A C-ordered array and a strided view are written as the same voxels.
    corrlap.write_volume(path, np.ascontiguousarray(values))
    np.testing.assert_array_equal(corrlap.read_volume(path)[0], values)
    corrlap.write_volume(path, values[::2, :, :])
    np.testing.assert_array_equal(corrlap.read_volume(path)[0], values[::2, :, :])


def test_the_affine_round_trips(tmp_path):
    values, affine = ellipsoid((1.0, 1.0, 2.5))
    corrlap.write_volume(tmp_path / "e.nrrd", values, affine)
    back, back_affine = corrlap.read_volume(tmp_path / "e.nrrd")
    np.testing.assert_array_equal(back, values)
    np.testing.assert_allclose(back_affine, affine)


def test_spaces_are_named_and_converted(tmp_path):
    """An LPS affine (3D Slicer's .seg.nrrd) written as NRRD keeps it and names it; as NIfTI it is
    flipped into RAS, nibabel's; space= converts on reading, return_space= names the affine's space."""
    values, affine = ellipsoid((1.0, 1.0, 2.5))
    affine[:3, 3] += [10.0, -20.0, 5.0]
    flip = np.diag([-1.0, -1.0, 1.0, 1.0])
    corrlap.write_volume(tmp_path / "s.nrrd", values, affine, space="LPS")
    corrlap.write_volume(tmp_path / "s.nii", values, affine, space="lps")
    back, lps, name = corrlap.read_volume(tmp_path / "s.nrrd", return_space=True)
    assert name == "LPS"
    np.testing.assert_allclose(lps, affine)
    _, ras, name = corrlap.read_volume(tmp_path / "s.nii", return_space=True)
    assert name == "RAS"
    np.testing.assert_allclose(ras, flip @ affine, atol=1e-5)  # NIfTI-1 holds float32
    np.testing.assert_allclose(corrlap.read_volume(tmp_path / "s.nrrd", space="RAS")[1], flip @ affine)
    np.testing.assert_allclose(corrlap.read_volume(tmp_path / "s.nii", space="LPS")[1], affine, atol=1e-5)
    # Without a space: the affine as it is, and no conversion to ask for.
    corrlap.write_volume(tmp_path / "u.nrrd", values, affine)
    assert corrlap.read_volume(tmp_path / "u.nrrd", return_space=True)[2] is None
    with pytest.raises(ValueError, match="names no anatomical space"):
        corrlap.read_volume(tmp_path / "u.nrrd", space="RAS")
    with pytest.raises(ValueError, match="expected 'RAS', 'LPS', 'LAS' or None"):
        corrlap.write_volume(tmp_path / "x.nrrd", values, affine, space="up")


def test_regularize_volume_returns_millimetres_for_anisotropic_voxels():
    values, affine = ellipsoid((1.0, 1.0, 2.5))
    V, F = corrlap.regularize_volume(values, affine=affine, h=1.0)
    assert F.shape[1] == 4 and V.shape[1] == 3
    assert np.isfinite(V).all()
    # Millimetres around the true ellipsoid (semi-axes 16, 12, 10): within the coarse voxel.
    np.testing.assert_allclose(V.max(axis=0), [16.0, 12.0, 10.0], atol=1.25)
    np.testing.assert_allclose(V.min(axis=0), [-16.0, -12.0, -10.0], atol=1.25)
    r = np.sqrt(((V / [16.0, 12.0, 10.0]) ** 2).sum(axis=1))
    assert np.abs(r - 1).max() < 0.15
    # Without an affine: voxel indices (the ellipsoid's centre voxel index).
    W, _ = corrlap.regularize_volume(values, h=1.0)
    centre = -affine[:3, 3] / np.diag(affine)[:3]
    np.testing.assert_allclose((W.max(axis=0) + W.min(axis=0)) / 2, centre, atol=1.0)


def test_regularize_volume_labels_and_paths(tmp_path):
    seg = np.zeros((24, 14, 14), dtype=np.int16)
    seg[2:10, 3:11, 3:11] = 3
    seg[13:21, 3:11, 3:11] = 7
    V, _ = corrlap.regularize_volume(seg, label=7, h=1.0)
    assert 12.0 < V[:, 0].min() and V[:, 0].max() < 21.0
    V, _ = corrlap.regularize_volume(seg, threshold=5, h=1.0)
    assert V[:, 0].min() > 12.0
    both, _ = corrlap.regularize_volume(seg, h=1.0)  # every nonzero voxel: both boxes
    assert both[:, 0].min() < 3.0 and both[:, 0].max() > 20.0
    with pytest.raises(ValueError, match="label, threshold: give one of them"):
        corrlap.regularize_volume(seg, label=3, threshold=1)
    with pytest.raises(ValueError, match="no voxel equal to the label 4"):
        corrlap.regularize_volume(seg, label=4)
    with pytest.raises(ValueError, match="affine: expected 4 rows"):
        corrlap.regularize_volume(seg, affine=np.eye(3))
    path = tmp_path / "seg.nrrd"
    corrlap.write_volume(path, seg.astype(np.uint8))
    P, _ = corrlap.regularize_volume(path, label=3, h=1.0)
    assert P[:, 0].max() < 10.0
    with pytest.raises(ValueError, match="a volume file has its own geometry"):
        corrlap.regularize_volume(str(path), affine=np.eye(4))


@needs_cli
def test_cli_and_python_take_the_default_curvature_radius_from_the_library(tmp_path):
    # A ball 8 voxels across: 0.1 of its size is below one voxel, so a volume's default curvature
    # radius is the library's floor in voxels, whichever front end regularizes it.
    x = np.arange(12) - 5.5
    ball = ((x[:, None, None] ** 2 + x[None, :, None] ** 2 + x[None, None, :] ** 2) <= 16).astype(np.uint8)
    path = tmp_path / "ball.nrrd"
    corrlap.write_volume(path, ball)
    run_cli("regularize", "--volume", path, "--no-render", "--no-view", "--out", tmp_path / "cli")
    metrics = json.loads((tmp_path / "cli" / "metrics.json").read_text())
    floor = corrlap._core.VOXEL_MIN_CURVATURE_RADIUS * metrics["h"]
    assert metrics["curvature_radius"] == floor
    assert corrlap._core.CURVATURE_RADIUS_FRACTION * metrics["size"] < floor
    P_cli, _ = corrlap.read_mesh(tmp_path / "cli" / "regularized.ply")
    V, _ = corrlap.regularize_volume(path)
    np.testing.assert_array_equal(V, P_cli)
    # The floor is what both used: given, it changes nothing; the paper's 0.1 size gives another surface.
    np.testing.assert_array_equal(corrlap.regularize_volume(path, curvature_radius=floor)[0], V)
    paper = corrlap._core.CURVATURE_RADIUS_FRACTION * metrics["size"]
    assert not np.array_equal(corrlap.regularize_volume(path, curvature_radius=paper)[0], V)
    # `corrlap curvature` on the volume: the same default as regularize.
    run_cli("curvature", "--volume", path, "--out", tmp_path / "k")
    run_cli("curvature", "--volume", path, "--radius", repr(floor), "--out", tmp_path / "k_floor")
    np.testing.assert_array_equal(np.loadtxt(tmp_path / "k" / "H_vertices.txt"),
                                  np.loadtxt(tmp_path / "k_floor" / "H_vertices.txt"))


@needs_cli
def test_cli_and_python_keep_the_papers_curvature_radius_on_a_shape(tmp_path):
    # sphere1 at h = 0.2: 0.1 size is half a voxel, below the volumes' floor, and kept for a shape.
    shape = ["--shape", "sphere1", "--h", "0.2", "--bbox", "-1.5", "1.5"]
    run_cli("regularize", *shape, "--normals", "true", "--no-render", "--no-view", "--out", tmp_path / "r")
    metrics = json.loads((tmp_path / "r" / "metrics.json").read_text())
    assert metrics["curvature_radius"] == corrlap._core.CURVATURE_RADIUS_FRACTION * metrics["size"]
    assert metrics["curvature_radius"] < corrlap._core.VOXEL_MIN_CURVATURE_RADIUS * metrics["h"]
    V, F = corrlap.digitize("sphere1", h=0.2, bbox=(-1.5, 1.5))
    fn = corrlap.true_normals("sphere1", V, F)
    P_cli, _ = corrlap.read_mesh(tmp_path / "r" / "regularized.ply")
    np.testing.assert_array_equal(corrlap.regularize(V, F, face_normals=fn, h=0.2), P_cli)
    # `corrlap curvature` and corrlap.curvature: the same default radius on the shape's surface.
    run_cli("curvature", *shape, "--normals", "true", "--out", tmp_path / "k")
    H = corrlap.curvature(V, F, face_normals=fn)[0]
    np.testing.assert_array_equal(H, np.loadtxt(tmp_path / "k" / "H_vertices.txt"))


def test_regularize_volume_in_another_anatomical_space(tmp_path):
    values, affine = ellipsoid((1.0, 1.0, 2.5))
    path = tmp_path / "e.nii"
    corrlap.write_volume(path, values.astype(np.uint8), affine, space="RAS")
    own, F = corrlap.regularize_volume(path, h=1.0)
    lps, G = corrlap.regularize_volume(path, h=1.0, space="LPS")
    # LPS flips x and y of RAS; the faces are the same (a rotation keeps them facing outwards).
    np.testing.assert_allclose(lps, own * [-1.0, -1.0, 1.0], atol=1e-12)
    assert (F == G).all()
    ras, _ = corrlap.regularize_volume(path, h=1.0, space="ras")
    np.testing.assert_allclose(ras, own, atol=1e-12)
    corrlap.write_volume(tmp_path / "u.nrrd", values.astype(np.uint8), affine)
    with pytest.raises(ValueError, match="space='LPS': the input's physical space is unknown"):
        corrlap.regularize_volume(tmp_path / "u.nrrd", space="LPS")
    with pytest.raises(ValueError, match="an array's affine names no anatomical space"):
        corrlap.regularize_volume(values, affine=affine, space="RAS")
    with pytest.raises(ValueError, match="expected 'RAS', 'LPS', 'LAS' or None"):
        corrlap.regularize_volume(path, space="up")


def test_regularize_volume_solve_accuracy():
    values, affine = ellipsoid((1.0, 1.0, 1.0))
    default, _ = corrlap.regularize_volume(values, h=1.0)
    exact, _ = corrlap.regularize_volume(values, h=1.0, solve_accuracy=0)
    coarse, _ = corrlap.regularize_volume(values, h=1.0, solve_accuracy=0.05)
    # The RMS error is within the accuracy asked, in voxels (h = 1: world units are voxels here).
    assert np.sqrt(((default - exact) ** 2).sum(axis=1).mean()) <= 1e-3 * np.sqrt(3)
    coarse_error = np.sqrt(((coarse - exact) ** 2).sum(axis=1).mean())
    assert coarse_error <= 0.05 * np.sqrt(3)
    # The keyword is taken: a coarser accuracy stops earlier (1e-2 voxels here, 2e-4 by default).
    assert coarse_error > 10 * np.sqrt(((default - exact) ** 2).sum(axis=1).mean())
    with pytest.raises(ValueError, match="solve accuracy"):
        corrlap.regularize_volume(values, h=1.0, solve_accuracy=-1)
    V, F = corrlap.digitize_volume(values, h=1.0)
    N = np.cross(V[F[:, 2]] - V[F[:, 0]], V[F[:, 3]] - V[F[:, 1]])
    N /= np.linalg.norm(N, axis=1)[:, None]
    P = corrlap.regularize(V, F, face_normals=N, solve_accuracy=0)
    assert np.isfinite(P).all()
    with pytest.raises(ValueError, match="solve accuracy"):
        corrlap.regularize(V, F, face_normals=N, solve_accuracy=float("nan"))


def test_regularize_curvature_spacing():
    values, _ = ellipsoid((1.0, 1.0, 1.0))
    V, F = corrlap.digitize_volume(values, h=1.0)
    N = np.cross(V[F[:, 2]] - V[F[:, 0]], V[F[:, 3]] - V[F[:, 1]])
    N /= np.linalg.norm(N, axis=1)[:, None]
    # A ball of 8 voxels: sites 4 voxels apart at spacing 0.5, every vertex at 0.
    every = corrlap.regularize(V, F, face_normals=N, curvature_radius=8.0, curvature_spacing=0,
                               return_curvature=True)
    sites = corrlap.regularize(V, F, face_normals=N, curvature_radius=8.0, curvature_spacing=0.5,
                               return_curvature=True)
    default = corrlap.regularize(V, F, face_normals=N, curvature_radius=8.0, return_curvature=True)
    # The keyword is taken (H interpolated between sites differs), and the default is the library's
    # quarter of the radius: 2 voxels, the smallest spacing that uses sites.
    assert np.abs(sites[1] - every[1]).max() > 0
    assert corrlap._core.CURVATURE_SITE_SPACING == 0.25
    assert np.abs(default[1] - every[1]).max() > 0
    # Means of balls 4 voxels apart, which share most of their faces: a few percent of H with these
    # staircase normals (2.4 % when written), not a different curvature.
    assert np.abs(sites[1] - every[1]).mean() < 0.05 * np.abs(every[1]).mean()
    with pytest.raises(ValueError, match="curvature site spacing"):
        corrlap.regularize(V, F, face_normals=N, curvature_spacing=-1)


def test_regularize_volume_reports_progress():
    values, _ = ellipsoid((1.0, 1.0, 1.0))
    lines = []
    V, F = corrlap.regularize_volume(values, h=1.0, progress=lines.append)
    # The II normals by tenths, in order (a tenth the loop's chunks jump over is not reported), then
    # the curvature and the first solve, as the CLI's lines.
    tenths = [line for line in lines if line.startswith("ii normals: ")]
    percents = [int(line[len("ii normals: "):-1]) for line in tenths]
    assert percents == sorted(set(percents)) and percents[-1] == 100
    assert set(percents) <= set(range(10, 101, 10))
    rest = lines[len(tenths):]
    assert rest[0].startswith("mean curvature in balls of radius ")
    assert rest[1] == "solving with alpha0 = 10"
    # Reporting changes nothing.
    V0, F0 = corrlap.regularize_volume(values, h=1.0)
    assert np.array_equal(V, V0) and np.array_equal(F, F0)
    with pytest.raises(TypeError, match="progress: expected None or a callable"):
        corrlap.regularize_volume(values, h=1.0, progress="yes")


def test_an_exception_in_progress_stops_the_computation():
    values, _ = ellipsoid((1.0, 1.0, 1.0))
    calls = []

    def stop(line):
        calls.append(line)
        raise KeyError("stopped at " + line)

    # From the II normals' loop (worker threads report too) ...
    with pytest.raises(KeyError, match="stopped at ii normals: "):
        corrlap.regularize_volume(values, h=1.0, progress=stop)
    assert len(calls) == 1 and calls[0].startswith("ii normals: ")
    # ... and from the regularization's stages, on a mesh.
    V, F = corrlap.digitize_volume(values, h=1.0)
    N = np.cross(V[F[:, 2]] - V[F[:, 0]], V[F[:, 3]] - V[F[:, 1]])
    N /= np.linalg.norm(N, axis=1)[:, None]
    calls.clear()
    with pytest.raises(KeyError, match="stopped at mean curvature"):
        corrlap.regularize(V, F, face_normals=N, progress=stop)
    assert len(calls) == 1
    # A callable that returns normally lets it finish, with the same result as without one.
    seen = []
    assert np.array_equal(corrlap.regularize(V, F, face_normals=N, progress=seen.append),
                          corrlap.regularize(V, F, face_normals=N))
    assert seen[0].startswith("mean curvature") and seen[1] == "solving with alpha0 = 10"


def test_ctrl_c_stops_a_regularization_at_its_next_stage():
    import collections
    import signal
    import threading
    import time

    values, _ = ellipsoid((1.0, 1.0, 1.0), axes=(40.0, 30.0, 24.0))
    # SIGINT once the computation has reported once. The progress callable is a builtin (no Python
    # code runs in the main thread until the computation returns), so only the library's own check
    # at its next report can raise KeyboardInterrupt before the end.
    lines = collections.deque()

    def interrupt():
        while not lines:
            time.sleep(0.001)
        signal.raise_signal(signal.SIGINT)

    timer = threading.Thread(target=interrupt)
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            corrlap.regularize_volume(values, h=1.0, progress=lines.append)
    finally:
        timer.join()
    # Stopped before the solve was announced.
    assert 1 <= len(lines) and "solving with alpha0 = 10" not in lines
