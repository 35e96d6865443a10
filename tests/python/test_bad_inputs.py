"""The Python catalogue of bad inputs (docs/python.md, Conventions: "Arguments"): every case
is refused with the documented exception type and a message that names the parameter or the
problem, never a crash, a RuntimeError for a user mistake, or a default silently taken instead.

Run by ctest (python_bad_inputs) with PYTHONPATH=<build>/python.
"""
import sys
import time

import numpy as np
import pytest
import scipy.sparse as sp

import corrlap

H = 0.3
BOX = (-1.5, 1.5)


@pytest.fixture(scope="module")
def sphere():
    V, F = corrlap.digitize("sphere1", h=H, bbox=BOX)
    return V, F, corrlap.true_normals("sphere1", V, F)


@pytest.fixture(scope="module")
def operators(sphere):
    V, F, fn = sphere
    L, M = corrlap.laplacian(V, F, method="fem", face_normals=fn)
    return L, M


def ball(n=12):
    x, y, z = np.meshgrid(*(np.arange(n),) * 3, indexing="ij")
    c = (n - 1) / 2
    return (x - c) ** 2 + (y - 0.8 * c) ** 2 + (z - 1.1 * c) ** 2 <= (0.4 * n) ** 2


def big_endian(a):
    return a.astype(a.dtype.newbyteorder(">"))


# ---- the table: (id, call, exception type, regex the message must contain) ----
# `call` takes the fixtures (V, F, fn, L, M).

NAN = float("nan")
INF = float("inf")

CASES = [
    # digitize_volume: arrays
    ("volume 2D", lambda V, F, fn, L, M: corrlap.digitize_volume(np.ones((4, 4))), ValueError,
     r"volume: expected a 3D array, got 2 dimensions"),
    ("volume 4D", lambda V, F, fn, L, M: corrlap.digitize_volume(np.ones((2, 2, 2, 2))), ValueError,
     r"volume: expected a 3D array"),
    ("volume empty axis", lambda V, F, fn, L, M: corrlap.digitize_volume(np.ones((0, 4, 4))), ValueError,
     r"volume: empty array \(0x4x4 voxels\)"),
    ("volume complex", lambda V, F, fn, L, M: corrlap.digitize_volume(np.ones((2, 2, 2), complex)), ValueError,
     r"volume: dtype complex128 is not supported"),
    ("volume float16", lambda V, F, fn, L, M: corrlap.digitize_volume(np.ones((2, 2, 2), np.float16)), ValueError,
     r"volume: dtype float16 is not supported.*astype"),
    ("volume strings", lambda V, F, fn, L, M: corrlap.digitize_volume(np.full((2, 2, 2), "a")), ValueError,
     r"volume: dtype <U1 is not supported"),
    ("volume objects", lambda V, F, fn, L, M: corrlap.digitize_volume(np.full((2, 2, 2), None)), ValueError,
     r"volume: dtype object is not supported"),
    ("volume ragged", lambda V, F, fn, L, M: corrlap.digitize_volume([[[1]], [[1, 2]]]), ValueError,
     r"volume: not convertible to a numpy array"),
    ("volume all zero", lambda V, F, fn, L, M: corrlap.digitize_volume(np.zeros((4, 4, 4), np.uint8)), ValueError,
     r"volume: no voxel above the threshold 0 \(empty volume\)"),
    ("volume all False", lambda V, F, fn, L, M: corrlap.digitize_volume(np.zeros((4, 4, 4), bool)), ValueError,
     r"empty volume"),
    ("volume below threshold", lambda V, F, fn, L, M: corrlap.digitize_volume(ball().astype(np.int16),
                                                                              threshold=1), ValueError,
     r"no voxel above the threshold 1 \(empty volume\)"),
    ("volume NaN", lambda V, F, fn, L, M: corrlap.digitize_volume(np.where(ball(), np.nan, 0.0)), ValueError,
     r"volume: value at \[\d+, \d+, \d+\] is NaN"),
    ("volume NaN float32 Fortran", lambda V, F, fn, L, M: corrlap.digitize_volume(
        np.asfortranarray(np.where(ball(), np.float32(np.nan), np.float32(0)))), ValueError, r"is NaN"),
    ("volume broadcast NaN 1600^3", lambda V, F, fn, L, M: corrlap.digitize_volume(
        np.broadcast_to(np.float64(np.nan), (1600,) * 3)), ValueError, r"value at \[0, 0, 0\] is NaN"),
    # digitize_volume: parameters
    ("volume h=0", lambda V, F, fn, L, M: corrlap.digitize_volume(ball(), h=0), ValueError,
     r"grid step h = 0 must be positive"),
    ("volume h=-1", lambda V, F, fn, L, M: corrlap.digitize_volume(ball(), h=-1), ValueError,
     r"grid step h = -1 must be positive"),
    ("volume h=nan", lambda V, F, fn, L, M: corrlap.digitize_volume(ball(), h=NAN), ValueError,
     r"grid step h = nan must be positive"),
    ("volume h=inf", lambda V, F, fn, L, M: corrlap.digitize_volume(ball(), h=INF), ValueError,
     r"grid step h = inf must be positive"),
    ("volume h=str", lambda V, F, fn, L, M: corrlap.digitize_volume(ball(), h="0.1"), TypeError,
     r"h: expected a real number, got str"),
    ("volume h=True", lambda V, F, fn, L, M: corrlap.digitize_volume(ball(), h=True), TypeError,
     r"h: expected a real number, got bool"),
    ("volume threshold=nan", lambda V, F, fn, L, M: corrlap.digitize_volume(ball(), threshold=NAN), ValueError,
     r"threshold = nan must be a finite number"),
    ("volume threshold=-inf", lambda V, F, fn, L, M: corrlap.digitize_volume(ball(), threshold=-INF), ValueError,
     r"threshold = -inf must be a finite number"),
    ("volume threshold=None", lambda V, F, fn, L, M: corrlap.digitize_volume(ball(), threshold=None), TypeError,
     r"threshold: a number is required"),
    # digitize
    ("digitize h=0", lambda V, F, fn, L, M: corrlap.digitize("sphere1", h=0, bbox=BOX), ValueError,
     r"grid step h = 0 must be positive"),
    ("digitize h=nan", lambda V, F, fn, L, M: corrlap.digitize("sphere1", h=NAN, bbox=BOX), ValueError,
     r"grid step h = nan must be positive"),
    ("digitize h=None", lambda V, F, fn, L, M: corrlap.digitize("sphere1", h=None, bbox=BOX), TypeError,
     r"h: a number is required"),
    ("digitize offset=5.5", lambda V, F, fn, L, M: corrlap.digitize("sphere1", h=H, bbox=BOX, offset=5.5),
     TypeError, r"offset: expected an integer, got float 5.5"),
    ("digitize bbox str", lambda V, F, fn, L, M: corrlap.digitize("sphere1", h=H, bbox=("a", 1)), TypeError,
     r"bbox: expected a real number, got str"),
    ("digitize bad shape", lambda V, F, fn, L, M: corrlap.digitize("nope", h=H, bbox=BOX), ValueError, r"nope"),
    ("digitize center NaN", lambda V, F, fn, L, M: corrlap.digitize("sphere1", h=H, bbox=BOX,
                                                                     center=(0, NAN, 0)), ValueError,
     r"center: row 0 is not finite"),
    # laplacian
    ("laplacian h=0", lambda V, F, fn, L, M: corrlap.laplacian(V, F, "heat-kernel", face_normals=fn, h=0),
     ValueError, r"grid step h = 0 must be positive"),
    ("laplacian h=-1", lambda V, F, fn, L, M: corrlap.laplacian(V, F, "heat-kernel", face_normals=fn, h=-1),
     ValueError, r"grid step h = -1 must be positive"),
    ("laplacian h=nan", lambda V, F, fn, L, M: corrlap.laplacian(V, F, "heat-kernel", face_normals=fn, h=NAN),
     ValueError, r"grid step h = nan must be positive"),
    ("laplacian h=inf", lambda V, F, fn, L, M: corrlap.laplacian(V, F, "heat-kernel", face_normals=fn, h=INF),
     ValueError, r"grid step h = inf must be positive"),
    ("laplacian bad method", lambda V, F, fn, L, M: corrlap.laplacian(V, F, "nope", face_normals=fn), ValueError,
     r"nope"),
    ("laplacian lam=nan", lambda V, F, fn, L, M: corrlap.laplacian(V, F, "polydec", face_normals=fn, lam=NAN),
     ValueError, r"lambda"),
    ("laplacian lam=-1", lambda V, F, fn, L, M: corrlap.laplacian(V, F, "polydec", face_normals=fn, lam=-1),
     ValueError, r"lambda = -1: expected >= 0"),
    ("laplacian integer parameter 5.5", lambda V, F, fn, L, M: corrlap.laplacian(
        V, F, "corrected-vrm", face_normals=fn, max_iterations=5.5), ValueError, r"max_iterations = 5.5: expected an integer"),
    ("laplacian integer parameter True", lambda V, F, fn, L, M: corrlap.laplacian(
        V, F, "corrected-vrm", face_normals=fn, max_iterations=True), ValueError, r"max_iterations"),
    ("heat-kernel k=nan", lambda V, F, fn, L, M: corrlap.laplacian(V, F, "heat-kernel", face_normals=fn, k=NAN),
     ValueError, r"heat-kernel: k = nan: expected a finite number"),
    ("heat-kernel t=0", lambda V, F, fn, L, M: corrlap.laplacian(V, F, "heat-kernel", face_normals=fn, t=0),
     ValueError, r"heat-kernel: t = 0"),
    ("heat-kernel alpha=inf", lambda V, F, fn, L, M: corrlap.laplacian(V, F, "heat-kernel", face_normals=fn,
                                                                       alpha=INF), ValueError, r"alpha = inf"),
    ("heat-kernel cutoff=-1", lambda V, F, fn, L, M: corrlap.laplacian(V, F, "heat-kernel", face_normals=fn,
                                                                       cutoff=-1), ValueError, r"cutoff = -1"),
    ("laplacian unknown keyword", lambda V, F, fn, L, M: corrlap.laplacian(V, F, "fem", face_normals=fn, bogus=1),
     ValueError, r"bogus"),
    ("laplacian option list", lambda V, F, fn, L, M: corrlap.laplacian(V, F, "fem", face_normals=fn, mass=[1]),
     ValueError, r"option 'mass' has type"),
    ("laplacian V 1D", lambda V, F, fn, L, M: corrlap.laplacian(V.ravel(), F, "fem", face_normals=fn), ValueError,
     r"V: expected shape \(n, 3\)"),
    ("laplacian V strings", lambda V, F, fn, L, M: corrlap.laplacian(V.astype(str), F, "fem", face_normals=fn),
     ValueError, r"V: dtype <U\d+ is not supported"),
    ("laplacian V inf", lambda V, F, fn, L, M: corrlap.laplacian(np.where(V == V[7], np.inf, V), F, "fem",
                                                                 face_normals=fn), ValueError, r"V: row \d+ is not finite"),
    ("laplacian F float", lambda V, F, fn, L, M: corrlap.laplacian(V, F.astype(float), "fem", face_normals=fn),
     ValueError, r"F: vertex ids must be integers"),
    ("laplacian F triangles", lambda V, F, fn, L, M: corrlap.laplacian(V, F[:, :3], "fem", face_normals=fn),
     ValueError, r"F: expected shape \(m, 4\)"),
    ("laplacian F negative", lambda V, F, fn, L, M: corrlap.laplacian(V, F - 1, "fem", face_normals=fn),
     ValueError, r"F: face 0 has vertex id -1"),
    ("laplacian no normals", lambda V, F, fn, L, M: corrlap.laplacian(V, F, "fem"), ValueError,
     r"needs face normals"),
    ("laplacian normals wrong rows", lambda V, F, fn, L, M: corrlap.laplacian(V, F, "fem", face_normals=fn[1:]),
     ValueError, r"face_normals: expected \d+ rows"),
    # solve
    ("solve A 0x0", lambda V, F, fn, L, M: corrlap.solve(sp.csc_matrix((0, 0)), np.zeros(0)), ValueError,
     r"A: expected a square matrix with at least one row, got 0 x 0"),
    ("solve A not square", lambda V, F, fn, L, M: corrlap.solve(M[:, :-1], np.ones(M.shape[0])), ValueError,
     r"A: expected a square matrix"),
    ("solve A 1D", lambda V, F, fn, L, M: corrlap.solve(np.ones(3), np.ones(3)), ValueError,
     r"A: expected a scipy sparse matrix or a 2D real array"),
    ("solve A NaN", lambda V, F, fn, L, M: corrlap.solve(np.diag([1.0, NAN]), np.ones(2)), ValueError,
     r"A: entry \(1, 1\) is not finite"),
    ("solve A bool", lambda V, F, fn, L, M: corrlap.solve(np.eye(2, dtype=bool), np.ones(2)), ValueError,
     r"A: expected a scipy sparse matrix or a 2D real array, got 2D dtype bool"),
    ("solve b rows", lambda V, F, fn, L, M: corrlap.solve(M, np.ones(M.shape[0] + 1)), ValueError,
     r"b: expected \d+ rows"),
    ("solve b 3D", lambda V, F, fn, L, M: corrlap.solve(M, np.ones((M.shape[0], 1, 1))), ValueError,
     r"b: expected shape \(n,\) or \(n, k\)"),
    ("solve b NaN", lambda V, F, fn, L, M: corrlap.solve(M, np.full(M.shape[0], NAN)), ValueError,
     r"b: a value is not finite"),
    ("solve b inf", lambda V, F, fn, L, M: corrlap.solve(M, np.full((M.shape[0], 2), INF)), ValueError,
     r"b: a value is not finite"),
    ("solve bad solver", lambda V, F, fn, L, M: corrlap.solve(M, np.ones(M.shape[0]), solver="nope"), ValueError,
     r"nope"),
    ("solve tolerance NaN", lambda V, F, fn, L, M: corrlap.solve(M, np.ones(M.shape[0]), solver="cg",
                                                                 tolerance=NAN), ValueError, r"tolerance"),
    # eigs
    ("eigs k=5.5", lambda V, F, fn, L, M: corrlap.eigs(L, M, k=5.5), TypeError, r"k: expected an integer, got float 5.5"),
    ("eigs k=True", lambda V, F, fn, L, M: corrlap.eigs(L, M, k=True), TypeError, r"k: expected an integer, got bool"),
    ("eigs k=None", lambda V, F, fn, L, M: corrlap.eigs(L, M, k=None), TypeError, r"k: expected an integer"),
    ("eigs k='5'", lambda V, F, fn, L, M: corrlap.eigs(L, M, k="5"), TypeError, r"k: expected an integer, got str"),
    ("eigs k=0", lambda V, F, fn, L, M: corrlap.eigs(L, M, k=0), ValueError, r"k = 0 must be in \[1, \d+\]"),
    ("eigs k=-3", lambda V, F, fn, L, M: corrlap.eigs(L, M, k=-3), ValueError, r"k = -3 must be in \[1, \d+\]"),
    ("eigs k > n", lambda V, F, fn, L, M: corrlap.eigs(L, M, k=L.shape[0] + 1), ValueError, r"k = \d+ must be in"),
    ("eigs k=2^40", lambda V, F, fn, L, M: corrlap.eigs(L, M, k=2**40), ValueError, r"k: 1099511627776 is out of range"),
    ("eigs dense k=0", lambda V, F, fn, L, M: corrlap.eigs(L, M, k=0, eigen_solver="dense"), ValueError,
     r"k = 0 must be in"),
    ("eigs L 0x0", lambda V, F, fn, L, M: corrlap.eigs(sp.csc_matrix((0, 0)), sp.csc_matrix((0, 0)), k=1),
     ValueError, r"L: expected a square matrix with at least one row, got 0 x 0"),
    ("eigs L not square", lambda V, F, fn, L, M: corrlap.eigs(L[:, :-1], M, k=2), ValueError,
     r"L: expected a square matrix"),
    ("eigs sizes differ", lambda V, F, fn, L, M: corrlap.eigs(L, M[:-1, :-1], k=2), ValueError,
     r"L, M: different sizes"),
    ("eigs L NaN", lambda V, F, fn, L, M: corrlap.eigs(L * NAN, M, k=2), ValueError, r"L: entry .* is not finite"),
    ("eigs bad eigen solver", lambda V, F, fn, L, M: corrlap.eigs(L, M, k=2, eigen_solver="nope"), ValueError,
     r"nope"),
    # normals and curvature
    ("curvature radius=-1", lambda V, F, fn, L, M: corrlap.curvature(V, F, face_normals=fn, radius=-1), ValueError,
     r"ball radius must be >= 0"),
    ("curvature radius=nan", lambda V, F, fn, L, M: corrlap.curvature(V, F, face_normals=fn, radius=NAN),
     ValueError, r"ball radius must be >= 0, got nan"),
    ("curvature radius=inf", lambda V, F, fn, L, M: corrlap.curvature(V, F, face_normals=fn, radius=INF),
     ValueError, r"ball radius must be >= 0, got inf"),
    ("curvature radius='x'", lambda V, F, fn, L, M: corrlap.curvature(V, F, face_normals=fn, radius="x"),
     TypeError, r"radius: expected a real number"),
    ("curvature at", lambda V, F, fn, L, M: corrlap.curvature(V, F, face_normals=fn, at="edges"), ValueError,
     r"at: 'edges': expected 'faces' or 'vertices'"),
    ("true_normals at", lambda V, F, fn, L, M: corrlap.true_normals("sphere1", V, F, at="edges"), ValueError,
     r"at: 'edges'"),
    ("ii_normals k=0", lambda V, F, fn, L, M: corrlap.ii_normals("sphere1", V, F, h=H, bbox=BOX, k=0), ValueError,
     r"radius factor k = 0\.0+ must be positive"),
    ("ii_normals alpha=nan", lambda V, F, fn, L, M: corrlap.ii_normals("sphere1", V, F, h=H, bbox=BOX, alpha=NAN),
     ValueError, r"alpha must be finite"),
    ("ii_normals h=0", lambda V, F, fn, L, M: corrlap.ii_normals("sphere1", V, F, h=0, bbox=BOX), ValueError,
     r"grid step h = 0 must be positive"),
    ("ii_normals h=None", lambda V, F, fn, L, M: corrlap.ii_normals("sphere1", V, F, bbox=BOX), ValueError,
     r"h: required with a shape"),
    ("ii_normals volume h=-1", lambda V, F, fn, L, M: corrlap.ii_normals(ball(), V, F, h=-1), ValueError,
     r"grid step h = -1 must be positive"),
    # regularize
    ("regularize h=0", lambda V, F, fn, L, M: corrlap.regularize(V, F, face_normals=fn, h=0), ValueError,
     r"grid step h = 0 must be positive"),
    ("regularize h=nan", lambda V, F, fn, L, M: corrlap.regularize(V, F, face_normals=fn, h=NAN), ValueError,
     r"grid step h = nan must be positive"),
    ("regularize alpha0=-1", lambda V, F, fn, L, M: corrlap.regularize(V, F, face_normals=fn, alpha0=-1),
     ValueError, r"alpha0 = [-\w]+: alpha0 must be a finite number >= 0"),
    ("regularize alpha0=nan", lambda V, F, fn, L, M: corrlap.regularize(V, F, face_normals=fn, alpha0=NAN),
     ValueError, r"alpha0 = [-\w]+: alpha0 must be a finite number >= 0"),
    ("regularize alpha0=inf", lambda V, F, fn, L, M: corrlap.regularize(V, F, face_normals=fn, alpha0=INF),
     ValueError, r"alpha0 = [-\w]+: alpha0 must be a finite number >= 0"),
    ("regularize alpha0=None", lambda V, F, fn, L, M: corrlap.regularize(V, F, face_normals=fn, alpha0=None),
     TypeError, r"alpha0: a number is required"),
    ("regularize curvature_radius=0", lambda V, F, fn, L, M: corrlap.regularize(V, F, face_normals=fn,
                                                                                curvature_radius=0), ValueError,
     r"curvature_radius = \w+: the curvature radius must be a finite number > 0"),
    ("regularize curvature_radius=nan", lambda V, F, fn, L, M: corrlap.regularize(V, F, face_normals=fn,
                                                                                  curvature_radius=NAN), ValueError,
     r"curvature_radius = \w+: the curvature radius must be a finite number > 0"),
    ("regularize size=-1", lambda V, F, fn, L, M: corrlap.regularize(V, F, face_normals=fn, size=-1), ValueError,
     r"size = -1: the object size must be a finite number > 0"),
    ("regularize no normals", lambda V, F, fn, L, M: corrlap.regularize(V, F), ValueError,
     r"face_normals, vertex_normals: give one of them"),
    ("regularize bad method", lambda V, F, fn, L, M: corrlap.regularize(V, F, face_normals=fn, method="nope"),
     ValueError, r"nope"),
    # module settings and files
    ("set_threads 1.5", lambda V, F, fn, L, M: corrlap.set_threads(1.5), TypeError,
     r"n: expected an integer, got float"),
    ("set_max_memory garbage", lambda V, F, fn, L, M: corrlap.set_max_memory("lots"), ValueError, r"lots"),
    ("set_max_memory 0", lambda V, F, fn, L, M: corrlap.set_max_memory(0), ValueError, r"'0'"),
    ("set_max_memory float", lambda V, F, fn, L, M: corrlap.set_max_memory(1.5e9), TypeError,
     r"size: expected bytes"),
    ("read_mesh missing", lambda V, F, fn, L, M: corrlap.read_mesh("/nonexistent/x.obj"), ValueError,
     r"/nonexistent/x.obj"),
    ("write_mesh scalars rows", lambda V, F, fn, L, M: corrlap.write_mesh("/tmp/corrlap_bad.ply", V, F,
                                                                          vertex_scalars={"H": np.ones(3)}),
     ValueError, r"vertex_scalars\['H'\]: expected \d+ values"),
]


@pytest.mark.parametrize("name,call,error,match", CASES, ids=[c[0] for c in CASES])
def test_bad_input_is_refused_with_a_named_error(sphere, operators, name, call, error, match):
    V, F, fn = sphere
    L, M = operators
    with pytest.raises(error, match=match) as e:
        call(V, F, fn, L, M)
    assert type(e.value) is error  # not a subclass standing in for another kind of failure


def test_broadcast_volume_of_1600_cubed_is_refused_quickly_without_a_copy():
    # 1600^3 voxels: a float64 copy would be 33 GB. The zero strides are read as they are, and the
    # one distinct value decides before anything is allocated.
    start = time.monotonic()
    with pytest.raises(ValueError, match=r"no voxel above the threshold 0 \(empty volume\)"):
        corrlap.digitize_volume(np.broadcast_to(np.uint8(0), (1600,) * 3))
    assert time.monotonic() - start < 1.0


def test_voxel_grid_is_checked_against_the_memory_budget_before_allocation():
    volume = np.ones((300, 300, 300), bool)  # a grid of 302^3 bits, 3.4 MB
    try:
        corrlap.set_max_memory("1M")
        assert corrlap.get_max_memory() == 2**20
        with pytest.raises(ValueError, match=r"voxel grid: a box of 302x302x302 voxels needs .* memory budget"):
            corrlap.digitize_volume(volume)
    finally:
        corrlap.set_max_memory(None)
    assert corrlap.get_max_memory() > 2**20


def test_none_is_the_default_and_only_none(sphere):
    V, F, fn = sphere
    # h=None: the longest side spans 2, as the CLI's default; an explicit equal h gives the same surface.
    volume = ball(10)
    V1, F1 = corrlap.digitize_volume(volume, h=None)
    V2, F2 = corrlap.digitize_volume(volume, h=0.2)
    assert np.array_equal(V1, V2) and np.array_equal(F1, F2)
    # Method parameters and solver options: None is "not given".
    L1, M1 = corrlap.laplacian(V, F, "polydec", face_normals=fn, lam=None)
    L2, M2 = corrlap.laplacian(V, F, "polydec", face_normals=fn)
    assert (L1 != L2).nnz == 0 and (M1 != M2).nnz == 0


# ---- arrays read in their own dtype and strides: the same surface as the C-ordered float64 array ----

def layouts(volume):
    """(name, array) views of the boolean volume in many dtypes and memory layouts, all equal to it
    as `value > 0.5` (bool: True)."""
    out = [("bool", volume)]
    for dtype in (np.int8, np.int16, np.int32, np.int64, np.uint8, np.uint16, np.uint32, np.uint64, np.float32,
                  np.float64):
        out.append((np.dtype(dtype).name, volume.astype(dtype)))
        out.append((np.dtype(dtype).name + " big-endian", big_endian(volume.astype(dtype))))
    out.append(("Fortran", np.asfortranarray(volume.astype(np.float32))))
    padded = np.zeros((2 * volume.shape[0], volume.shape[1], 3 * volume.shape[2]), np.int16)
    padded[::2, :, ::3] = volume
    out.append(("strided view", padded[::2, :, ::3]))
    flipped = np.ascontiguousarray(volume[::-1, :, ::-1])
    out.append(("negative strides", flipped[::-1, :, ::-1]))
    out.append(("transposed view", np.ascontiguousarray(volume.transpose(2, 0, 1)).transpose(1, 2, 0)))
    return out


def test_volume_of_any_dtype_and_layout_gives_the_same_surface():
    volume = ball(13)
    reference = corrlap.digitize_volume(volume.astype(np.float64), threshold=0.5)
    for name, array in layouts(volume):
        V, F = corrlap.digitize_volume(array, threshold=0.5)
        assert np.array_equal(V, reference[0]) and np.array_equal(F, reference[1]), name


def test_broadcast_volume_equals_its_explicit_copy():
    column = np.array([0, 3, 3, 0, 5, 0], np.uint16)
    broadcast = np.broadcast_to(column, (4, 5, 6))  # strides (0, 0, 2)
    assert broadcast.strides[0] == 0
    for threshold in (0, 2, 4):
        V1, F1 = corrlap.digitize_volume(broadcast, threshold=threshold)
        V2, F2 = corrlap.digitize_volume(np.ascontiguousarray(broadcast).astype(np.float64), threshold=threshold)
        assert np.array_equal(V1, V2) and np.array_equal(F1, F2)


def test_64_bit_integers_are_compared_exactly():
    # As float64 both values are 2^62: a converted copy would find no voxel above 2^62.
    volume = np.full((1, 1, 1), 2**62 + 1, np.int64)
    V, F = corrlap.digitize_volume(volume, threshold=float(2**62))
    assert len(F) == 6
    with pytest.raises(ValueError, match="empty volume"):
        corrlap.digitize_volume(np.full((1, 1, 1), 2**62, np.int64), threshold=float(2**62))
    V, F = corrlap.digitize_volume(np.full((1, 1, 1), 2**64 - 1, np.uint64), threshold=float(2**63))
    assert len(F) == 6


def test_solve_with_no_right_hand_side_gives_an_empty_solution(operators):
    L, M = operators
    n = M.shape[0]
    x = corrlap.solve(M - L, np.zeros((n, 0)))
    assert x.shape == (n, 0)


# ---- the regularization's solution check (the library side is in regularization/solution_check.hpp) ----

def test_regularize_huge_alpha0(sphere):
    """alpha0 = 1e160 makes alpha overflow the solve: the result must not be zeros returned as success."""
    V, F, fn = sphere
    with pytest.raises((ValueError, RuntimeError)):
        P = corrlap.regularize(V, F, face_normals=fn, alpha0=1e160)
        print(f"regularize(alpha0=1e160) returned P with |P| max {np.abs(P).max()}", file=sys.stderr)


def test_regularize_without_attachment(sphere):
    """alpha0 = 0 is the unattached solve (docs/math.md §9.3), not an error: the limit of the attached
    solutions as alpha0 -> 0, so a tiny alpha0 lands next to it (the library test follows the gap
    down to 2e-7 at 1e-6; here, below 1e-4 of the sphere's size)."""
    V, F, fn = sphere
    free = corrlap.regularize(V, F, face_normals=fn, alpha0=0)
    assert free.shape == V.shape and np.isfinite(free).all()
    tiny = corrlap.regularize(V, F, face_normals=fn, alpha0=1e-6)
    assert np.abs(free - tiny).max() < 1e-4 * 2.0
    # Without attachment the corrected operator still rounds the staircase (224 vertices at h = 0.3):
    # the spread of the radii falls from 0.125 to 0.005, and the mean radius stays as near 1 (0.035).
    r, r0 = np.linalg.norm(free, axis=1), np.linalg.norm(V, axis=1)
    assert r.std() < 0.1 * r0.std()
    assert abs(r.mean() - 1.0) <= abs(r0.mean() - 1.0)


def test_regularize_alpha0_auto(sphere):
    """alpha0='auto' is the default (docs/math.md §9.4): on a smooth sphere it keeps alpha0 = 10, so
    the result is the fixed alpha0's to the bit; another word is refused, naming alpha0."""
    V, F, fn = sphere
    default = corrlap.regularize(V, F, face_normals=fn)
    auto = corrlap.regularize(V, F, face_normals=fn, alpha0="auto")
    fixed = corrlap.regularize(V, F, face_normals=fn, alpha0=10)
    assert np.array_equal(default, auto) and np.array_equal(auto, fixed)
    with pytest.raises((TypeError, ValueError), match="alpha0"):
        corrlap.regularize(V, F, face_normals=fn, alpha0="automatic")
