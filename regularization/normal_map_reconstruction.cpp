#include "normal_map_reconstruction.hpp"

#include <algorithm>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/core/mesh_topology.hpp>
#include <corrlap/regularization/surface_quality.hpp>
#include <numbers>
#include <string>

namespace corrlap {

SurfelMesh subdivide_quads(const SurfelMesh& mesh, int levels) {
  if (levels < 0 || levels > 6)
    throw InputError("subdivide_quads: " + std::to_string(levels) + " levels (expected 0 to 6: 4^6 quads per face)");
  mesh.validate("subdivide_quads");
  if (levels == 0) return mesh;
  const int s = 1 << levels;
  const EdgeTopology topology = build_edges(mesh);
  const int V = mesh.num_vertices(), E = topology.num_edges(), F = mesh.num_faces();
  const Eigen::Index edge_base = V, face_base = V + Eigen::Index(E) * (s - 1);
  SurfelMesh out;
  out.h = mesh.h > 0 ? mesh.h / s : 0.0;
  out.positions.resize(face_base + Eigen::Index(F) * (s - 1) * (s - 1), 3);
  out.positions.topRows(V) = mesh.positions;
  for (int e = 0; e < E; ++e) {
    const Eigen::RowVector3d a = mesh.positions.row(topology.edges(e, 0)), b = mesh.positions.row(topology.edges(e, 1));
    for (int k = 1; k < s; ++k)
      out.positions.row(edge_base + Eigen::Index(e) * (s - 1) + (k - 1)) = a + (b - a) * (double(k) / s);
  }
  out.faces.resize(Eigen::Index(F) * s * s, 4);
  for (int f = 0; f < F; ++f) {
    const Eigen::RowVector3d c0 = mesh.positions.row(mesh.faces(f, 0)), c1 = mesh.positions.row(mesh.faces(f, 1)),
                             c2 = mesh.positions.row(mesh.faces(f, 2)), c3 = mesh.positions.row(mesh.faces(f, 3));
    const Eigen::Index inner = face_base + Eigen::Index(f) * (s - 1) * (s - 1);
    for (int j = 1; j < s; ++j)
      for (int i = 1; i < s; ++i) {
        const double u = double(i) / s, v = double(j) / s;
        out.positions.row(inner + Eigen::Index(j - 1) * (s - 1) + (i - 1)) =
            (1 - u) * (1 - v) * c0 + u * (1 - v) * c1 + u * v * c2 + (1 - u) * v * c3;
      }
    // The index of grid point (i, j) of face f: corner (0,0) = c0, (s,0) = c1, (s,s) = c2, (0,s) = c3.
    // A point on local edge m (corner m -> m+1) at k steps from corner m is the edge's point k
    // counted from its smaller vertex when the face runs along it (sign +1), else s - k.
    const auto on_edge = [&](int m, int k) -> int {
      const int e = topology.face_edges(f, m);
      const int from_min = topology.face_edge_signs(f, m) > 0 ? k : s - k;
      return int(edge_base + Eigen::Index(e) * (s - 1) + (from_min - 1));
    };
    const auto index = [&](int i, int j) -> int {
      if (j == 0) return i == 0 ? mesh.faces(f, 0) : i == s ? mesh.faces(f, 1) : on_edge(0, i);
      if (j == s) return i == 0 ? mesh.faces(f, 3) : i == s ? mesh.faces(f, 2) : on_edge(2, s - i);
      if (i == s) return on_edge(1, j);
      if (i == 0) return on_edge(3, s - j);
      return int(inner + Eigen::Index(j - 1) * (s - 1) + (i - 1));
    };
    for (int j = 0; j < s; ++j)
      for (int i = 0; i < s; ++i)
        out.faces.row(Eigen::Index(f) * s * s + j * s + i) << index(i, j), index(i + 1, j), index(i + 1, j + 1),
            index(i, j + 1);
  }
  return out;
}

Eigen::MatrixX3d triangle_mesh_vertex_normals(const Eigen::MatrixX3d& V, const TriangleIndices& T) {
  Eigen::MatrixX3d n = Eigen::MatrixX3d::Zero(V.rows(), 3);
  for (Eigen::Index t = 0; t < T.rows(); ++t) {
    const Eigen::Vector3d a = V.row(T(t, 0)), b = V.row(T(t, 1)), c = V.row(T(t, 2));
    const Eigen::RowVector3d w = (b - a).cross(c - a).transpose();  // twice the area times the unit normal
    for (int k = 0; k < 3; ++k) n.row(T(t, k)) += w;
  }
  for (Eigen::Index v = 0; v < n.rows(); ++v) {
    const double len = n.row(v).norm();
    if (len > 0) n.row(v) /= len;
  }
  return n;
}

namespace {
Eigen::MatrixX3d interpolate_normals(const TriangleLocator& fine, const Eigen::MatrixX3d& N, const TriangleIndices& T,
                                     const Eigen::MatrixX3d& points, const char* what) {
  const std::vector<ClosestPoint> cp = closest_points(fine, points);
  Eigen::MatrixX3d n(points.rows(), 3);
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    const ClosestPoint& c = cp[std::size_t(i)];
    Eigen::RowVector3d m = Eigen::RowVector3d::Zero();
    for (int k = 0; k < 3; ++k) m += c.barycentric[k] * N.row(T(c.triangle, k));
    const double len = m.norm();
    if (!(len > 1e-9))
      throw NumericalError(std::string("normal map: the interpolated normal at ") + what + " " + std::to_string(i) +
                           " vanishes (the fine mesh folds back there)");
    n.row(i) = m / len;
  }
  return n;
}

// One normal per vertex of the fine mesh, or a named error.
void check_normal_count(const TriangleLocator& fine, const Eigen::MatrixX3d& fine_vertex_normals) {
  if (fine_vertex_normals.rows() != fine.vertices().rows())
    throw InputError("normal map: " + std::to_string(fine_vertex_normals.rows()) + " normals for " +
                     std::to_string(fine.vertices().rows()) + " vertices of the fine mesh");
}
}  // namespace

NormalFields sample_normal_map(const SurfelMesh& mesh, const TriangleLocator& fine,
                               const Eigen::MatrixX3d& fine_vertex_normals) {
  check_normal_count(fine, fine_vertex_normals);
  NormalFields out;
  out.vertex = interpolate_normals(fine, fine_vertex_normals, fine.triangles(), mesh.positions, "vertex");
  out.face = interpolate_normals(fine, fine_vertex_normals, fine.triangles(), mesh.face_centroids(), "face");
  return out;
}

DistanceToMesh distance_to_mesh(const SurfelMesh& mesh, const TriangleLocator& fine) {
  DistanceToMesh d;
  const std::vector<ClosestPoint> cp = closest_points(fine, mesh.positions);
  for (const ClosestPoint& c : cp) {
    d.mean += c.distance;
    d.max = std::max(d.max, c.distance);
  }
  if (!cp.empty()) d.mean /= double(cp.size());
  return d;
}

double normal_angle_to_map(const SurfelMesh& mesh, const TriangleLocator& fine,
                           const Eigen::MatrixX3d& fine_vertex_normals) {
  if (mesh.num_vertices() == 0) return 0.0;
  check_normal_count(fine, fine_vertex_normals);
  const Eigen::MatrixX3d map =
      interpolate_normals(fine, fine_vertex_normals, fine.triangles(), mesh.positions, "vertex");
  const Eigen::MatrixX3d own = geometric_vertex_normals(mesh);
  double sum = 0.0;
  for (Eigen::Index v = 0; v < own.rows(); ++v) sum += std::acos(std::clamp(own.row(v).dot(map.row(v)), -1.0, 1.0));
  return sum / double(own.rows()) * 180.0 / std::numbers::pi;
}

}  // namespace corrlap
