#include "surface_quality.hpp"

#include <algorithm>
#include <cmath>
#include <corrlap/core/normal_fields.hpp>
#include <corrlap/estimators/corrected_curvature.hpp>
#include <corrlap/estimators/implicit_normals.hpp>
#include <numbers>

namespace corrlap {

Eigen::MatrixX3d geometric_vertex_normals(const SurfelMesh& mesh) {
  return vertex_normals_from_face_normals(mesh.face_normals_from_positions(), mesh.faces, mesh.num_vertices());
}

double surface_area(const SurfelMesh& mesh) {
  double area = 0.0;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Eigen::RowVector3d d0 = mesh.positions.row(mesh.faces(f, 2)) - mesh.positions.row(mesh.faces(f, 0));
    const Eigen::RowVector3d d1 = mesh.positions.row(mesh.faces(f, 3)) - mesh.positions.row(mesh.faces(f, 1));
    area += 0.5 * d0.cross(d1).norm();
  }
  return area;
}

double enclosed_volume(const SurfelMesh& mesh) {
  double six_volumes = 0.0;  // six times the volume, doubled by the two splits
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Eigen::RowVector3d a = mesh.positions.row(mesh.faces(f, 0)), b = mesh.positions.row(mesh.faces(f, 1)),
                             c = mesh.positions.row(mesh.faces(f, 2)), d = mesh.positions.row(mesh.faces(f, 3));
    // Triangles (a, b, c) + (a, c, d), and (b, c, d) + (b, d, a): a tetrahedron with the origin each.
    six_volumes += a.dot(b.cross(c)) + a.dot(c.cross(d)) + b.dot(c.cross(d)) + b.dot(d.cross(a));
  }
  return six_volumes / 12.0;
}

SurfaceQuality measure_against_shape(const SurfelMesh& mesh, const ImplicitShape& shape, double curvature_radius) {
  SurfaceQuality q;
  if (mesh.num_vertices() == 0) return q;
  q.distance_l1 = distances_to_surface(shape, mesh.positions).mean();
  const Eigen::MatrixX3d n = geometric_vertex_normals(mesh);
  const Eigen::MatrixX3d truth = true_vertex_normals(shape, mesh);
  double angles = 0.0;
  for (Eigen::Index v = 0; v < n.rows(); ++v) angles += std::acos(std::clamp(n.row(v).dot(truth.row(v)), -1.0, 1.0));
  q.normal_angle_deg = angles / double(n.rows()) * 180.0 / std::numbers::pi;
  const Eigen::VectorXd H = CorrectedCurvature::interpolated(mesh, n).mean_curvature_at_vertices(curvature_radius).H;
  q.mean_curvature_error = (H - true_mean_curvatures(shape, mesh.positions)).cwiseAbs().mean();
  return q;
}

}  // namespace corrlap
