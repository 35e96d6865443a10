#pragma once
// Conversions between Python values (numpy arrays, dicts) and the library's Eigen types, with the
// checks the bindings promise (docs/python.md): dtype, shape, finite values and index range, each
// failure a ValueError naming the argument. Outputs are numpy arrays the caller owns.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <Eigen/Core>
#include <Eigen/Sparse>
#include <corrlap/core/config.hpp>
#include <corrlap/core/progress.hpp>
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/estimators/normal_resolution.hpp>
#include <corrlap/pipeline/load_surface.hpp>
#include <optional>
#include <string>

namespace corrlap::python {

namespace py = pybind11;
using FaceMatrix = Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor>;

/// The `progress=` keyword: None or a callable taking one str. The line function returned calls it
/// with each progress line (the GIL taken, from whichever thread reports) and, callable or not,
/// checks for Ctrl-C, so that a long computation stops at its next report. What the callable
/// raises, KeyboardInterrupt included, leaves through the computation as py::error_already_set and
/// is raised in Python; later reports call nothing. TypeError for anything else than None or a
/// callable.
ProgressLine progress_arg(const py::object& progress);

/// Rows x 3 floats (any of int32/int64/float32/float64, any order), finite. `rows` < 0: any count.
Eigen::MatrixX3d points_arg(py::handle obj, const std::string& name, Eigen::Index rows = -1);
/// Vertex ids of faces: an m x d integer array (any width) with ids in [0, num_vertices) and d in
/// [min_corners, max_corners]; `shape_wanted` words the shape for the error, e.g. "(m, 4) (quads)".
/// The ids as int64 in C order.
using FaceIds = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;
FaceIds face_ids_arg(py::handle obj, const std::string& name, Eigen::Index num_vertices, Eigen::Index min_corners,
                     Eigen::Index max_corners, const std::string& shape_wanted);
/// Quads: face_ids_arg with d = 4.
FaceMatrix faces_arg(py::handle obj, const std::string& name, Eigen::Index num_vertices);
/// A vector of `rows` finite values (rows < 0: any length).
Eigen::VectorXd vector_arg(py::handle obj, const std::string& name, Eigen::Index rows = -1);
/// (rows,) or (rows, k) finite values as rows x k; `was_vector` tells which it was.
Eigen::MatrixXd matrix_arg(py::handle obj, const std::string& name, Eigen::Index rows, bool& was_vector);
/// The array behind `obj` as numpy, refusing complex, object, string and (unless allow_bool) bool dtypes.
py::array numeric_array(py::handle obj, const std::string& name, bool allow_bool = false);

/// The element type of a volume (bool, int8 ... uint64, float32, float64); other dtypes (float16,
/// longdouble) are refused with a hint.
VoxelValueType voxel_value_type(const py::dtype& dtype, const std::string& name);

/// V, F and the grid step (not given: unknown, as for a mesh read from a file; given: positive and
/// finite) as a SurfelMesh without surfels.
SurfelMesh mesh_arg(py::handle V, py::handle F, std::optional<double> h = std::nullopt);

/// face_normals (#F, 3) and vertex_normals (#V, 3), each None or an array, as the library's request
/// of given normals (NormalSource::Given) for resolve_normals.
NormalRequest given_normals_arg(py::handle face_normals, py::handle vertex_normals, const SurfelMesh& mesh);

/// Keyword options as a Config: bool, int, float and str values (the types of the CLI's key=value);
/// None is "not given" (the default).
Config config_arg(const py::dict& options, const std::string& what);

/// thin_parts: "shrink" | "keep" (docs/math.md §7.2, the CLI's --ii-thin-parts) as
/// IIParams::shrink_on_thin_parts; None: the input's default (default_ii_params). ValueError otherwise.
std::optional<bool> thin_parts_arg(const std::optional<std::string>& thin_parts);

/// CSC arrays (data, indices, indptr, shape) viewing the matrix's own storage: the matrix is moved
/// into the arrays' owner, so no entry is copied.
py::tuple sparse_out(Eigen::SparseMatrix<double>&& matrix);
/// A CSC matrix from scipy's arrays (float64 data, integer indices and indptr), checked.
Eigen::SparseMatrix<double> sparse_in(py::handle data, py::handle indices, py::handle indptr, Eigen::Index rows,
                                      Eigen::Index cols, const std::string& name);

/// Row-major numpy copies (n, 3) / (n,) / (n, k) / (m, 4) int64.
py::array_t<double> to_numpy(const Eigen::MatrixX3d& m);
py::array_t<double> to_numpy(const Eigen::VectorXd& v);
py::array_t<double> to_numpy(const Eigen::MatrixXd& m);
py::array_t<std::int64_t> faces_to_numpy(const FaceMatrix& f);

}  // namespace corrlap::python
