#pragma once
// Reading and writing meshes. Formats chosen by file extension: .obj (read/write), .ply
// (binary write with per-vertex/per-face scalars and normals; ASCII/binary read), .off (read).
#include <Eigen/Core>
#include <map>
#include <string>

#include <corrlap/core/polygon_mesh.hpp>
#include <corrlap/core/surfel_mesh.hpp>

namespace corrlap {

/// Reads OBJ (v / f lines; "f a/b/c" forms, negative indices), PLY or OFF by extension.
/// Throws IoError naming the file, the line and the problem.
PolygonMesh read_mesh(const std::string& path);
PolygonMesh read_obj(const std::string& path);

/// Per-element attributes written with a mesh (PLY); OBJ writes positions and faces only.
struct MeshAttributes {
  std::map<std::string, Eigen::VectorXd> vertex_scalars, face_scalars;
  Eigen::MatrixX3d vertex_normals, face_normals;  // empty = absent
};

/// Writes by extension (.obj or .ply). Positions with 17 significant digits in OBJ.
void write_mesh(const std::string& path, const PolygonMesh& mesh, const MeshAttributes& attributes = {});
void write_obj(const std::string& path, const PolygonMesh& mesh);
inline void write_mesh(const std::string& path, const SurfelMesh& mesh, const MeshAttributes& attributes = {}) {
  write_mesh(path, to_polygon_mesh(mesh), attributes);
}

}  // namespace corrlap
