#pragma once
// General polygon meshes (as read from files) and their conversion to quad/triangle meshes.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "face_list.hpp"
#include "surfel_mesh.hpp"

namespace corrlap {

/// Triangles as rows of three 0-based vertex ids (#T x 3).
using TriangleIndices = Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>;

/// Vertices and faces of any degree >= 3 (0-based ids), as stored in a file.
struct PolygonMesh {
  Eigen::MatrixX3d positions;
  FaceList faces;  ///< faces[f] is a std::span of the corner ids of face f

  bool all_quads() const;
  bool all_triangles() const;
};

/// Quad mesh with vertex and face order kept exactly. Throws InputError naming the first face
/// that is not a quad or refers to a missing vertex. `what` names the source in messages.
SurfelMesh to_surfel_mesh(const PolygonMesh& mesh, const std::string& what);

/// Polygon mesh with the same vertices and faces.
PolygonMesh to_polygon_mesh(const SurfelMesh& mesh);

/// Triangles (#T x 3): triangles kept, other polygons fanned from their first corner.
TriangleIndices triangulate(const PolygonMesh& mesh);

}  // namespace corrlap
