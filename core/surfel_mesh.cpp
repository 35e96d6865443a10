#include "surfel_mesh.hpp"

#include <cmath>
#include <sstream>

#include "error.hpp"

namespace corrlap {

Eigen::Vector3i Surfel::inner_voxel() const {
  return outward > 0 ? lower_voxel : Eigen::Vector3i(lower_voxel + Eigen::Vector3i::Unit(axis));
}
Eigen::Vector3i Surfel::outer_voxel() const {
  return outward > 0 ? Eigen::Vector3i(lower_voxel + Eigen::Vector3i::Unit(axis)) : lower_voxel;
}
Eigen::Vector3d Surfel::trivial_normal() const { return double(outward) * Eigen::Vector3d::Unit(axis); }
Eigen::Vector3i Surfel::khalimsky() const {
  return 2 * lower_voxel + Eigen::Vector3i::Unit(axis) + Eigen::Vector3i::Ones();
}
bool Surfel::positive() const {
  // docs/math.md §1.4: outward -e0 (k=0), +e1 (k=1), -e2 (k=2)
  return axis == 1 ? outward > 0 : outward < 0;
}

Eigen::MatrixX3d SurfelMesh::face_centroids() const {
  Eigen::MatrixX3d c(faces.rows(), 3);
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    c.row(f) = 0.25 * (positions.row(faces(f, 0)) + positions.row(faces(f, 1)) + positions.row(faces(f, 2)) +
                       positions.row(faces(f, 3)));
  return c;
}

Eigen::MatrixX3d SurfelMesh::face_normals_from_positions() const {
  Eigen::MatrixX3d n(faces.rows(), 3);
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    for (int j = 0; j < 4; ++j) b += positions.row(faces(f, j)).transpose();
    b *= 0.25;
    Eigen::Vector3d s = Eigen::Vector3d::Zero();
    for (int j = 0; j < 4; ++j) {
      const Eigen::Vector3d a = positions.row(faces(f, j)).transpose() - b;
      const Eigen::Vector3d c = positions.row(faces(f, (j + 1) % 4)).transpose() - b;
      s += a.cross(c);
    }
    const double len = s.norm();
    n.row(f) = len > 0 ? Eigen::RowVector3d((s / len).transpose()) : Eigen::RowVector3d::Zero();
  }
  return n;
}

double SurfelMesh::grid_step() const {
  if (h > 0) return h;
  if (faces.rows() == 0) return 0.0;
  double sum = 0.0;
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    for (int j = 0; j < 4; ++j) sum += (positions.row(faces(f, (j + 1) % 4)) - positions.row(faces(f, j))).norm();
  return sum / double(4 * faces.rows());
}

void SurfelMesh::validate(const char* what) const {
  const int nv = num_vertices();
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    for (int j = 0; j < 4; ++j) {
      const int v = faces(f, j);
      if (v < 0 || v >= nv) {
        std::ostringstream os;
        os << what << ": face " << f << " refers to vertex " << v << " but there are " << nv << " vertices";
        throw InputError(os.str());
      }
      for (int k = 0; k < j; ++k)
        if (faces(f, k) == v) {
          std::ostringstream os;
          os << what << ": face " << f << " uses vertex " << v << " twice (degenerate quad)";
          throw InputError(os.str());
        }
    }
  for (Eigen::Index v = 0; v < positions.rows(); ++v)
    if (!positions.row(v).allFinite()) {
      std::ostringstream os;
      os << what << ": vertex " << v << " has a non-finite position";
      throw InputError(os.str());
    }
  if (!surfels.empty() && surfels.size() != std::size_t(faces.rows()))
    throw InputError(std::string(what) + ": surfel data does not match the number of faces");
}

}  // namespace corrlap
