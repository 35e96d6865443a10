#include "normal_fields.hpp"

#include <cmath>
#include <sstream>

#include "error.hpp"

namespace corrlap {

const char* to_string(NormalKind kind) {
  switch (kind) {
    case NormalKind::None: return "none";
    case NormalKind::Face: return "face";
    case NormalKind::Vertex: return "vertex";
  }
  return "?";
}

Eigen::MatrixX3d vertex_normals_from_face_normals(const Eigen::MatrixX3d& face_normals,
                                                  const Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor>& faces,
                                                  int num_vertices) {
  if (face_normals.rows() != faces.rows())
    throw InputError("vertex normals: expected one face normal per face");
  Eigen::MatrixX3d vn = Eigen::MatrixX3d::Zero(num_vertices, 3);
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    for (int j = 0; j < 4; ++j) vn.row(faces(f, j)) += face_normals.row(f);
  for (Eigen::Index v = 0; v < vn.rows(); ++v) {
    const double n = vn.row(v).norm();
    if (n > 0) vn.row(v) /= n;
  }
  return vn;
}

void validate_normals(Eigen::MatrixX3d& normals, Eigen::Index expected_rows, const std::string& what,
                      bool normalize, double tolerance) {
  if (normals.rows() != expected_rows) {
    std::ostringstream os;
    os << what << ": expected " << expected_rows << " normals, got " << normals.rows();
    throw InputError(os.str());
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

}  // namespace corrlap
