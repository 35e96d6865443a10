"""corrlap: corrected Laplace-Beltrami operators on digital surfaces, from numpy and scipy.

    import corrlap
    V, F = corrlap.digitize("sphere1", h=0.1, bbox=(-1.5, 1.5))   # V (n, 3) float64, F (m, 4) int64
    fn = corrlap.true_normals("sphere1", V, F)                      # (m, 3) unit normals per face
    L, M = corrlap.laplacian(V, F, method="fem", face_normals=fn)   # scipy.sparse.csc_matrix, #V by #V
    vals, vecs = corrlap.eigs(L, M, k=10)

Sign convention (the C++ library's, docs/math.md section 0): L is NEGATIVE semi-definite, L 1 = 0,
u^T L u <= 0, M^-1 L approximates the Laplace-Beltrami operator, and the eigenvalues of
L u = lambda M u are <= 0 (-lambda ~ l(l+1) on the unit sphere). ``positive=True`` on laplacian and
eigs gives -L and -lambda instead, the convention of robust_laplacian and gpytoolbox.

Arrays in may be any numpy array-like of int32/int64/float32/float64 in C or Fortran order; a wrong
dtype or shape, a NaN or an out-of-range face index raises ValueError naming the argument. None is
the only way to ask for a default; a value outside its parameter's domain (h=0, h=nan, k=0) raises
ValueError and a value of the wrong type (k=5.5, h="x", h=True) TypeError, both naming the
parameter. The C++ library's errors keep their message: bad input (including unreadable files)
raises ValueError, a failed solve RuntimeError. Allocations sized by the input are checked against
the memory budget (set_max_memory) first. The long calls release the GIL, and use the threads of
set_threads(n).
"""

import numbers as _numbers
import operator as _operator

import numpy as _np
import scipy.sparse as _sparse

from . import _core

__all__ = [
    "digitize", "digitize_volume", "read_volume", "write_volume", "regularize_volume", "read_mesh", "write_mesh", "true_normals", "ii_normals", "curvature",
    "laplacian", "solve", "eigs", "regularize", "set_threads", "get_threads", "set_max_memory", "get_max_memory",
    "methods", "backends", "view", "ViewPage",
]

def _csc(parts):
    data, indices, indptr, shape = parts
    # The arrays view the C++ matrix's storage (no copy); scipy keeps them as they are.
    return _sparse.csc_matrix((data, indices, indptr), shape=shape, copy=False)


def _sparse_parts(A, name):
    """(data, indices, indptr, rows, cols) of A as a canonical float64 CSC matrix."""
    if not _sparse.issparse(A):
        A = _np.asarray(A)
        if A.dtype.kind not in "iuf" or A.ndim != 2:
            raise ValueError(f"{name}: expected a scipy sparse matrix or a 2D real array, got "
                             f"{A.ndim}D dtype {A.dtype}")
    if A.dtype.kind not in "iuf":
        raise ValueError(f"{name}: dtype {A.dtype} is not supported (expected a real matrix)")
    A = _sparse.csc_matrix(A, dtype=_np.float64)
    if not A.has_canonical_format:
        A = A.copy()
        A.sum_duplicates()  # also sorts the row indices
    return A.data, A.indices, A.indptr, A.shape[0], A.shape[1]


def _warn(messages):
    import warnings
    for m in messages:
        warnings.warn(m, RuntimeWarning, stacklevel=3)


def _thin_parts(value):
    """thin_parts as a string or None; its value is the library's to check (ValueError)."""
    if value is None or isinstance(value, str):
        return value
    raise TypeError(f"thin_parts: expected 'shrink', 'keep' or None, got {type(value).__name__} {value!r}")


def _progress(progress):
    """The progress keyword for _core: None, a callable, or True for lines on stderr."""
    if progress is True:
        import sys
        return lambda line: print(line, file=sys.stderr, flush=True)
    if progress is False:
        return None
    return progress


def _real(value, name, required=False):
    """A real argument as a float, None (the default) as None. Its range is the library's to check
    (ValueError naming the parameter); here only the type: a bool, a string or a complex number is
    a TypeError naming it, never silently a number."""
    if value is None:
        if required:
            raise TypeError(f"{name}: a number is required, got None")
        return None
    if isinstance(value, (bool, _np.bool_)) or not isinstance(value, _numbers.Real):
        raise TypeError(f"{name}: expected a real number, got {type(value).__name__} {value!r}")
    return float(value)


def _alpha0(value):
    """None for 'auto' (the library's automatic choice), else the number."""
    if isinstance(value, str) and value == "auto":
        return None
    return _real(value, "alpha0", required=True)


def _integer(value, name):
    """An integer argument: an int or a numpy integer (never a float such as 5.5, never a bool),
    within the library's int range."""
    if isinstance(value, (bool, _np.bool_)):
        raise TypeError(f"{name}: expected an integer, got bool {value!r}")
    try:
        i = _operator.index(value)
    except TypeError:
        raise TypeError(f"{name}: expected an integer, got {type(value).__name__} {value!r}") from None
    if not -2**31 <= i < 2**31:
        raise ValueError(f"{name}: {i} is out of range (|{name}| < 2^31)")
    return i


def _bbox(bbox):
    lo, hi = bbox
    return _real(lo, "bbox", required=True), _real(hi, "bbox", required=True)


def digitize(shape, h, bbox=(-10.0, 10.0), offset=5, center=(0.0, 0.0, 0.0)):
    """Digital surface of an implicit shape {P <= 0} (Gauss digitization, docs/math.md 1.2-1.4).

    shape   name of a built-in shape (sphere1, sphere9, ellipsoid, cylinder, torus, rcube, goursat,
            goursat-hole, distel, leopold, diabolo, heart, crixxi) or a polynomial in x, y, z
            such as "x^2+y^2+z^2-1"
    h       grid step (world units per voxel)
    bbox    (min, max) of the digitization box on every axis (reference default (-10, 10))
    offset  extra voxels around the box (default 5)
    center  (3,) translation of the shape

    Returns V (#V, 3) float64 vertex positions and F (#F, 4) int64 quads, counter-clockwise seen
    from outside, numbered as the reference implementation and `corrlap digitize` number them.
    """
    lo, hi = _bbox(bbox)
    return _core.digitize(str(shape), _real(h, "h", required=True), lo, hi, _integer(offset, "offset"),
                          _np.reshape(center, (1, 3)))


def digitize_volume(volume, h=None, threshold=0.0):
    """Digital surface of the voxels of a 3D array: voxel (x, y, z) is volume[x, y, z], inside when
    its value is > threshold (bool arrays: True), centred at the origin as `corrlap digitize --volume`
    centres a volume file.

    volume     (nx, ny, nz) array of bool, int8 ... int64, uint8 ... uint64, float32 or float64, read
               where it is, in its own dtype and strides (C or Fortran order, views, broadcasts):
               no converted copy is made, and the voxel grid (one bit per voxel) is checked
               against the memory budget before it is allocated
    h          grid step > 0; None: 2 / max(nx, ny, nz), so that the longest side spans 2 (the CLI's default)
    threshold  inside iff value > threshold (finite; bool arrays: True is 1)

    Returns V (#V, 3) float64 and F (#F, 4) int64 quads. A NaN value, or no voxel inside, raises
    ValueError naming it.
    """
    return _core.digitize_volume(volume, _real(h, "h"), _real(threshold, "threshold", required=True))


def read_volume(path, space=None, return_space=False):
    """Reads a volume file (every format of docs/io.md) as it is. Returns (array, affine): array is
    indexed [i, j, k] in the file's own dtype (bool, int8 ... uint64, float32, float64; Fortran
    order, i fastest, as the file stores it), affine the 4 by 4 map from (i, j, k, 1) to physical
    coordinates (millimetres for NIfTI, NRRD, MetaImage; the identity for files without geometry).

    The affine is in the file's own anatomical space: RAS for NIfTI (nibabel's affine), LPS for
    MetaImage (ITK's), the 'space' an NRRD names (LPS for 3D Slicer's .seg.nrrd). space='RAS' or
    'LPS' converts it (x and y flipped between the two; ValueError for a file that names no space).
    return_space=True returns (array, affine, space_name) with the space of that affine: 'RAS',
    'LPS', 'LAS' or None (unknown). An unreadable file raises ValueError naming it."""
    array, affine, name = _core.read_volume(str(path), "" if space is None else str(space))
    return (array, affine, name) if return_space else (array, affine)


def write_volume(path, array, affine=None, space=None):
    """Writes a 3D array indexed [i, j, k] as a volume file chosen by extension (docs/io.md), in
    its own dtype where the format has it, with the 4 by 4 affine (index -> physical; None: the
    identity) where the format has a geometry. space: the anatomical space of the affine ('RAS',
    'LPS', 'LAS'; None: unknown). A known space is converted into the format's (NIfTI: RAS,
    MetaImage: LPS) and named in an NRRD; an unknown one is written as it is."""
    a = _np.asarray(array)
    if a.ndim != 3:
        raise ValueError(f"array: expected a 3D array, got {a.ndim} dimensions")
    # The C++ side takes the bytes as they are: native byte order, i fastest.
    a = _np.asfortranarray(a.astype(a.dtype.newbyteorder("="), copy=False))
    _core.write_volume(str(path), a, None if affine is None else _np.asarray(affine, dtype=_np.float64),
                       "" if space is None else str(space))


def regularize_volume(volume, label=None, threshold=None, affine=None, h=None, method="fem", alpha0="auto",
                      curvature_radius=None, size=None, solver="cholmod", solver_options=None, solve_accuracy=None,
                      space=None, curvature_spacing=None, thin_parts=None, progress=None, **params):
    """The regularized surface of a volume, as `corrlap regularize --volume` computes it (II normals
    from the voxels, docs/regularization.md), in physical coordinates.

    volume     a volume file's path (its geometry is used) or a 3D array indexed [i, j, k] (as
               digitize_volume reads it)
    label      inside iff value == label; threshold: inside iff value > threshold; neither: every
               nonzero value is inside (give at most one)
    affine     arrays only: 4 by 4 map from (i, j, k, 1) to physical coordinates (read_volume's,
               nibabel's img.affine); None: voxel indices. Anisotropic voxels are resampled to
               cubes of the finest spacing first (docs/io.md)
    h, method, alpha0, curvature_radius, curvature_spacing, size, solver, solver_options, solve_accuracy, params:
               as regularize, in the normalized units of the computation (the longest side spans 2);
               the default curvature_radius is at least {voxel_min_curvature_radius} voxels, as for
               `corrlap regularize --volume`
    space      volume files only: None (the file's own physical space, as read_volume's affine), 'RAS'
               or 'LPS' (x and y flipped from the file's space, as `--output-space`; ValueError for a
               file that names no space, or with an array)
    thin_parts the II normals' balls where a part is thinner than them, as ii_normals (None: "shrink")
    progress   as regularize; here also the II normals by tenths ("ii normals: 40%")

    Returns V (#V, 3) in physical coordinates and F (#F, 4) int64 quads facing outwards.
    """
    if isinstance(volume, (str, bytes)) or hasattr(volume, "__fspath__"):
        import os
        volume = os.fsdecode(volume)
    V, F, warnings = _core.regularize_volume(
        volume, _real(label, "label"), _real(threshold, "threshold"),
        None if affine is None else _np.asarray(affine, dtype=_np.float64), _real(h, "h"), str(method), params,
        _alpha0(alpha0), _real(curvature_radius, "curvature_radius"),
        _real(curvature_spacing, "curvature_spacing"), _real(size, "size"),
        str(solver), dict(solver_options or {}), _real(solve_accuracy, "solve_accuracy"),
        "" if space is None else str(space), _thin_parts(thin_parts), _progress(progress))
    _warn(warnings)
    return V, F


def read_mesh(path):
    """Reads an .obj, .ply or .off mesh. Returns V (#V, 3) float64 and F (#F, d) int64 (d = 4 for
    quad meshes; every face must have the same number of corners d)."""
    return _core.read_mesh(str(path))


def write_mesh(path, V, F, vertex_scalars=None, face_scalars=None, vertex_normals=None, face_normals=None):
    """Writes a quad mesh V (#V, 3), F (#F, 4) as .obj (positions and faces) or binary .ply (with
    attributes): vertex_scalars {name: (#V,)}, face_scalars {name: (#F,)}, vertex_normals (#V, 3),
    face_normals (#F, 3)."""
    _core.write_mesh(str(path), V, F, dict(vertex_scalars or {}), dict(face_scalars or {}), vertex_normals,
                     face_normals)


def true_normals(shape, V, F, at="faces", center=(0.0, 0.0, 0.0)):
    """True normals of an implicit shape (docs/math.md 1.5): exact radial normals on spheres, else
    the gradient at the projection onto {P = 0}.

    shape  as in digitize; V (#V, 3), F (#F, 4)
    at     "faces": one normal per face at its centroid, (#F, 3); "vertices": the normalized sum of
           the incident face normals, (#V, 3) (what `--normals true` gives every CLI command)
    """
    return _core.true_normals(str(shape), V, F, at, _np.reshape(center, (1, 3)))


def ii_normals(volume_or_shape, V, F, h=None, alpha=None, k=None, at="faces", bbox=(-10.0, 10.0), offset=5,
               center=(0.0, 0.0, 0.0), threshold=0.0, thin_parts=None):
    """Integral-invariant normals (docs/math.md 7): covariance of the voxels in a ball of radius
    k h^alpha around each surfel.

    volume_or_shape  a shape name or polynomial (digitized again with h, bbox, offset, center) or
                     a 3D array (digitized as digitize_volume with h, threshold); V, F must be the
                     surface digitize / digitize_volume returned for it
    h                grid step (required for shapes; volumes: None means 2 / longest side)
    alpha, k         radius exponent and factor, the CLI's defaults: for a shape the paper's 0.33 and 3
                     (the paper says 1/3); for a volume 1 and {voxel_ii_radius}, a radius of {voxel_ii_radius}
                     voxels (docs/regularization.md, "Default radii")
    at               "faces": (#F, 3); "vertices": normalized sums of face normals, (#V, 3)
    thin_parts       "shrink": estimate again with smaller balls where the ball sees across a part
                     thinner than itself (docs/math.md 7.2); "keep": the radius everywhere; None:
                     the CLI's default, "shrink" for a volume and "keep" for a shape (`--ii-thin-parts`)
    """
    if isinstance(volume_or_shape, str):
        if h is None:
            raise ValueError("h: required with a shape")
        lo, hi = _bbox(bbox)
        return _core.ii_normals_shape(volume_or_shape, V, F, _real(h, "h"), lo, hi, _integer(offset, "offset"),
                                      _np.reshape(center, (1, 3)), _real(k, "k"), _real(alpha, "alpha"), str(at),
                                      _thin_parts(thin_parts))
    return _core.ii_normals_volume(volume_or_shape, V, F, _real(h, "h"), _real(threshold, "threshold", required=True),
                                   _real(k, "k"), _real(alpha, "alpha"), str(at), _thin_parts(thin_parts))


def curvature(V, F, face_normals=None, vertex_normals=None, radius=None, at="vertices", constant=False):
    """Corrected curvature measures (docs/math.md 8) in balls of the given radius (None: the
    default of `corrlap curvature --mesh`, {curvature_radius_fraction} s with s half the longest side of
    the bounding box).

    V (#V, 3), F (#F, 4); face_normals (#F, 3) and/or vertex_normals (#V, 3). By default the normals
    are interpolated from the vertex normals (the normalized sum of the face normals when only
    those are given), as `corrlap curvature --normals ...`; constant=True uses the face normals as
    constant per face.
    at  "vertices" (balls at vertices, arrays of #V rows) or "faces" (at face centroids, #F rows)

    Returns H, G, k1, k2 (n,) mean, Gaussian and principal curvatures (k1 <= k2; the unit sphere
    has H = 1) and d1, d2 (n, 3) their unit principal directions.
    """
    return _core.curvature(V, F, face_normals, vertex_normals, _real(radius, "radius"), str(at),
                           bool(constant))


def laplacian(V, F, method="fem", face_normals=None, vertex_normals=None, h=None, positive=False, **params):
    """Stiffness L and mass M of a discretization of the registry (docs/discretizations.md).

    V (#V, 3) positions, F (#F, 4) quads (a digital surface, e.g. from digitize).
    method          fem (face normals), interpolated (vertex normals), polydec, projected-polydec
                    (face), vrm, corrected-vrm (vertex), heat-kernel (face), cotan; see methods()
    face_normals    (#F, 3) unit normals, for methods on face normals
    vertex_normals  (#V, 3), for methods on vertex normals; default: the normalized sum of the face
                    normals (as every CLI command makes them)
    h               grid step of the surface (heat-kernel's default t and lattice); None: unknown,
                    the mean edge length is used, as for a mesh read from a file. Give the h of
                    digitize to get what `corrlap operators --shape ... --h` gives.
    positive        positive=True returns -L (positive semi-definite), the convention of
                    robust_laplacian and gpytoolbox
    **params        the method's parameters as keywords, the same names as `corrlap operators`'
                    flags (`lam` for lambda, a Python keyword); an unknown key or a value out of
                    range raises ValueError naming it. The parameters of every method:
{parameters}
    Returns L, M as scipy.sparse.csc_matrix, #V by #V (the heat-kernel's default variant: #F by #F,
    on surfel centres). L is negative semi-definite: L 1 = 0, u^T L u <= 0, M^-1 L approximates
    the Laplace-Beltrami operator, eigenvalues of L u = lambda M u are <= 0. M is symmetric
    positive definite for consistent normals. Bitwise what `corrlap operators` writes for the same
    surface, normals and parameters.
    """
    params = {_PARAMETER_OF_KEYWORD.get(k, k): v for k, v in params.items()}
    Lp, Mp, _domain, warnings = _core.laplacian(V, F, str(method), face_normals, vertex_normals, _real(h, "h"),
                                                params)
    _warn(warnings)
    L = _csc(Lp)
    if positive:
        L.data *= -1.0  # exact, in place: L's arrays are fresh
    return L, _csc(Mp)


# The method parameters as keywords, derived from the C++ declarations (one place): a parameter
# whose name is a Python keyword (lambda) is spelt with the short form below.
_PARAMETER_OF_KEYWORD = {"lam": "lambda"}


def _method_keyword(name):
    import keyword
    for k, v in _PARAMETER_OF_KEYWORD.items():
        if v == name:
            return k
    return name if not keyword.iskeyword(name) else name + "_"


def _document_laplacian():
    import inspect
    uses = {}  # keyword -> [(method, default, description)]
    for method, (_normals, params) in _core.methods().items():
        for name, default, description in params:
            uses.setdefault(_method_keyword(name), []).append((method, default, description))
    lines = []
    for kw, items in uses.items():
        methods = ", ".join(m for m, _d, _t in items)
        lines.append(f"                    {kw}: {items[0][2]}")
        defaults = sorted({f"{m}={d}" for m, d, _t in items})
        lines.append(f"                        ({methods}; defaults: {', '.join(defaults)})")
    laplacian.__doc__ = laplacian.__doc__.replace("{parameters}", "\n".join(lines))
    signature = inspect.signature(laplacian)
    fixed = [p for p in signature.parameters.values() if p.kind != inspect.Parameter.VAR_KEYWORD]
    keywords = [inspect.Parameter(kw, inspect.Parameter.KEYWORD_ONLY, default=None) for kw in uses]
    laplacian.__signature__ = signature.replace(parameters=fixed + keywords)


def solve(A, b, solver="cholmod", positions=None, **options):
    """Solves A x = b for a symmetric positive (semi-)definite A with a linear solver backend.

    A          (n, n) scipy sparse matrix (any format) or dense array, e.g. M - dt L: laplacian's L
               is negative semi-definite, so M - dt L (dt > 0) is positive definite
    b          (n,) or (n, k) right-hand sides; x has the same shape
    solver     cholmod (default), eigen-ldlt, eigen-llt, cg; see backends()
    positions  (n, 3) points of the unknowns (e.g. V), the ordering hint of direct solvers
    options    the backend's options as keywords (`corrlap backends`), e.g. ordering="metis",
               preconditioner="ichol", tolerance=1e-12; an unknown key raises ValueError listing
               the valid ones, a failed solve RuntimeError with the backend's message.
    """
    data, indices, indptr, rows, cols = _sparse_parts(A, "A")
    return _core.solve(data, indices, indptr, rows, cols, b, str(solver), options, positions)


def eigs(L, M, k=49, solver=None, eigen_solver="shift-invert", positions=None, positive=False, **options):
    """The k eigenpairs of L u = lambda M u of smallest |lambda| (docs/math.md 10.5).

    L, M          #V by #V scipy sparse matrices from laplacian (L negative semi-definite, M SPD)
    k             number of pairs
    solver        linear solver of shift-invert (default cholmod), as `corrlap eigs --solver`
    eigen_solver  shift-invert (Spectra's Lanczos, default) or dense (small problems)
    positions     (#V, 3) points of the unknowns (the CLI passes V), the solver's ordering hint
    options       eigen and linear solver options as keywords (`corrlap backends`), e.g. tolerance
    positive      return -lambda >= 0 (the robust_laplacian/gpytoolbox convention)

    Returns vals (k,) and vecs (#V, k), M-orthonormal columns. Eigenvalues follow L's sign: L is
    negative semi-definite, so vals <= 0, from the one nearest 0 (vals[0] ~ 0 on a closed surface)
    to the most negative; with positive=True they are -lambda >= 0, ascending, the values
    `corrlap eigs` prints.
    """
    Lp = _sparse_parts(L, "L")
    Mp = _sparse_parts(M, "M")
    values, vectors, _method, _iterations = _core.eigs(Lp, Mp, _integer(k, "k"), solver or "", str(eigen_solver),
                                                       options, positions)
    return (values if positive else -values), vectors


def regularize(V, F, face_normals=None, vertex_normals=None, method="fem", h=None, alpha0="auto",
               curvature_radius=None, size=None, solver="cholmod", solver_options=None, solve_accuracy=None,
               return_curvature=False, allow_nonmanifold=False, curvature_spacing=None, progress=None, **params):
    """Regularized positions of a closed digital surface (paper 4.1, docs/regularization.md): the
    positions P minimizing the distance to V plus the corrected Dirichlet energy, with
    Delta p = -2 H n from the corrected mean curvature H.

    V (#V, 3), F (#F, 4); face_normals (#F, 3) and/or vertex_normals (#V, 3) (default: normalized
    sums of the face normals). method: a vertex-based discretization (its parameters as keywords).
    h: grid step (None: the mean edge length); alpha0: attachment alpha = alpha0 / (h size)^2, or
    'auto' (as `--alpha0 auto`: from {alpha0_start} up while the result keeps away from the input's
    local mean and a larger alpha0 brings it back; docs/regularization.md; the paper uses 10);
    curvature_radius, size: as `corrlap regularize --mesh` (defaults {curvature_radius_fraction} size and half the
    bounding box). curvature_spacing: the curvature ball is walked at vertices this fraction of the
    radius apart and interpolated between them (None: the library's {curvature_site_spacing}, as
    `--curvature-spacing`; 0: at every vertex; docs/math.md 8.4).
    solver, solver_options: the linear solver and its options. solve_accuracy: the iterative solve
    stops when the RMS error of the positions is provably below this many grid steps h (None: the
    library's {solve_accuracy}, as `--solve-accuracy`; 0: to rounding; docs/regularization.md).
    The surface must be closed and manifold (ValueError naming the counts otherwise). Surfaces from
    voxels (digitize_volume, digitize) always are: pointels where voxels touch along an edge or at a
    corner are split into one vertex per sheet (docs/math.md 1.4). A mesh from elsewhere is taken as
    it is. allow_nonmanifold: accepted and ignored (it let pinched digital surfaces through before
    they were split).
    progress: None, True (each line printed to stderr, as `corrlap regularize` prints them on large
    surfaces), or a callable taking one str, called before each long stage ("mean curvature in
    balls of radius ...", "solving with alpha0 = 10", each further trial of alpha0='auto'). Ctrl-C
    stops the computation at its next stage, with or without progress; an exception raised by the
    callable stops it too and is raised here.

    Returns P (#V, 3), and H (#V,) too when return_curvature.
    """
    P, H, warnings = _core.regularize(V, F, face_normals, vertex_normals, str(method), _real(h, "h"), params,
                                      _alpha0(alpha0), _real(curvature_radius, "curvature_radius"),
                                      _real(curvature_spacing, "curvature_spacing"), _real(size, "size"), str(solver),
                                      dict(solver_options or {}), _real(solve_accuracy, "solve_accuracy"),
                                      _progress(progress))
    _warn(warnings)
    return (P, H) if return_curvature else P


def set_threads(n):
    """Limits the worker threads of every later call (TBB and OpenBLAS) to n; n <= 0: all cores.
    Process-wide, the last call wins. Surfaces, normals, curvature and operators are bitwise the
    same for any thread count; solves and eigenpairs agree to rounding (OpenBLAS's sums depend on
    its thread count)."""
    _core.set_threads(_integer(n, "n"))


def get_threads():
    """The current thread limit (the hardware concurrency unless set_threads was called)."""
    return _core.get_threads()


def set_max_memory(size):
    """Sets the memory budget: every allocation whose size comes from the input (a volume's voxel
    grid, a surface, a file's counts) is checked against it before it is made, and an absurd one
    raises ValueError with the numbers instead of exhausting the machine. size: bytes (int) or a
    text such as "8G", "512M" (powers of 1024), as `corrlap --max-memory`; None: the default, the
    machine's memory (or CORRLAP_MAX_MEMORY when set at import). Process-wide."""
    if size is not None and not isinstance(size, str):
        size = str(_integer_bytes(size))
    _core.set_max_memory(size)


def get_max_memory():
    """The current memory budget in bytes (set_max_memory)."""
    return _core.get_max_memory()


def _integer_bytes(value):
    if isinstance(value, (bool, _np.bool_)):
        raise TypeError(f"size: expected bytes (an int) or a text such as '8G', got bool {value!r}")
    try:
        return _operator.index(value)
    except TypeError:
        raise TypeError(f"size: expected bytes (an int) or a text such as '8G', got {type(value).__name__} "
                        f"{value!r}") from None


class ViewPage:
    """The page corrlap.view made: ``path`` (None when not written), ``html`` (the page's text).
    Shown inline by Jupyter (an iframe holding the page)."""

    def __init__(self, html, path):
        self.html = html
        self.path = path

    def _repr_html_(self):
        import html as _html
        return (f'<iframe srcdoc="{_html.escape(self.html, quote=True)}" '
                'style="width: 100%; height: 600px; border: 1px solid #ccc"></iframe>')

    def __repr__(self):
        where = f" at {self.path}" if self.path else ""
        return f"<corrlap.ViewPage{where}, {len(self.html) >> 10} KB>"


def _view_surface(V, F, name, scalars, face_scalars, visible):
    V = _np.asarray(V)
    F = _np.asarray(F)
    vertex, face = {}, dict(face_scalars or {})
    for key, values in dict(scalars or {}).items():
        n = _np.shape(values)[0] if _np.ndim(values) == 1 else -1
        if n == V.shape[0] or V.ndim != 2:
            vertex[key] = values  # a vertex scalar when the length is ambiguous (#V == #F)
        elif F.ndim == 2 and n == F.shape[0]:
            face[key] = values
        else:
            raise ValueError(f"scalars['{key}']: expected {V.shape[0]} values (one per vertex) or "
                             f"{F.shape[0] if F.ndim == 2 else '?'} (one per face), got shape {_np.shape(values)}")
    return {"name": str(name), "V": V, "F": F, "vertex_scalars": vertex, "face_scalars": face,
            "visible": bool(visible)}


def view(V, F, scalars=None, path=None, name="surface", title=None, field="auto", face_scalars=None, others=(),
         layout=None):
    """An interactive page of the surface V (#V, 3), F (#F, d), 3 <= d <= 255 corners per face: one
    self-contained HTML file (no server, no network) to turn around, zoom and colour by a scalar in
    a browser, with the maps and ranges of the PNG pictures (docs/viewer.md).

    scalars       {name: (#V,) or (#F,) values}: per vertex or per face by their length (per vertex
                  when #V == #F; face_scalars then names the per-face ones)
    path          where to write the page (None: not written, only returned)
    field         the scalar shown first: a name, "auto" (H if present, else the first) or "none"
    others        more surfaces on the same page, each a dict with V, F and optionally name,
                  scalars, face_scalars, visible (e.g. the staircase beside the regularized surface)
    layout        "side" (side by side) or "overlay" (where they are); None: the library's, side

    Returns a ViewPage (.html, .path), which Jupyter shows inline.
    """
    surfaces = [_view_surface(V, F, name, scalars, face_scalars, True)]
    for i, o in enumerate(others):
        if not isinstance(o, dict) or "V" not in o or "F" not in o:
            raise ValueError(f"others[{i}]: expected a dict with V and F")
        surfaces.append(_view_surface(o["V"], o["F"], o.get("name", f"surface {i + 2}"), o.get("scalars"),
                                      o.get("face_scalars"), o.get("visible", True)))
    page = _core.view_page(surfaces, str(title) if title is not None else f"corrlap view: {name}", str(field),
                           layout)
    if path is not None:
        import os
        partial = str(path) + ".partial"
        with open(partial, "wb") as f:
            f.write(page)
        os.replace(partial, str(path))
    return ViewPage(page.decode("utf-8"), None if path is None else str(path))


def methods():
    """{method: (normals needed: "face" | "vertex" | "none", [(parameter, default, description)])}
    of every discretization laplacian accepts."""
    return _core.methods()


def backends():
    """({linear solver: [(option, default, description)]}, {eigen solver: [...]}): the names and
    keyword options of solve and eigs."""
    return _core.backends()


_document_laplacian()


def _document_defaults():
    """The library's default radii in the docstrings that name them."""
    values = {"{voxel_ii_radius}": _core.VOXEL_II_RADIUS,
              "{voxel_min_curvature_radius}": _core.VOXEL_MIN_CURVATURE_RADIUS,
              "{curvature_radius_fraction}": _core.CURVATURE_RADIUS_FRACTION,
              "{curvature_site_spacing}": _core.CURVATURE_SITE_SPACING,
              "{solve_accuracy}": _core.SOLVE_ACCURACY,
              "{alpha0_start}": _core.ALPHA0_START}
    for function in (ii_normals, curvature, regularize, regularize_volume):
        for name, value in values.items():
            function.__doc__ = function.__doc__.replace(name, f"{value:g}")


_document_defaults()
