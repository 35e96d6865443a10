#pragma once
// A mesh file written in pieces, by writers that each hold only some of the mesh (the MPI ranks of
// distributed/distributed_mesh_output.hpp): the header, and the bytes of runs of consecutive
// vertices or faces. The header, then every vertex run, then every face run, each run in the
// order of its first id, is byte for byte the file write_mesh writes for the whole mesh (binary
// PLY or OBJ, by the path's extension).
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "mesh_io.hpp"

namespace corrlap {

/// What every piece of one file agrees on.
struct MeshFileLayout {
  std::string path;                         ///< its extension chooses the format: .ply or .obj
  std::int64_t vertices = 0, faces = 0;     ///< of the whole mesh
  bool vertex_normals = false;              ///< PLY: nx ny nz per vertex
  std::vector<std::string> vertex_scalars;  ///< PLY: the names, in MeshAttributes' (sorted) order
  std::vector<std::string> comments;        ///< header lines, without line breaks
};

/// The layout of `path` for a mesh of `vertices` and `faces` with `attributes`' vertex normals,
/// vertex scalars (by name) and comments. IoError as write_mesh on an unknown extension, a bad
/// scalar name, a comment with a line break, face attributes (not written in pieces).
MeshFileLayout mesh_file_layout(const std::string& path, std::int64_t vertices, std::int64_t faces,
                                const MeshAttributes& attributes);

/// The file's header.
std::string mesh_file_header(const MeshFileLayout& layout);

/// The bytes of vertices first, first + 1, ...: the rows of `positions` (k by 3) and, in PLY, of
/// `attributes`' vertex normals and scalars (the layout's, k rows each). IoError naming the vertex
/// (its id in the whole mesh) on a non-finite value, and on attributes that do not match.
std::string mesh_file_vertices(const MeshFileLayout& layout, std::int64_t first, const Eigen::MatrixX3d& positions,
                               const MeshAttributes& attributes);

/// Quadrilateral faces as rows of 4 vertex ids of the whole mesh (0-based).
using QuadFaces = Eigen::Matrix<std::int64_t, Eigen::Dynamic, 4, Eigen::RowMajor>;

/// The bytes of `faces`. IoError on an id outside the mesh's vertices.
std::string mesh_file_faces(const MeshFileLayout& layout, const QuadFaces& faces);

}  // namespace corrlap
