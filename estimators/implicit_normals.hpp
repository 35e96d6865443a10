#pragma once
// True normals of implicit shapes (docs/math.md §1.5): exact radial normals on spheres, otherwise the
// gradient at the projection of the point onto {P = 0} by a damped Newton iteration.
#include <Eigen/Core>
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/surface/implicit_shape.hpp>

namespace corrlap {

/// Damped Newton projection onto {P = 0} (docs/math.md §1.5; reference defaults).
struct ProjectionParams {
  int max_iterations = 20;
  double accuracy = 1e-4;
  double gamma = 0.5;
};

/// Projection of x onto the zero level set of the shape.
Eigen::Vector3d project_onto_surface(const ImplicitShape& shape, const Eigen::Vector3d& x,
                                     const ProjectionParams& params = {});

/// Unit outward normal of the shape "at" x: radial for spheres, else grad P at the projection.
Eigen::Vector3d true_normal(const ImplicitShape& shape, const Eigen::Vector3d& x, const ProjectionParams& params = {});

/// True normal at every face centroid (#F x 3).
Eigen::MatrixX3d true_face_normals(const ImplicitShape& shape, const SurfelMesh& mesh,
                                   const ProjectionParams& params = {});
/// True normal at every vertex (#V x 3).
Eigen::MatrixX3d true_vertex_normals(const ImplicitShape& shape, const SurfelMesh& mesh,
                                     const ProjectionParams& params = {});

/// Distance from each point (#P x 3) to the zero level set: exact on spheres, else |x - p(x)| with
/// the Newton projection run to |P| < 1e-12 (the reference's 1e-4 would dominate the distances of
/// regularized surfaces, ~1e-3 h). Used to measure surfaces, not by the operators.
Eigen::VectorXd distances_to_surface(const ImplicitShape& shape, const Eigen::MatrixX3d& points);

/// Mean curvature of the level set at the projection of each point (#P x 3), with outward normals
/// (the unit sphere has H = 1, so that Delta x = -2 H n): H = (|g|^2 tr(D^2P) - g^T D^2P g) / (2 |g|^3),
/// g = grad P, half the divergence of the unit normal field.
Eigen::VectorXd true_mean_curvatures(const ImplicitShape& shape, const Eigen::MatrixX3d& points);

}  // namespace corrlap
