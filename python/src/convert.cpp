#include "convert.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>

namespace corrlap::python {
namespace {

std::string shape_of(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

// Lowest index i in [0, n) with bad(i), or n: the first offending row whatever the thread count.
template <class Bad>
Eigen::Index first_bad(Eigen::Index n, const Bad& bad) {
  std::atomic<Eigen::Index> first(n);
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, n, 4096), [&](const tbb::blocked_range<Eigen::Index>& r) {
    if (r.begin() >= first.load(std::memory_order_relaxed)) return;
    for (Eigen::Index i = r.begin(); i != r.end(); ++i)
      if (bad(i)) {
        Eigen::Index seen = first.load();
        while (i < seen && !first.compare_exchange_weak(seen, i)) {
        }
        return;
      }
  });
  return first.load();
}

using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

DoubleArray as_doubles(const py::array& a) { return DoubleArray::ensure(a); }

}  // namespace

py::array numeric_array(py::handle obj, const std::string& name, bool allow_bool) {
  py::array a;
  try {
    a = py::module_::import("numpy").attr("asarray")(obj);
  } catch (py::error_already_set& e) {
    throw py::value_error(name + ": not convertible to a numpy array (" + e.what() + ")");
  }
  const char kind = a.dtype().kind();
  if (kind == 'f' || kind == 'i' || kind == 'u' || (allow_bool && kind == 'b')) return a;
  throw py::value_error(name + ": dtype " + std::string(py::str(a.dtype())) +
                        " is not supported (expected int32, int64, float32 or float64" +
                        (allow_bool ? " or bool" : "") + ")");
}

Eigen::MatrixX3d points_arg(py::handle obj, const std::string& name, Eigen::Index rows) {
  const py::array a = numeric_array(obj, name);
  if (a.ndim() != 2 || a.shape(1) != 3) throw py::value_error(name + ": expected shape (n, 3), got " + shape_of(a));
  if (rows >= 0 && a.shape(0) != rows)
    throw py::value_error(name + ": expected " + std::to_string(rows) + " rows, got " + shape_of(a));
  const DoubleArray d = as_doubles(a);
  const double* p = d.data();
  const Eigen::Index n = a.shape(0);
  Eigen::MatrixX3d out(n, 3);
  // One pass copies to Eigen's column-major layout and checks the values.
  const Eigen::Index bad = first_bad(n, [&](Eigen::Index i) {
    const double x = p[3 * i], y = p[3 * i + 1], z = p[3 * i + 2];
    out(i, 0) = x;
    out(i, 1) = y;
    out(i, 2) = z;
    return !(std::isfinite(x) && std::isfinite(y) && std::isfinite(z));
  });
  if (bad < n) throw py::value_error(name + ": row " + std::to_string(bad) + " is not finite (NaN or Inf)");
  return out;
}

FaceIds face_ids_arg(py::handle obj, const std::string& name, Eigen::Index num_vertices, Eigen::Index min_corners,
                     Eigen::Index max_corners, const std::string& shape_wanted) {
  const py::array a = numeric_array(obj, name);
  const char kind = a.dtype().kind();
  if (kind != 'i' && kind != 'u')
    throw py::value_error(name + ": vertex ids must be integers, got dtype " + std::string(py::str(a.dtype())));
  if (a.ndim() != 2 || a.shape(1) < min_corners || a.shape(1) > max_corners)
    throw py::value_error(name + ": expected shape " + shape_wanted + ", got " + shape_of(a));
  FaceIds ids = FaceIds::ensure(a);
  const std::int64_t* p = ids.data();
  const Eigen::Index m = a.shape(0), d = a.shape(1);
  const auto out_of_range = [&](std::int64_t v) { return v < 0 || v >= num_vertices; };
  const Eigen::Index bad =
      first_bad(m, [&](Eigen::Index f) { return std::any_of(p + f * d, p + (f + 1) * d, out_of_range); });
  if (bad < m) {
    const std::int64_t v = *std::find_if(p + bad * d, p + (bad + 1) * d, out_of_range);
    throw py::value_error(name + ": face " + std::to_string(bad) + " has vertex id " + std::to_string(v) +
                          ", out of range [0, " + std::to_string(num_vertices) + ")");
  }
  return ids;
}

FaceMatrix faces_arg(py::handle obj, const std::string& name, Eigen::Index num_vertices) {
  const FaceIds ids = face_ids_arg(obj, name, num_vertices, 4, 4, "(m, 4) (quads)");
  return Eigen::Map<const Eigen::Matrix<std::int64_t, Eigen::Dynamic, 4, Eigen::RowMajor>>(ids.data(), ids.shape(0), 4)
      .cast<int>();
}

Eigen::VectorXd vector_arg(py::handle obj, const std::string& name, Eigen::Index rows) {
  const py::array a = numeric_array(obj, name);
  if (a.ndim() != 1) throw py::value_error(name + ": expected shape (n,), got " + shape_of(a));
  if (rows >= 0 && a.shape(0) != rows)
    throw py::value_error(name + ": expected " + std::to_string(rows) + " values, got " + shape_of(a));
  const DoubleArray d = as_doubles(a);
  const Eigen::VectorXd v = Eigen::Map<const Eigen::VectorXd>(d.data(), a.shape(0));
  if (!v.allFinite()) throw py::value_error(name + ": a value is not finite (NaN or Inf)");
  return v;
}

Eigen::MatrixXd matrix_arg(py::handle obj, const std::string& name, Eigen::Index rows, bool& was_vector) {
  const py::array a = numeric_array(obj, name);
  if (a.ndim() != 1 && a.ndim() != 2)
    throw py::value_error(name + ": expected shape (n,) or (n, k), got " + shape_of(a));
  if (a.shape(0) != rows)
    throw py::value_error(name + ": expected " + std::to_string(rows) + " rows, got " + shape_of(a));
  was_vector = a.ndim() == 1;
  const Eigen::Index cols = was_vector ? 1 : a.shape(1);
  const DoubleArray d = as_doubles(a);
  const Eigen::MatrixXd m =
      Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(d.data(), rows, cols);
  if (!m.allFinite()) throw py::value_error(name + ": a value is not finite (NaN or Inf)");
  return m;
}

VoxelValueType voxel_value_type(const py::dtype& dtype, const std::string& name) {
  const char kind = dtype.kind();
  const auto size = dtype.itemsize();
  if (kind == 'b') return VoxelValueType::Bool;
  if (kind == 'i' && size == 1) return VoxelValueType::Int8;
  if (kind == 'i' && size == 2) return VoxelValueType::Int16;
  if (kind == 'i' && size == 4) return VoxelValueType::Int32;
  if (kind == 'i' && size == 8) return VoxelValueType::Int64;
  if (kind == 'u' && size == 1) return VoxelValueType::UInt8;
  if (kind == 'u' && size == 2) return VoxelValueType::UInt16;
  if (kind == 'u' && size == 4) return VoxelValueType::UInt32;
  if (kind == 'u' && size == 8) return VoxelValueType::UInt64;
  if (kind == 'f' && size == 4) return VoxelValueType::Float32;
  if (kind == 'f' && size == 8) return VoxelValueType::Float64;
  throw py::value_error(name + ": dtype " + std::string(py::str(py::handle(dtype))) +
                        " is not supported (expected bool, an integer type, float32 or float64); convert it, e.g. " +
                        name + ".astype(numpy.float32)");
}

SurfelMesh mesh_arg(py::handle V, py::handle F, std::optional<double> h) {
  if (h) check_grid_step(*h, "the surface");
  SurfelMesh mesh;
  mesh.positions = points_arg(V, "V");
  mesh.faces = faces_arg(F, "F", mesh.positions.rows());
  mesh.h = h.value_or(0.0);  // 0: unknown (SurfelMesh::grid_step uses the mean edge length)
  return mesh;
}

NormalRequest given_normals_arg(py::handle face_normals, py::handle vertex_normals, const SurfelMesh& mesh) {
  NormalRequest request;
  request.source = NormalSource::Given;
  if (!face_normals.is_none()) request.face_normals = points_arg(face_normals, "face_normals", mesh.num_faces());
  if (!vertex_normals.is_none())
    request.vertex_normals = points_arg(vertex_normals, "vertex_normals", mesh.num_vertices());
  return request;
}

Config config_arg(const py::dict& options, const std::string& what) {
  Config config;
  for (const auto& [key, value] : options) {
    const std::string k = py::str(key);
    if (value.is_none()) continue;
    if (py::isinstance<py::bool_>(value)) {
      config.set(k, value.cast<bool>());
    } else if (py::isinstance<py::str>(value)) {
      config.set(k, value.cast<std::string>());
    } else if (py::hasattr(value, "__float__")) {
      config.set(k, value.cast<double>());  // ints too: the CLI's key=value numbers are doubles
    } else {
      throw py::value_error(what + ": option '" + k + "' has type " + std::string(py::str(value.get_type())) +
                            "; expected a bool, a number or a string");
    }
  }
  return config;
}

py::tuple sparse_out(Eigen::SparseMatrix<double>&& matrix) {
  auto* held = new Eigen::SparseMatrix<double>();
  held->swap(matrix);  // Eigen 3.4's SparseMatrix has no move constructor
  held->makeCompressed();
  const py::capsule owner(held, [](void* p) { delete static_cast<Eigen::SparseMatrix<double>*>(p); });
  const py::ssize_t nnz = held->nonZeros();
  const py::ssize_t cols = held->outerSize();
  py::array_t<double> data(nnz, held->valuePtr(), owner);
  py::array_t<int> indices(nnz, held->innerIndexPtr(), owner);
  py::array_t<int> indptr(cols + 1, held->outerIndexPtr(), owner);
  return py::make_tuple(data, indices, indptr, py::make_tuple(held->rows(), held->cols()));
}

Eigen::SparseMatrix<double> sparse_in(py::handle data, py::handle indices, py::handle indptr, Eigen::Index rows,
                                      Eigen::Index cols, const std::string& name) {
  const DoubleArray x = as_doubles(numeric_array(data, name + ".data"));
  using Ints = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;
  const Ints inner = Ints::ensure(numeric_array(indices, name + ".indices"));
  const Ints outer = Ints::ensure(numeric_array(indptr, name + ".indptr"));
  const py::ssize_t nnz = x.size();
  if (inner.size() != nnz || outer.size() != cols + 1 || outer.data()[0] != 0 || outer.data()[cols] != nnz)
    throw py::value_error(name + ": inconsistent CSC arrays");
  if (nnz > std::numeric_limits<int>::max()) throw py::value_error(name + ": more than 2^31 entries");
  Eigen::SparseMatrix<double> m(rows, cols);
  m.resizeNonZeros(nnz);
  for (Eigen::Index j = 0; j <= cols; ++j) m.outerIndexPtr()[j] = int(outer.data()[j]);
  for (Eigen::Index j = 0; j < cols; ++j) {
    const std::int64_t begin = outer.data()[j], end = outer.data()[j + 1];
    if (end < begin) throw py::value_error(name + ": indptr decreases at column " + std::to_string(j));
    for (std::int64_t k = begin; k < end; ++k) {
      const std::int64_t i = inner.data()[k];
      if (i < 0 || i >= rows || (k > begin && i <= inner.data()[k - 1]))
        throw py::value_error(name + ": row indices of column " + std::to_string(j) +
                              " are out of range or not sorted and distinct");
      if (!std::isfinite(x.data()[k]))
        throw py::value_error(name + ": entry (" + std::to_string(i) + ", " + std::to_string(j) + ") is not finite");
      m.innerIndexPtr()[k] = int(i);
      m.valuePtr()[k] = x.data()[k];
    }
  }
  return m;
}

py::array_t<double> to_numpy(const Eigen::MatrixX3d& m) {
  py::array_t<double> a({m.rows(), Eigen::Index(3)});
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(a.mutable_data(), m.rows(), 3) = m;
  return a;
}

py::array_t<double> to_numpy(const Eigen::VectorXd& v) {
  py::array_t<double> a(v.size());
  Eigen::Map<Eigen::VectorXd>(a.mutable_data(), v.size()) = v;
  return a;
}

py::array_t<double> to_numpy(const Eigen::MatrixXd& m) {
  py::array_t<double> a({m.rows(), m.cols()});
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(a.mutable_data(), m.rows(),
                                                                                     m.cols()) = m;
  return a;
}

py::array_t<std::int64_t> faces_to_numpy(const FaceMatrix& f) {
  py::array_t<std::int64_t> a({f.rows(), Eigen::Index(4)});
  Eigen::Map<Eigen::Matrix<std::int64_t, Eigen::Dynamic, 4, Eigen::RowMajor>>(a.mutable_data(), f.rows(), 4) =
      f.cast<std::int64_t>();
  return a;
}

std::optional<bool> thin_parts_arg(const std::optional<std::string>& thin_parts) {
  if (!thin_parts) return std::nullopt;
  if (*thin_parts != "shrink" && *thin_parts != "keep")
    throw py::value_error("thin_parts: '" + *thin_parts + "': expected 'shrink' or 'keep'");
  return *thin_parts == "shrink";
}

ProgressLine progress_arg(const py::object& progress) {
  if (!progress.is_none() && !PyCallable_Check(progress.ptr()))
    throw py::type_error("progress: expected None or a callable taking one str, got " +
                         std::string(py::str(py::type::of(progress).attr("__name__"))));
  // Shared by the copies of the returned function, which the computation may drop without the GIL:
  // the callable is released with it taken.
  struct State {
    py::object callable;
    std::atomic<bool> stopped{false};
    ~State() {
      py::gil_scoped_acquire gil;
      callable = py::object();
    }
  };
  auto state = std::make_shared<State>();
  state->callable = progress;
  return [state](const std::string& line) {
    if (state->stopped) return;
    py::gil_scoped_acquire gil;
    try {
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
      if (!state->callable.is_none()) state->callable(py::str(line));
    } catch (...) {
      state->stopped = true;
      throw;
    }
  };
}

}  // namespace corrlap::python
