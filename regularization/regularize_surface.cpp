#include "regularize_surface.hpp"

#include <algorithm>
#include <cmath>
#include <corrlap/backends/registry.hpp>
#include <corrlap/core/error.hpp>
#include <corrlap/core/mesh_topology.hpp>
#include <corrlap/core/stopwatch.hpp>
#include <corrlap/discretizations/registry.hpp>
#include <corrlap/estimators/corrected_curvature.hpp>
#include <numbers>
#include <optional>

namespace corrlap {

double regularization_size(const SurfelMesh& mesh) {
  if (mesh.num_vertices() == 0) return 0.0;
  return 0.5 * (mesh.positions.colwise().maxCoeff() - mesh.positions.colwise().minCoeff()).maxCoeff();
}

namespace {
double object_size(const SurfelMesh& mesh, const RegularizationOptions& o) {
  const double size = o.size ? *o.size : regularization_size(mesh);
  if (!(size > 0.0) || !std::isfinite(size)) throw InputError("regularization: the size must be positive");
  return size;
}
}  // namespace

RegularizationCurvature regularization_curvature(const SurfelMesh& mesh, const NormalFields& normals,
                                                 const RegularizationOptions& o) {
  if (!normals.has_vertex()) throw InputError("regularization: vertex normals are needed");
  RegularizationCurvature c;
  const double h = mesh.grid_step();
  c.size = object_size(mesh, o);
  c.curvature_radius = o.curvature_radius ? *o.curvature_radius : 0.1 * c.size;
  if (!(c.curvature_radius > 0.0)) throw InputError("regularization: the curvature radius must be positive");
  Stopwatch watch;
  // docs/math.md §9.2: H from the corrected curvature measures with the same normals (§8).
  // Principal edits need k1, k2 and their directions; H alone has a faster walk (equal results).
  const bool principal = o.k1_edit.active() || o.k2_edit.active();
  const CorrectedCurvature measures = CorrectedCurvature::interpolated(mesh, normals.vertex);
  CurvatureEstimates estimates;
  if (principal)
    estimates = measures.at_vertices(c.curvature_radius);
  else
    estimates.H = measures.mean_curvature_at_vertices(c.curvature_radius).H;
  c.H = estimates.H;
  for (Eigen::Index v = 0; v < c.H.size(); ++v)
    if (!std::isfinite(c.H[v]))
      throw NumericalError("regularization: the mean curvature of vertex " + std::to_string(v) +
                           " is not finite (is the curvature radius larger than the mesh?)");
  // A curvature radius below one voxel cannot be resolved: an estimate |H| > 1/h means the normals
  // are wrong there (II normals whose radius exceeds the shape's features). Solving with such H
  // moves the surface by many voxels, silently; refuse unless the user clamps H. (The check is on
  // the estimate, before the edits.)
  if (!o.h_clamp) {
    int absurd = 0;
    double worst = 0.0;
    for (Eigen::Index v = 0; v < c.H.size(); ++v)
      if (std::abs(c.H[v]) > 1.0 / h) {
        ++absurd;
        worst = std::max(worst, std::abs(c.H[v]));
      }
    if (absurd > 0)
      throw InputError("regularization: the mean curvature exceeds 1/h = " + std::to_string(1.0 / h) + " at " +
                           std::to_string(absurd) + " of " + std::to_string(c.H.size()) + " vertices (up to " +
                           std::to_string(worst) +
                           "): the normals are likely wrong there, e.g. II normals whose radius exceeds the shape's "
                           "features; give a smaller ii_radius, other normals, or h_clamp to clamp H",
                       "ii_radius");
  }
  c.normals = normals.vertex;
  if (principal) {
    // Paper §4.3: edit k1, k2 in S, integrate dn = S' into n', H' = tr(S') / 2 (curvature_editing.hpp).
    const std::vector<Eigen::Matrix3d> S =
        edited_shape_operators(estimates.k1, estimates.k2, estimates.d1, estimates.d2, o.k1_edit, o.k2_edit);
    auto integration_solver = make_linear_solver(o.solver, kDefaultLinearSolver);
    c.normals = integrate_shape_operator(mesh, S, normals.vertex, c.size, o.normal_attachment, *integration_solver);
    double angles = 0.0;
    for (Eigen::Index v = 0; v < c.H.size(); ++v) {
      c.H[v] = 0.5 * S[std::size_t(v)].trace();
      angles += std::acos(std::clamp(c.normals.row(v).dot(normals.vertex.row(v)), -1.0, 1.0));
    }
    c.normal_angle_change_deg = c.H.size() > 0 ? angles / double(c.H.size()) * 180.0 / std::numbers::pi : 0.0;
  }
  c.H *= o.h_scale;  // curvature editing (paper §4.3): scale, then clamp
  if (o.h_clamp) c.H = c.H.cwiseMax(-*o.h_clamp).cwiseMin(*o.h_clamp);
  c.seconds = watch.lap();
  return c;
}

RegularizedSurface regularize_surface(const SurfelMesh& mesh, const NormalFields& normals,
                                      const RegularizationOptions& o, const RegularizationCurvature* curvature) {
  // Options first: a bad name fails before the curvature and the assembly.
  auto solver = make_linear_solver(o.solver, kDefaultLinearSolver);
  auto method = make_discretization(o.method);
  const int boundary_edges = compute_mesh_info(mesh).boundary_edges;
  if (boundary_edges > 0)
    throw InputError("regularization: the surface is open (" + std::to_string(boundary_edges) +
                     " boundary edges); it is defined for closed surfaces");
  if (!normals.has_vertex()) throw InputError("regularization: vertex normals are needed");
  if (curvature && (curvature->H.size() != mesh.num_vertices() || curvature->normals.rows() != mesh.num_vertices()))
    throw InputError("regularization: the given curvature has " + std::to_string(curvature->H.size()) + " values for " +
                     std::to_string(mesh.num_vertices()) + " vertices");

  RegularizedSurface r;
  r.h = mesh.grid_step();
  if (o.alpha_step && !(*o.alpha_step > 0.0)) throw InputError("regularization: the alpha step must be positive");
  r.solver = o.solver.get_string("solver", kDefaultLinearSolver);
  std::optional<RegularizationCurvature> computed;
  if (!curvature) curvature = &computed.emplace(regularization_curvature(mesh, normals, o));
  r.size = curvature->size;
  r.curvature_radius = curvature->curvature_radius;
  r.alpha = regularization_alpha((o.alpha_step ? *o.alpha_step : r.h) * r.size, o.alpha0);
  r.H = curvature->H;
  r.normals = curvature->normals;
  r.normal_angle_change_deg = curvature->normal_angle_change_deg;
  r.curvature_seconds = computed ? curvature->seconds : 0.0;
  Stopwatch watch;

  Operators ops = method->assemble(mesh, normals, o.method_params);
  r.warnings = ops.warnings;
  if (ops.domain != Operators::Domain::Vertices)
    throw InputError("regularization: method '" + o.method +
                     "' defines operators on faces; positions live on vertices");
  r.operators_seconds = watch.lap();

  r.mesh = mesh;
  // With a direct backend, CG preconditioned by a factorization with L's pattern gives the normal
  // equations' solution at a fraction of the cost of factorizing L M_l^{-1} L (the header of
  // regularize_positions_preconditioned); it needs L negative semi-definite, else the direct solve.
  if (r.solver != "cg") {
    try {
      SolverReport cg;
      r.mesh.positions =
          regularize_positions_preconditioned(ops.L, ops.M, mesh.positions, r.normals, r.H, r.alpha, *solver, &cg);
      r.solve_scheme = "preconditioned-cg";
      r.solve_iterations = cg.iterations;
    } catch (const SolverError& e) {
      if (e.status() != SolverStatus::NotPositiveDefinite) throw;
      r.warnings.push_back("regularization: " + std::string(e.what()) +
                           "; L is not negative semi-definite, solved the normal equations directly");
    }
  }
  if (r.solve_scheme.empty()) {
    r.mesh.positions = regularize_positions(ops.L, ops.M, mesh.positions, r.normals, r.H, r.alpha, *solver);
    r.solve_scheme = "direct";
  }
  r.solve_seconds = watch.lap();
  r.energy_before = regularization_energy(ops.L, ops.M, mesh.positions, r.normals, r.H, mesh.positions);
  r.energy_after = regularization_energy(ops.L, ops.M, mesh.positions, r.normals, r.H, r.mesh.positions);
  return r;
}

}  // namespace corrlap
