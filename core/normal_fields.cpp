#include "normal_fields.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <cmath>
#include <sstream>

#include "error.hpp"

namespace corrlap {

const char* to_string(NormalKind kind) {
  switch (kind) {
    case NormalKind::None:
      return "none";
    case NormalKind::Face:
      return "face";
    case NormalKind::Vertex:
      return "vertex";
  }
  return "?";
}

Eigen::MatrixX3d vertex_normals_from_face_normals(const Eigen::MatrixX3d& face_normals,
                                                  const Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor>& faces,
                                                  int num_vertices) {
  if (face_normals.rows() != faces.rows()) throw InputError("vertex normals: expected one face normal per face");
  Eigen::MatrixX3d vn = Eigen::MatrixX3d::Zero(num_vertices, 3);
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    for (int j = 0; j < 4; ++j) vn.row(faces(f, j)) += face_normals.row(f);
  for (Eigen::Index v = 0; v < vn.rows(); ++v) {
    const double n = vn.row(v).norm();
    if (n > 0) vn.row(v) /= n;
  }
  return vn;
}

void validate_normals(Eigen::MatrixX3d& normals, Eigen::Index expected_rows, const std::string& what, bool normalize,
                      double tolerance) {
  if (normals.rows() != expected_rows) {
    std::ostringstream os;
    os << what << ": expected " << expected_rows << " normals, got " << normals.rows();
    throw InputError(os.str());
  }
  // Fast path (parallel): every row finite and unit. Otherwise the serial scan below names the
  // first offending row (or normalizes).
  if (!normalize) {
    const bool all_good = tbb::parallel_reduce(
        tbb::blocked_range<Eigen::Index>(0, normals.rows(), 8192), true,
        [&](const tbb::blocked_range<Eigen::Index>& r, bool ok) {
          for (Eigen::Index i = r.begin(); ok && i != r.end(); ++i) {
            const double len = normals.row(i).norm();
            ok = std::isfinite(len) && std::abs(len - 1.0) <= tolerance;
          }
          return ok;
        },
        [](bool a, bool b) { return a && b; });
    if (all_good) return;
  }
  for (Eigen::Index i = 0; i < normals.rows(); ++i) {
    const Eigen::Vector3d n = normals.row(i).transpose();
    if (!n.allFinite()) {
      std::ostringstream os;
      os << what << ": normal " << i << " is not finite (" << n.transpose() << ")";
      throw InputError(os.str());
    }
    const double len = n.norm();
    if (len == 0.0) {
      std::ostringstream os;
      os << what << ": normal " << i << " is the zero vector";
      throw InputError(os.str());
    }
    if (normalize) {
      normals.row(i) /= len;
    } else if (std::abs(len - 1.0) > tolerance) {
      std::ostringstream os;
      os.precision(10);
      os << what << ": normal " << i << " has length " << len
         << " (unit normals required; ask for normalization to accept it)";
      throw InputError(os.str());
    }
  }
}

void check_normals(const Eigen::MatrixX3d& normals, Eigen::Index expected_rows, const std::string& what,
                   double tolerance) {
  // validate_normals writes only when normalizing, so the cast never leads to a write.
  validate_normals(const_cast<Eigen::MatrixX3d&>(normals), expected_rows, what, false, tolerance);
}

}  // namespace corrlap
