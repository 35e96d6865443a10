#include "normal_resolution.hpp"

#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/estimators/implicit_normals.hpp>
#include <corrlap/io/text_io.hpp>

namespace corrlap {

NormalSource effective_normal_source(NormalSource source, const ImplicitShape* shape, const VoxelGrid* grid) {
  if (source != NormalSource::Auto) return source;
  if (shape) return NormalSource::True;
  if (grid) return NormalSource::II;
  return NormalSource::Auto;
}

namespace {

// A file or a matrix (not both) with one row per face or vertex; 0 rows when neither is given.
Eigen::MatrixX3d given_normals(const std::string& path, const Eigen::MatrixX3d& matrix, Eigen::Index expected,
                               const std::string& per) {
  const std::string parameter = per + "_normals";
  if (!path.empty() && matrix.rows() > 0)
    throw InputError(parameter + ": given both as a file ('" + path + "') and as a matrix; give one", parameter);
  Eigen::MatrixX3d n = path.empty() ? matrix : read_normals(path);
  const std::string name = path.empty() ? parameter : per + " normals file '" + path + "'";
  if ((!path.empty() || matrix.rows() > 0) && n.rows() != expected)
    throw InputError(name + ": " + std::to_string(n.rows()) + " rows, expected " + std::to_string(expected) +
                         " (one per " + per + ")",
                     parameter);
  return n;
}

}  // namespace

NormalFields resolve_normals(const SurfelMesh& mesh, NormalKind need, const NormalRequest& request,
                             const ImplicitShape* shape, const VoxelGrid* grid, const std::string& what) {
  NormalFields n;
  if (need == NormalKind::None) return n;
  n.face = given_normals(request.face_normals_file, request.face_normals, mesh.num_faces(), "face");
  n.vertex = given_normals(request.vertex_normals_file, request.vertex_normals, mesh.num_vertices(), "vertex");
  const bool need_vertex = need == NormalKind::Vertex;
  const bool have_all = need_vertex ? n.has_vertex() : n.has_face();
  const bool have_given = n.has_face() || n.has_vertex();
  // Auto with given normals: they decide. Without them, true for shapes, II for voxels.
  const NormalSource source = request.source == NormalSource::Auto && have_given
                                  ? NormalSource::Given
                                  : effective_normal_source(request.source, shape, grid);
  const bool estimates = source != NormalSource::Auto && source != NormalSource::Given;
  if (!have_all && !n.has_face() && estimates) {
    if (source == NormalSource::II && !(request.ii.k > 0.0 && std::isfinite(request.ii.k)))
      throw InputError(
          "II normals: the radius factor k = " + std::to_string(request.ii.k) + " must be positive and finite",
          "ii_radius");
    if (source == NormalSource::II && !std::isfinite(request.ii.alpha))
      throw InputError("II normals: the radius exponent alpha must be finite", "ii_alpha");
    n.face = estimate_face_normals(source, mesh, grid, shape, request.ii, request.progress);
  }
  if (need_vertex && !n.has_vertex() && source == NormalSource::Exact) {
    if (!shape) throw InputError("exact normals need an implicit shape", "normals");
    n.vertex = exact_vertex_normals(*shape, mesh);
  }
  // docs/math.md §1.5: vertex normals = normalized sum of the incident face normals (one definition).
  if (need_vertex && !n.has_vertex() && n.has_face())
    n.vertex = vertex_normals_from_face_normals(n.face, mesh.faces, mesh.num_vertices());
  if (need == NormalKind::Face && !n.has_face())
    throw InputError(what + " needs face normals: give face_normals or a normals source (true, ii, trivial)" +
                         (n.has_vertex() ? " (vertex normals do not give face normals)" : ""),
                     "face_normals");
  if (need_vertex && !n.has_vertex())
    throw InputError(
        what + " needs vertex normals: give vertex_normals, face_normals or a normals source (true, ii, trivial)",
        "vertex_normals");
  return n;
}

Eigen::MatrixX3d true_vertex_normals_from_faces(const ImplicitShape& shape, const SurfelMesh& mesh) {
  return vertex_normals_from_face_normals(true_face_normals(shape, mesh), mesh.faces, mesh.num_vertices());
}

Eigen::MatrixX3d exact_vertex_normals(const ImplicitShape& shape, const SurfelMesh& mesh) {
  return true_vertex_normals(shape, mesh);
}

}  // namespace corrlap
