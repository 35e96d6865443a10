#include "polygon_mesh.hpp"

#include <sstream>

#include "error.hpp"

namespace corrlap {

bool PolygonMesh::all_quads() const {
  for (const auto& f : faces)
    if (f.size() != 4) return false;
  return true;
}

bool PolygonMesh::all_triangles() const {
  for (const auto& f : faces)
    if (f.size() != 3) return false;
  return true;
}

SurfelMesh to_surfel_mesh(const PolygonMesh& mesh, const std::string& what) {
  SurfelMesh out;
  out.positions = mesh.positions;
  out.faces.resize(Eigen::Index(mesh.faces.size()), 4);
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    if (mesh.faces[f].size() != 4) {
      std::ostringstream os;
      os << what << ": face " << f << " has " << mesh.faces[f].size()
         << " corners; digital surfaces need quads (one per surfel)";
      throw InputError(os.str());
    }
    for (int j = 0; j < 4; ++j) out.faces(Eigen::Index(f), j) = mesh.faces[f][std::size_t(j)];
  }
  out.validate(what.c_str());
  return out;
}

PolygonMesh to_polygon_mesh(const SurfelMesh& mesh) {
  PolygonMesh out;
  out.positions = mesh.positions;
  out.faces.reserve(std::size_t(mesh.num_faces()), 4 * std::size_t(mesh.num_faces()));
  for (int f = 0; f < mesh.num_faces(); ++f)
    out.faces.push_back({mesh.faces(f, 0), mesh.faces(f, 1), mesh.faces(f, 2), mesh.faces(f, 3)});
  return out;
}

Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor> triangulate(const PolygonMesh& mesh) {
  std::size_t count = 0;
  for (const auto& f : mesh.faces) count += f.size() >= 3 ? f.size() - 2 : 0;
  Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor> T(Eigen::Index(count), 3);
  Eigen::Index t = 0;
  for (const auto& f : mesh.faces)
    for (std::size_t j = 1; j + 1 < f.size(); ++j) T.row(t++) << f[0], f[j], f[j + 1];
  return T;
}

}  // namespace corrlap
