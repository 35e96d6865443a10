"""The Python bindings (python/, docs/python.md) give what the CLI gives for the same input: the
operators bit for bit, the eigenvalues, normals, curvature and meshes; errors keep the C++ message.

Run by ctest (python_bindings) with PYTHONPATH=<build>/python and CORRLAP_CLI=<the built corrlap>.
"""
import os
import subprocess
import threading
import time

import numpy as np
import pytest
import scipy.io
import scipy.sparse as sp

import corrlap

CLI = os.environ.get("CORRLAP_CLI")
needs_cli = pytest.mark.skipif(not CLI, reason="CORRLAP_CLI is not set (the CLI is not built)")
H = 0.2
SHAPE = ["--shape", "sphere1", "--h", str(H)]  # the CLI's default box (-10, 10), offset 5


def run_cli(*args, check=True):
    r = subprocess.run([CLI, *map(str, args)], capture_output=True, text=True)
    if check and r.returncode != 0:
        raise AssertionError(f"corrlap {' '.join(map(str, args))} failed:\n{r.stderr}")
    return r


@pytest.fixture(scope="module")
def sphere():
    V, F = corrlap.digitize("sphere1", h=H)
    return V, F, corrlap.true_normals("sphere1", V, F)


def assert_same_csc(A, B):
    """Same shape, pattern and values, bit for bit (explicit zeros included)."""
    A, B = sp.csc_matrix(A), sp.csc_matrix(B)
    A.sort_indices()
    B.sort_indices()
    assert A.shape == B.shape
    assert np.array_equal(A.indptr, B.indptr)
    assert np.array_equal(A.indices, B.indices)
    assert np.array_equal(A.data, B.data)


# (method, CLI options, laplacian keywords): every method, and the named parameters of `operators`.
OPERATOR_CASES = [
    ("fem", [], {}),
    ("fem", ["--mass", "lumped"], {"mass": "lumped"}),
    ("interpolated", ["--lambda", "0.1"], {"lam": 0.1}),
    ("interpolated", ["--lambda", "0.3", "--kappa", "1", "--assembly", "local"],
     {"lam": 0.3, "kappa": 1, "assembly": "local"}),
    ("polydec", [], {}),
    ("polydec", ["--lambda", "0.5"], {"lam": 0.5}),
    ("projected-polydec", [], {}),
    ("vrm", [], {}),
    ("corrected-vrm", [], {}),
    ("heat-kernel", [], {}),
    ("heat-kernel", ["--t", "0.02", "--cutoff", "2.5", "--param", "variant=primal"],
     {"t": 0.02, "cutoff": 2.5, "variant": "primal"}),
    ("cotan", [], {}),
]


def test_operator_cases_cover_every_registered_method():
    assert {case[0] for case in OPERATOR_CASES} == set(corrlap.methods())


@needs_cli
@pytest.mark.parametrize("method,cli_args,kwargs", OPERATOR_CASES,
                         ids=[f"{m}{'-' + '-'.join(a[1::2]) if a else ''}" for m, a, _ in OPERATOR_CASES])
def test_laplacian_equals_cli_operators_bitwise(sphere, tmp_path, method, cli_args, kwargs):
    V, F, fn = sphere
    run_cli("operators", "--method", method, *SHAPE, "--normals", "true", *cli_args, "--out", tmp_path)
    # h: the grid step the CLI's surface carries (heat-kernel's default t and lattice depend on it).
    L, M = corrlap.laplacian(V, F, method=method, face_normals=fn, h=H, **kwargs)
    assert isinstance(L, sp.csc_matrix) and isinstance(M, sp.csc_matrix)
    assert_same_csc(L, scipy.io.mmread(str(tmp_path / "L.mtx")))
    assert_same_csc(M, scipy.io.mmread(str(tmp_path / "M.mtx")))


def test_every_method_parameter_is_a_keyword_of_laplacian(sphere):
    # The keywords are derived from the C++ declarations (corrlap.methods()): each one reaches the
    # signature and the docstring, and its declared default gives the operators of no keyword.
    import inspect
    V, F, fn = sphere
    signature = inspect.signature(corrlap.laplacian).parameters
    for method, (_normals, params) in corrlap.methods().items():
        plain_L, plain_M = corrlap.laplacian(V, F, method=method, face_normals=fn, h=H)
        for name, default, _description in params:
            keyword = "lam" if name == "lambda" else name
            assert keyword in signature, (method, name)
            assert signature[keyword].kind == inspect.Parameter.KEYWORD_ONLY
            assert f"{keyword}:" in corrlap.laplacian.__doc__
            if default in ("true", "false"):
                value = default == "true"
            else:
                try:
                    value = float(default)
                except ValueError:
                    value = default
            if name == "t":
                continue  # computed from h: "k h^alpha"
            L, M = corrlap.laplacian(V, F, method=method, face_normals=fn, h=H, **{keyword: value})
            assert_same_csc(L, plain_L)
            assert_same_csc(M, plain_M)


def test_out_of_range_parameter_names_it(sphere):
    V, F, fn = sphere
    with pytest.raises(ValueError, match=r"polydec: lambda = -1: expected >= 0"):
        corrlap.laplacian(V, F, method="polydec", lam=-1.0)


def test_laplacian_sign_convention_and_positive(sphere):
    V, F, fn = sphere
    L, M = corrlap.laplacian(V, F, method="fem", face_normals=fn)
    assert L.shape == M.shape == (len(V), len(V))
    assert np.abs(L @ np.ones(len(V))).max() < 1e-12
    u = np.random.default_rng(1).standard_normal(len(V))
    assert u @ (L @ u) < 0
    P, _ = corrlap.laplacian(V, F, method="fem", face_normals=fn, positive=True)
    assert np.array_equal(P.toarray(), -L.toarray())


def test_vertex_normals_default_to_the_normalized_sum_of_face_normals(sphere):
    V, F, fn = sphere
    vn = corrlap.true_normals("sphere1", V, F, at="vertices")
    assert vn.shape == (len(V), 3)
    a, _ = corrlap.laplacian(V, F, method="interpolated", face_normals=fn)
    b, _ = corrlap.laplacian(V, F, method="interpolated", vertex_normals=vn)
    assert_same_csc(a, b)


def test_inputs_of_any_numeric_dtype_and_order_give_the_same_operators(sphere):
    V, F, fn = sphere
    ref, _ = corrlap.laplacian(V, F, method="fem", face_normals=fn)
    L, _ = corrlap.laplacian(np.asfortranarray(V), F.astype(np.int32), method="fem", face_normals=np.asfortranarray(fn))
    assert_same_csc(ref, L)
    L, _ = corrlap.laplacian(V.tolist(), F.astype(np.uint32).tolist(), method="fem", face_normals=fn.tolist())
    assert_same_csc(ref, L)
    # float32 normals are rounded: normalize=True makes them unit again, and the operator close.
    L, _ = corrlap.laplacian(V, F, method="fem", face_normals=fn.astype(np.float32), normalize=True)
    assert abs(L - ref).max() < 1e-5 * abs(ref).max()


@needs_cli
def test_eigs_equals_cli_eigs(sphere, tmp_path):
    V, F, fn = sphere
    L, M = corrlap.laplacian(V, F, method="fem", face_normals=fn)
    # Both paths of the default eigen solver: the dense one (chosen at this size) and Lanczos.
    for extra in ([], ["dense_threshold=0"]):
        out = tmp_path / f"eigs{len(extra)}.txt"
        opts = [a for e in extra for a in ("--solver-option", e)]
        run_cli("eigs", "--method", "fem", *SHAPE, "--normals", "true", "-k", 20, "--solver", "cholmod", *opts,
                "--out", out)
        expected = np.loadtxt(out)
        kw = dict(e.split("=") for e in extra)
        kw = {k: float(v) for k, v in kw.items()}
        vals, vecs = corrlap.eigs(L, M, k=20, solver="cholmod", positions=V, positive=True, **kw)
        # The same operators (bitwise, above), solver and ordering hint (V, as the CLI passes); the
        # tolerance only allows for OpenBLAS's thread-count-dependent sums inside CHOLMOD: 1e-12 of
        # the largest value, 100 times below the Lanczos tolerance (1e-10).
        assert vals.shape == (20,) and vecs.shape == (len(V), 20)
        assert np.allclose(vals, expected, rtol=0, atol=1e-12 * expected.max())
        neg, _ = corrlap.eigs(L, M, k=20, solver="cholmod", positions=V, **kw)
        assert np.array_equal(neg, -vals) or np.allclose(neg, -vals, rtol=0, atol=1e-12 * expected.max())
    # The sign convention: lambda <= 0, the first one 0 on a closed surface; M-orthonormal vectors.
    vals, vecs = corrlap.eigs(L, M, k=10)
    assert vals[0] == pytest.approx(0, abs=1e-8) and np.all(vals <= 1e-8)
    assert np.allclose(vecs.T @ (M @ vecs), np.eye(10), atol=1e-8)


def test_solve_with_every_linear_backend(sphere):
    V, F, fn = sphere
    L, M = corrlap.laplacian(V, F, method="fem", face_normals=fn)
    A = (M - 0.01 * L).tocsr()  # SPD: L is negative semi-definite; given as CSR to test the conversion
    b = np.random.default_rng(2).standard_normal((len(V), 2))
    linear, _ = corrlap.backends()
    assert {"cholmod", "eigen-ldlt", "eigen-llt", "cg"} <= set(linear)
    for name in linear:
        x = corrlap.solve(A, b, solver=name)
        assert x.shape == b.shape
        assert np.linalg.norm(A @ x - b) <= 1e-8 * np.linalg.norm(b), name
        x0 = corrlap.solve(A, b[:, 0], solver=name, positions=V)
        assert x0.shape == (len(V),)
        assert np.linalg.norm(A @ x0 - b[:, 0]) <= 1e-8 * np.linalg.norm(b[:, 0]), name
    x = corrlap.solve(A.toarray(), b, solver="cg", preconditioner="ichol", tolerance=1e-12)
    assert np.linalg.norm(A @ x - b) <= 1e-10 * np.linalg.norm(b)


# ---- error paths: ValueError / RuntimeError naming the argument, or with the C++ message ----

@pytest.mark.parametrize("bad,match", [
    (lambda V: V.astype(np.complex128), "V: dtype complex128 is not supported"),
    (lambda V: V.astype(object), "V: dtype object is not supported"),
    (lambda V: V[:, :2], r"V: expected shape \(n, 3\)"),
    (lambda V: V.ravel(), r"V: expected shape \(n, 3\)"),
    (lambda V: np.where(np.arange(len(V))[:, None] == 7, np.nan, V), "V: row 7 is not finite"),
])
def test_bad_positions_raise_value_error(sphere, bad, match):
    V, F, fn = sphere
    with pytest.raises(ValueError, match=match):
        corrlap.laplacian(bad(V), F, method="fem", face_normals=fn)


def test_bad_faces_and_normals_raise_value_error(sphere):
    V, F, fn = sphere
    F2 = F.copy()
    F2[3, 2] = len(V)
    with pytest.raises(ValueError, match=rf"F: face 3 has vertex id {len(V)}, out of range \[0, {len(V)}\)"):
        corrlap.laplacian(V, F2, method="fem", face_normals=fn)
    F2[3, 2] = -1
    with pytest.raises(ValueError, match="F: face 3 has vertex id -1"):
        corrlap.laplacian(V, F2, method="fem", face_normals=fn)
    with pytest.raises(ValueError, match="F: vertex ids must be integers"):
        corrlap.laplacian(V, F.astype(float), method="fem", face_normals=fn)
    with pytest.raises(ValueError, match=r"F: expected shape \(m, 4\)"):
        corrlap.laplacian(V, F[:, :3], method="fem", face_normals=fn)
    with pytest.raises(ValueError, match=f"face_normals: expected {len(F)} rows"):
        corrlap.laplacian(V, F, method="fem", face_normals=fn[:-1])
    fn2 = fn.copy()
    fn2[5, 0] = np.nan
    with pytest.raises(ValueError, match="face_normals: row 5 is not finite"):
        corrlap.laplacian(V, F, method="fem", face_normals=fn2)
    # The library's resolve_normals reports it (before: the discretization's own "fem needs one
    # normal per face"), in library terms, as for every front end.
    with pytest.raises(ValueError, match="laplacian needs face normals: give face_normals"):
        corrlap.laplacian(V, F, method="fem")


@needs_cli
def test_bad_method_and_option_keep_the_cli_message(sphere, tmp_path):
    V, F, fn = sphere
    with pytest.raises(ValueError) as e:
        corrlap.laplacian(V, F, method="nope", face_normals=fn)
    assert "nope" in str(e.value) and "cotan" in str(e.value)
    assert str(e.value) in run_cli("operators", "--method", "nope", *SHAPE, "--out", tmp_path, check=False).stderr
    with pytest.raises(ValueError) as e:
        corrlap.laplacian(V, F, method="fem", face_normals=fn, bogus=1)
    assert "bogus" in str(e.value)
    assert str(e.value) in run_cli("operators", "--method", "fem", *SHAPE, "--param", "bogus=1", "--out", tmp_path,
                                   check=False).stderr
    L, M = corrlap.laplacian(V, F, method="fem", face_normals=fn)
    with pytest.raises(ValueError) as e:
        corrlap.solve(M - L, np.ones(len(V)), solver="cholmod", bogus=1)
    assert "bogus" in str(e.value) and "ordering" in str(e.value)
    cli = run_cli("eigs", "--method", "fem", *SHAPE, "--solver", "cholmod", "--solver-option", "bogus=1", check=False)
    with pytest.raises(ValueError) as e:
        corrlap.eigs(L, M, k=5, solver="cholmod", bogus=1)
    assert "bogus" in str(e.value) and str(e.value) in cli.stderr
    with pytest.raises(ValueError, match="nope"):
        corrlap.solve(M - L, np.ones(len(V)), solver="nope")
    with pytest.raises(ValueError, match="option 'ordering' has type"):
        corrlap.solve(M - L, np.ones(len(V)), solver="cholmod", ordering=[1])
    # None is "not given": the default, as everywhere in the module.
    b = np.ones(len(V))
    assert np.array_equal(corrlap.solve(M - L, b, ordering=None), corrlap.solve(M - L, b))


def test_solver_failure_raises_runtime_error(sphere):
    V, F, fn = sphere
    L, M = corrlap.laplacian(V, F, method="fem", face_normals=fn)
    for name in ("cholmod", "eigen-llt"):
        with pytest.raises(RuntimeError, match="positive definite"):
            corrlap.solve(L - M, np.ones(len(V)), solver=name)  # negative definite


def test_bad_sparse_and_right_hand_side(sphere):
    V, F, fn = sphere
    L, M = corrlap.laplacian(V, F, method="fem", face_normals=fn)
    with pytest.raises(ValueError, match="b: expected"):
        corrlap.solve(M, np.ones(len(V) + 1))
    with pytest.raises(ValueError, match="b: a value is not finite"):
        corrlap.solve(M, np.full(len(V), np.nan))
    with pytest.raises(ValueError, match="A: dtype complex128"):
        corrlap.solve(M.astype(np.complex128), np.ones(len(V)))
    with pytest.raises(ValueError, match="A: expected a square matrix"):
        corrlap.solve(M[:, :-1], np.ones(len(V)))


# ---- the other functions against the CLI ----

@needs_cli
def test_digitize_and_read_mesh_equal_cli_digitize(sphere, tmp_path):
    V, F, _ = sphere
    assert V.dtype == np.float64 and V.shape[1] == 3 and F.dtype == np.int64 and F.shape[1] == 4
    run_cli("digitize", *SHAPE, "--out", tmp_path / "s.obj")
    V2, F2 = corrlap.read_mesh(tmp_path / "s.obj")  # OBJ positions have 17 digits: exact
    assert np.array_equal(V, V2) and np.array_equal(F, F2)
    V3, F3 = corrlap.digitize("x^2+y^2+z^2-1", h=0.1, bbox=(-1.5, 1.5))
    run_cli("digitize", "--polynomial", "x^2+y^2+z^2-1", "--h", 0.1, "--bbox", -1.5, 1.5, "--out", tmp_path / "p.obj")
    V4, F4 = corrlap.read_mesh(tmp_path / "p.obj")
    assert np.array_equal(V3, V4) and np.array_equal(F3, F4)


def test_write_mesh_round_trip(sphere, tmp_path):
    V, F, fn = sphere
    H = np.linspace(0, 1, len(V))
    corrlap.write_mesh(tmp_path / "m.ply", V, F, vertex_scalars={"H": H}, face_normals=fn)
    V2, F2 = corrlap.read_mesh(tmp_path / "m.ply")
    assert np.array_equal(V, V2) and np.array_equal(F, F2)
    with pytest.raises(ValueError, match=r"vertex_scalars\['H'\]: expected"):
        corrlap.write_mesh(tmp_path / "m.ply", V, F, vertex_scalars={"H": H[:-1]})
    with pytest.raises(ValueError, match="missing.obj"):
        corrlap.read_mesh(tmp_path / "missing.obj")


@needs_cli
def test_digitize_volume_equals_cli_on_the_same_raw_volume(tmp_path):
    x, y, z = np.meshgrid(np.arange(20), np.arange(16), np.arange(12), indexing="ij")
    volume = (x - 9.5) ** 2 / 64 + (y - 7) ** 2 / 36 + (z - 6) ** 2 / 16 <= 1  # volume[x, y, z], not symmetric
    # A raw file has x fastest: the array indexed [z, y, x] in C order.
    (tmp_path / "v.raw").write_bytes((volume.transpose(2, 1, 0) * 255).astype(np.uint8).tobytes())
    # digitize_volume gives the computation's (world) coordinates; the CLI writes physical ones by default.
    run_cli("digitize", "--volume", tmp_path / "v.raw", "--raw-dimensions", 20, 16, 12, "--output-units", "world",
            "--out", tmp_path / "v.obj")
    V, F = corrlap.digitize_volume(volume)
    V2, F2 = corrlap.read_mesh(tmp_path / "v.obj")
    assert np.array_equal(V, V2) and np.array_equal(F, F2)
    V3, F3 = corrlap.digitize_volume(volume.astype(np.float32) * 10, threshold=5)
    assert np.array_equal(V, V3) and np.array_equal(F, F3)
    run_cli("normals", "--volume", tmp_path / "v.raw", "--raw-dimensions", 20, 16, 12, "--normals", "ii",
            "--out", tmp_path / "n.txt")
    assert np.array_equal(corrlap.ii_normals(volume, V, F), np.loadtxt(tmp_path / "n.txt"))
    with pytest.raises(ValueError, match="volume: expected a 3D array"):
        corrlap.digitize_volume(volume[0])
    with pytest.raises(ValueError, match="empty volume"):
        corrlap.digitize_volume(np.zeros((4, 4, 4), bool))


@needs_cli
def test_ii_normals_thin_parts_as_the_cli(tmp_path):
    # A rod 1.5 voxels in radius along x: the 4-voxel balls see across it (docs/math.md 7.2).
    x, y, z = np.meshgrid(np.arange(40), np.arange(12), np.arange(12), indexing="ij")
    volume = (y - 5.5) ** 2 + (z - 5.7) ** 2 <= 1.5 ** 2
    volume[:4] = volume[36:] = False
    (tmp_path / "v.raw").write_bytes((volume.transpose(2, 1, 0) * 255).astype(np.uint8).tobytes())
    V, F = corrlap.digitize_volume(volume)
    default = corrlap.ii_normals(volume, V, F)
    for thin_parts in ("shrink", "keep"):
        run_cli("normals", "--volume", tmp_path / "v.raw", "--raw-dimensions", 40, 12, 12, "--normals", "ii",
                "--ii-thin-parts", thin_parts, "--out", tmp_path / f"{thin_parts}.txt")
        n = corrlap.ii_normals(volume, V, F, thin_parts=thin_parts)
        assert np.array_equal(n, np.loadtxt(tmp_path / f"{thin_parts}.txt"))
        assert np.array_equal(n, default) == (thin_parts == "shrink")  # the volume's default shrinks
    with pytest.raises(ValueError, match="thin_parts: 'smaller'"):
        corrlap.ii_normals(volume, V, F, thin_parts="smaller")
    with pytest.raises(TypeError, match="thin_parts"):
        corrlap.ii_normals(volume, V, F, thin_parts=True)
    # regularize_volume's normals take the same choice: its default shrinks.
    P, _ = corrlap.regularize_volume(volume)
    P2, _ = corrlap.regularize_volume(volume, thin_parts="shrink")
    assert np.array_equal(P, P2)
    P3, _ = corrlap.regularize_volume(volume, thin_parts="keep")
    assert np.abs(P - P3).max() > 0.1  # the kept radius's normals point across the rod
    with pytest.raises(ValueError, match="thin_parts: 'no'"):
        corrlap.regularize_volume(volume, thin_parts="no")


@needs_cli
@pytest.mark.parametrize("estimator,at", [("true", "faces"), ("true", "vertices"), ("ii", "faces"),
                                          ("ii", "vertices")])
def test_normals_equal_cli_normals(sphere, tmp_path, estimator, at):
    V, F, _ = sphere
    run_cli("normals", *SHAPE, "--normals", estimator, "--at", at, "--out", tmp_path / "n.txt")
    if estimator == "true":
        n = corrlap.true_normals("sphere1", V, F, at=at)
    else:
        n = corrlap.ii_normals("sphere1", V, F, h=H, at=at)
    assert np.array_equal(n, np.loadtxt(tmp_path / "n.txt"))  # written with 17 digits


def test_ii_normals_refuse_another_surface(sphere):
    V, F, _ = sphere
    with pytest.raises(ValueError, match="not the surface of these voxels"):
        corrlap.ii_normals("sphere1", V, F, h=0.25)


@needs_cli
def test_curvature_equals_cli_curvature(sphere, tmp_path):
    V, F, fn = sphere
    run_cli("curvature", *SHAPE, "--normals", "true", "--radius", 0.5, "--out", tmp_path)
    for at in ("vertices", "faces"):
        H_, G, k1, k2, d1, d2 = corrlap.curvature(V, F, face_normals=fn, radius=0.5, at=at)
        for name, values in (("H", H_), ("G", G), ("k1", k1), ("k2", k2), ("d1", d1), ("d2", d2)):
            assert np.array_equal(values, np.loadtxt(tmp_path / f"{name}_{at}.txt")), (name, at)
    assert abs(np.mean(H_) - 1) < 0.1  # the unit sphere


@needs_cli
def test_regularize_equals_cli_regularize(sphere, tmp_path):
    V, F, fn = sphere
    run_cli("regularize", *SHAPE, "--normals", "true", "--out", tmp_path)
    P2, _ = corrlap.read_mesh(tmp_path / "regularized.ply")
    P = corrlap.regularize(V, F, face_normals=fn, h=H)
    assert P.shape == V.shape
    assert np.array_equal(P, P2)
    # closer to the sphere than the staircase
    assert np.abs(np.linalg.norm(P, axis=1) - 1).mean() < 0.5 * np.abs(np.linalg.norm(V, axis=1) - 1).mean()


def test_regularize_splits_touching_voxels_and_refuses_a_given_non_manifold_mesh():
    # Two one-voxel-thin 2 x 2 blocks that touch along one edge only: the digital surface gives each
    # block its own vertices along that edge (docs/math.md 1.4), so it is manifold and regularizes.
    volume = np.zeros((6, 6, 3), bool)
    volume[0:2, 0:2, 1] = True
    volume[2:4, 2:4, 1] = True
    V, F = corrlap.digitize_volume(volume)
    assert len(F) == 2 * 16 and len(V) == 2 * 18
    # Surfel normals (quads counter-clockwise seen from outside).
    fn = np.cross(V[F[:, 2]] - V[F[:, 0]], V[F[:, 3]] - V[F[:, 1]])
    fn /= np.linalg.norm(fn, axis=1)[:, None]
    P = corrlap.regularize(V, F, face_normals=fn)
    assert P.shape == V.shape and np.isfinite(P).all() and not np.array_equal(P, V)
    # The keyword is still accepted and changes nothing.
    assert np.array_equal(corrlap.regularize(V, F, face_normals=fn, allow_nonmanifold=True), P)
    # The same quads with the vertices merged by position: a mesh given as it is, refused.
    _, first, inverse = np.unique(V, axis=0, return_index=True, return_inverse=True)
    F_merged = first[inverse.reshape(-1)][F]
    with pytest.raises(ValueError, match=r"not manifold \(1 non-manifold edges"):
        corrlap.regularize(V, F_merged, face_normals=fn)
    with pytest.raises(ValueError, match="the surface is open"):
        corrlap.regularize(V, F[: len(F) // 2], face_normals=fn[: len(F) // 2])


@needs_cli
def test_python_equals_cli_on_the_front_end_input(tmp_path):
    """The input of tests/pipeline/test_front_ends_agree.cpp (sphere1, h = 0.1, box -1.5 1.5, II
    normals with alpha = 1/3, fem), where the study's surface, normals and operators equal the
    CLI's: Python's equal them too, bit for bit."""
    h, alpha = 0.1, 1.0 / 3.0
    cli_input = ["--shape", "sphere1", "--h", h, "--bbox", -1.5, 1.5]
    ii = ["--normals", "ii", "--ii-radius", 3, "--ii-alpha", repr(alpha)]
    run_cli("digitize", *cli_input, "--out", tmp_path / "mesh.obj")
    run_cli("normals", *cli_input, *ii, "--out", tmp_path / "fn.txt")
    run_cli("normals", *cli_input, *ii, "--at", "vertices", "--out", tmp_path / "vn.txt")
    run_cli("operators", "--method", "fem", *cli_input, *ii, "--out", tmp_path / "ops")
    V, F = corrlap.digitize("sphere1", h=h, bbox=(-1.5, 1.5))
    V2, F2 = corrlap.read_mesh(tmp_path / "mesh.obj")
    assert np.array_equal(V, V2) and np.array_equal(F, F2)
    fn = corrlap.ii_normals("sphere1", V, F, h=h, alpha=alpha, k=3.0, bbox=(-1.5, 1.5))
    vn = corrlap.ii_normals("sphere1", V, F, h=h, alpha=alpha, k=3.0, bbox=(-1.5, 1.5), at="vertices")
    assert np.array_equal(fn, np.loadtxt(tmp_path / "fn.txt"))
    assert np.array_equal(vn, np.loadtxt(tmp_path / "vn.txt"))
    L, M = corrlap.laplacian(V, F, method="fem", face_normals=fn, h=h)
    assert_same_csc(L, scipy.io.mmread(str(tmp_path / "ops" / "L.mtx")))
    assert_same_csc(M, scipy.io.mmread(str(tmp_path / "ops" / "M.mtx")))


# ---- threads and the GIL ----

def test_set_threads_keeps_results_bitwise(sphere):
    V, F, fn = sphere
    before = corrlap.get_threads()
    try:
        corrlap.set_threads(1)
        assert corrlap.get_threads() == 1
        one, _ = corrlap.laplacian(V, F, method="interpolated", face_normals=fn)
        corrlap.set_threads(2)
        assert corrlap.get_threads() == 2
        two, _ = corrlap.laplacian(V, F, method="interpolated", face_normals=fn)
        assert_same_csc(one, two)
    finally:
        corrlap.set_threads(before)


def test_concurrent_calls_release_the_gil_and_agree():
    V, F = corrlap.digitize("sphere1", h=0.04, bbox=(-1.5, 1.5))
    fn = corrlap.true_normals("sphere1", V, F)
    ref, _ = corrlap.laplacian(V, F, method="interpolated", face_normals=fn)
    results = [None, None]

    def work(i):
        results[i], _ = corrlap.laplacian(V, F, method="interpolated", face_normals=fn)

    threads = [threading.Thread(target=work, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for r in results:
        assert_same_csc(ref, r)

    # While one thread is inside a long C++ call, this one keeps running: the longest pause of its
    # loop stays far below the duration of any one call (it would span a call with the GIL held).
    # The worker repeats the call until enough time has passed, so that a fast machine still gives
    # calls long enough to tell a released GIL from scheduling jitter.
    done = threading.Event()
    spans = []

    def long_calls():
        start = time.perf_counter()
        while time.perf_counter() - start < 0.6:
            t0 = time.perf_counter()
            corrlap.ii_normals("sphere1", V, F, h=0.04, bbox=(-1.5, 1.5), k=6)
            spans.append(time.perf_counter() - t0)
        done.set()

    worker = threading.Thread(target=long_calls)
    last, longest = time.perf_counter(), 0.0
    worker.start()
    while not done.is_set():
        now = time.perf_counter()
        longest, last = max(longest, now - last), now
    worker.join()
    assert min(spans) > 0.05, "the calls are too short to tell"
    assert longest < 0.5 * min(spans)


def test_docstrings_state_shapes_and_the_sign():
    for name in corrlap.__all__:
        assert getattr(corrlap, name).__doc__, name
    for name in ("laplacian", "eigs"):
        doc = getattr(corrlap, name).__doc__
        assert "#V by #V" in doc and "negative semi-definite" in doc and "positive=True" in doc
