#pragma once
// Reading and writing meshes. Formats chosen by file extension: .obj (read/write), .ply
// (binary little-endian write with per-vertex/per-face scalars and normals; ASCII and binary
// little-endian read), .off (read). See docs/io.md for the table of supported formats.
#include <Eigen/Core>
#include <corrlap/core/polygon_mesh.hpp>
#include <corrlap/core/surfel_mesh.hpp>
#include <map>
#include <string>
#include <vector>

namespace corrlap {

/// Per-element attributes written with a mesh (PLY); OBJ writes positions and faces only.
/// Scalar names must be PLY identifiers (letters, digits, '_', '-', '.'), distinct from
/// x, y, z, nx, ny, nz and vertex_indices.
struct MeshAttributes {
  std::map<std::string, Eigen::VectorXd> vertex_scalars, face_scalars;
  Eigen::MatrixX3d vertex_normals, face_normals;  // empty = absent
  /// Header comments, one line each, written by OBJ ("# ...") and PLY ("comment ..."): e.g.
  /// "SPACE=LPS", which 3D Slicer reads to place the mesh.
  std::vector<std::string> comments;
};

/// The extension of a file name, lower case, without the dot ("" when there is none): how the
/// readers and writers pick a format.
std::string file_extension(const std::string& path);

/// Reads OBJ (v / f lines; "f a/b/c" forms, negative indices), PLY or OFF by extension (any case).
/// `attributes`, when given, receives a PLY file's normals and scalars (see read_ply) and is emptied
/// for the other formats. Throws IoError naming the file, the line (or element) and the problem.
PolygonMesh read_mesh(const std::string& path, MeshAttributes* attributes = nullptr);
PolygonMesh read_obj(const std::string& path);
/// PLY, ASCII or binary little-endian: vertex x y z (any numeric type), face list
/// "vertex_indices" or "vertex_index". Other elements are skipped. When `attributes` is given,
/// vertex/face properties nx ny nz become normals and every other scalar property a named scalar.
/// Vertex positions and normals must be finite; a named scalar may hold NaN (an undefined value).
PolygonMesh read_ply(const std::string& path, MeshAttributes* attributes = nullptr);
/// OFF (also COFF/NOFF headers): counts line, vertices (extra columns ignored), faces "n i1 .. in".
PolygonMesh read_off(const std::string& path);

/// Writes by extension (.obj or .ply). Positions with 17 significant digits in OBJ; PLY stores
/// doubles (exact round trip). OBJ writes the attributes' comments only.
void write_mesh(const std::string& path, const PolygonMesh& mesh, const MeshAttributes& attributes = {});
/// `comments`: header lines after the first, each without a line break (IoError otherwise).
void write_obj(const std::string& path, const PolygonMesh& mesh, const std::vector<std::string>& comments = {});
/// Binary little-endian PLY: vertex x y z [nx ny nz] [scalars] as double, face list
/// (uchar count, int ids) "vertex_indices" [nx ny nz] [scalars]. Throws IoError when an attribute
/// has the wrong number of rows or an invalid name.
void write_ply(const std::string& path, const PolygonMesh& mesh, const MeshAttributes& attributes = {});
inline void write_mesh(const std::string& path, const SurfelMesh& mesh, const MeshAttributes& attributes = {}) {
  write_mesh(path, to_polygon_mesh(mesh), attributes);
}

}  // namespace corrlap
