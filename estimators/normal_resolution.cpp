#include "normal_resolution.hpp"

#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/core/mesh_topology.hpp>
#include <corrlap/estimators/implicit_normals.hpp>
#include <corrlap/io/text_io.hpp>
#include <limits>
#include <sstream>

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

namespace detail {

// A vertex whose II face normals cancel out has no normal. When the II ball reaches across the part
// the vertex lies on (a radius of at least half its thinnest side), it sees the whole part, whose
// covariance has no preferred direction: the message names the radius in voxels and the part's size
// so that the user knows which radius to give. A smaller ball is not the cause, and the message
// says so instead of asking for a radius the user already has.
void check_ii_vertex_normals(const SurfelMesh& mesh, const Eigen::MatrixX3d& vertex_normals, const IIParams& ii) {
  Eigen::Index bad = -1;
  for (Eigen::Index v = 0; v < vertex_normals.rows() && bad < 0; ++v)
    if (!(vertex_normals.row(v).squaredNorm() > 0.0)) bad = v;
  if (bad < 0) return;
  int count = 0;
  for (Eigen::Index v = 0; v < vertex_normals.rows(); ++v) count += !(vertex_normals.row(v).squaredNorm() > 0.0);
  // The component (faces joined by vertices) of the first such vertex, and its bounding box.
  int components = 0;
  const std::vector<int> component = face_components(mesh, components);
  int c = -1;
  for (int f = 0; f < mesh.num_faces() && c < 0; ++f)
    for (int j = 0; j < 4; ++j)
      if (mesh.faces(f, j) == int(bad)) c = component[std::size_t(f)];
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (int f = 0; f < mesh.num_faces(); ++f)
    if (component[std::size_t(f)] == c)
      for (int j = 0; j < 4; ++j) {
        lo = lo.cwiseMin(mesh.positions.row(mesh.faces(f, j)).transpose());
        hi = hi.cwiseMax(mesh.positions.row(mesh.faces(f, j)).transpose());
      }
  const double h = mesh.grid_step();
  const Eigen::Vector3d extent = (hi - lo) / h;
  const double radius = ii_digital_radius(h, ii);
  std::ostringstream os;
  os << "II normals: the normal of vertex " << bad << " (and of " << count - 1
     << " other vertices) is the zero vector: the II normals of its faces cancel out";
  if (radius >= 0.5 * extent.minCoeff()) {
    os << " because the II radius, " << radius << " voxels, exceeds the part it lies on (" << extent.x() << " x "
       << extent.y() << " x " << extent.z() << " voxels, " << extent.minCoeff()
       << " across at its thinnest); give a smaller ii_radius (a radius below " << 0.5 * extent.minCoeff()
       << " voxels; with alpha = " << ii.alpha << ", k is the radius in units of h^alpha)";
    throw InputError(os.str(), "ii_radius");
  }
  os << ", although the II radius, " << radius << " voxels, is less than half the part it lies on (" << extent.x()
     << " x " << extent.y() << " x " << extent.z()
     << " voxels), so the radius is not what makes them cancel: the faces around the vertex have "
        "II normals pointing in opposite directions; try another ii_radius, or give the normals another way (the "
        "trivial or convolved source, or a normals file)";
  throw InputError(os.str(), "normals");
}

}  // namespace detail

void check_ii_params(const IIParams& ii) {
  if (!(ii.k > 0.0 && std::isfinite(ii.k)))
    throw InputError("II normals: the radius factor k = " + std::to_string(ii.k) + " must be positive and finite",
                     "ii_radius");
  if (!std::isfinite(ii.alpha)) throw InputError("II normals: the radius exponent alpha must be finite", "ii_alpha");
}

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
  const IIParams ii = request.ii ? *request.ii : default_ii_params(shape != nullptr);
  bool ii_estimated = false;
  if (!have_all && !n.has_face() && estimates) {
    if (source == NormalSource::II) check_ii_params(ii);
    n.face = estimate_face_normals(source, mesh, grid, shape, ii, request.progress);
    ii_estimated = source == NormalSource::II;
  }
  if (need_vertex && !n.has_vertex() && source == NormalSource::Exact) {
    if (!shape) throw InputError("exact normals need an implicit shape", "normals");
    n.vertex = exact_vertex_normals(*shape, mesh);
  }
  // docs/math.md §1.5: vertex normals = normalized sum of the incident face normals (one definition).
  if (need_vertex && !n.has_vertex() && n.has_face()) {
    n.vertex = vertex_normals_from_face_normals(n.face, mesh.faces, mesh.num_vertices());
    if (ii_estimated) detail::check_ii_vertex_normals(mesh, n.vertex, ii);
  }
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
