#pragma once
// Normal fields given to the discretizations and produced by the estimators (docs/math.md §1.5).
#include <Eigen/Core>
#include <string>

namespace corrlap {

/// Which normal field an operator needs.
enum class NormalKind { None, Face, Vertex };
const char* to_string(NormalKind kind);

/// Unit normals per face (#F x 3) and/or per vertex (#V x 3); an empty matrix means absent.
struct NormalFields {
  Eigen::MatrixX3d face;
  Eigen::MatrixX3d vertex;

  bool has_face() const { return face.rows() > 0; }
  bool has_vertex() const { return vertex.rows() > 0; }
};

/// Normalized sum of the incident face normals (docs/math.md §1.5, the reference's
/// computeVertexNormalsFromFaceNormals). Vertices with no face (or a zero sum) get (0,0,0).
Eigen::MatrixX3d vertex_normals_from_face_normals(const Eigen::MatrixX3d& face_normals,
                                                  const Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor>& faces,
                                                  int num_vertices);

/// Throws InputError naming the first offending row when the field has the wrong number of
/// rows, a NaN/Inf or zero vector, or (unless normalize) a length off 1 by more than tolerance.
/// With normalize = true, rows are normalized in place instead of rejected for their length.
void validate_normals(Eigen::MatrixX3d& normals, Eigen::Index expected_rows, const std::string& what,
                      bool normalize = false, double tolerance = 1e-6);
/// The same checks without normalization, on a field that stays unchanged (no copy needed).
void check_normals(const Eigen::MatrixX3d& normals, Eigen::Index expected_rows, const std::string& what,
                   double tolerance = 1e-6);

}  // namespace corrlap
