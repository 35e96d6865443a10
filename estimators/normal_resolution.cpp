#include "normal_resolution.hpp"

#include <corrlap/core/error.hpp>
#include <corrlap/estimators/implicit_normals.hpp>
#include <corrlap/estimators/normal_estimation.hpp>
#include <corrlap/io/text_io.hpp>

namespace corrlap {

NormalSource parse_normal_source(const std::string& name) {
  if (name == "auto") return NormalSource::Auto;
  if (name == "true") return NormalSource::True;
  if (name == "ii") return NormalSource::II;
  if (name == "trivial") return NormalSource::Trivial;
  if (name == "convolved") return NormalSource::ConvolvedTrivial;
  throw InputError("unknown normal source '" + name + "' (valid: auto, true, ii, trivial, convolved)");
}

const char* to_string(NormalSource source) {
  switch (source) {
    case NormalSource::Auto:
      return "auto";
    case NormalSource::True:
      return "true";
    case NormalSource::II:
      return "ii";
    case NormalSource::Trivial:
      return "trivial";
    case NormalSource::ConvolvedTrivial:
      return "convolved";
  }
  return "?";
}

NormalSource effective_normal_source(NormalSource source, const ImplicitShape* shape, const VoxelGrid* grid) {
  if (source != NormalSource::Auto) return source;
  if (shape) return NormalSource::True;
  if (grid) return NormalSource::II;
  return NormalSource::Auto;
}

namespace {
Eigen::MatrixX3d read_normals_file(const std::string& path, Eigen::Index expected, const char* per) {
  Eigen::MatrixX3d n = read_normals(path);
  if (n.rows() != expected)
    throw InputError(std::string(per) + " normals file '" + path + "': " + std::to_string(n.rows()) +
                     " rows, expected " + std::to_string(expected) + " (one per " + per + ")");
  return n;
}
}  // namespace

NormalFields resolve_normals(const SurfelMesh& mesh, NormalKind need, const NormalRequest& request,
                             const ImplicitShape* shape, const VoxelGrid* grid, const std::string& what) {
  NormalFields n;
  if (need == NormalKind::None) return n;
  if (!request.face_normals_file.empty())
    n.face = read_normals_file(request.face_normals_file, mesh.num_faces(), "face");
  if (!request.vertex_normals_file.empty())
    n.vertex = read_normals_file(request.vertex_normals_file, mesh.num_vertices(), "vertex");
  const bool need_vertex = need == NormalKind::Vertex;
  const bool have_all = need_vertex ? n.has_vertex() : n.has_face();
  const bool have_files = n.has_face() || n.has_vertex();
  // Auto with a file: the file decides. Without one, true for shapes, II for voxels.
  const NormalSource source = request.source == NormalSource::Auto && have_files
                                  ? NormalSource::Auto
                                  : effective_normal_source(request.source, shape, grid);
  if (!have_all && !n.has_face() && source != NormalSource::Auto) {
    NormalEstimator estimator = NormalEstimator::Trivial;
    if (source == NormalSource::True) estimator = NormalEstimator::True;
    if (source == NormalSource::II) estimator = NormalEstimator::II;
    if (source == NormalSource::ConvolvedTrivial) estimator = NormalEstimator::ConvolvedTrivial;
    n.face = estimate_face_normals(estimator, mesh, grid, shape, request.ii, request.progress);
  }
  // docs/math.md §1.5: vertex normals = normalized sum of the incident face normals (one definition).
  if (need_vertex && !n.has_vertex() && n.has_face())
    n.vertex = vertex_normals_from_face_normals(n.face, mesh.faces, mesh.num_vertices());
  if (need == NormalKind::Face && !n.has_face())
    throw InputError(what + " needs face normals: give --face-normals FILE or --normals true|ii|trivial" +
                     (n.has_vertex() ? " (vertex normals do not give face normals)" : ""));
  if (need_vertex && !n.has_vertex())
    throw InputError(
        what + " needs vertex normals: give --vertex-normals FILE, --face-normals FILE or --normals true|ii|trivial");
  return n;
}

Eigen::MatrixX3d true_vertex_normals_from_faces(const ImplicitShape& shape, const SurfelMesh& mesh) {
  return vertex_normals_from_face_normals(true_face_normals(shape, mesh), mesh.faces, mesh.num_vertices());
}

Eigen::MatrixX3d exact_vertex_normals(const ImplicitShape& shape, const SurfelMesh& mesh) {
  return true_vertex_normals(shape, mesh);
}

}  // namespace corrlap
