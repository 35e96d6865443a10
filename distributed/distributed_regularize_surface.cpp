#include "distributed_regularize_surface.hpp"

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/core/stopwatch.hpp>
#include <corrlap/regularization/surface_quality.hpp>
#include <limits>
#include <string>

#include "distributed_curvature.hpp"
#include "distributed_regularization.hpp"

namespace corrlap {

namespace {

double sum_over_ranks(double x) {
  MPI_Allreduce(MPI_IN_PLACE, &x, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  return x;
}

}  // namespace

DistributedRegularizedSurface distributed_regularize_surface(const DistributedProblem& problem,
                                                             const RegularizationOptions& o, bool voxels_from_file,
                                                             PetscLinearSolver& solver) {
  // What is not distributed, before any computation (the same on every rank).
  if (o.method != "fem" || !o.method_params.empty())
    throw InputError("distributed regularization: only the method fem with its default parameters is distributed");
  if (o.solver.get_string("solver", "petsc") != "petsc")
    throw InputError("distributed regularization: only the petsc solver is distributed");
  if (o.k1_edit.active() || o.k2_edit.active())
    throw InputError("distributed regularization: principal curvature edits are not distributed");
  if (o.alpha0 == 0.0) throw InputError("distributed regularization: the unattached solve is not distributed");
  check_regularization_options(o);

  const DistributedSurface& s = problem.surface();
  const Eigen::Index n = s.num_owned;
  const double h = s.mesh.h;
  const Eigen::MatrixX3d p = s.mesh.positions.topRows(n);
  // The whole surface's extremes, its area and largest coordinate, as sums and extrema over the ranks.
  Eigen::RowVector3d lo = Eigen::RowVector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  if (n > 0) lo = p.colwise().minCoeff(), hi = p.colwise().maxCoeff();
  MPI_Allreduce(MPI_IN_PLACE, lo.data(), 3, MPI_DOUBLE, MPI_MIN, MPI_COMM_WORLD);
  MPI_Allreduce(MPI_IN_PLACE, hi.data(), 3, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  double reach = n > 0 ? p.cwiseAbs().maxCoeff() : 0.0;
  MPI_Allreduce(MPI_IN_PLACE, &reach, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  const double area = sum_over_ranks(surface_area(s.mesh));  // each face on one rank

  DistributedRegularizedSurface r;
  r.size = o.size ? *o.size : 0.5 * (hi - lo).maxCoeff();
  if (!(r.size > 0.0) || !std::isfinite(r.size))
    throw InputError("regularization: the object size must be a positive number", "size");
  const double alpha_step = o.alpha_step ? *o.alpha_step : h;
  const double scale = alpha_step * r.size;
  r.alpha0 = o.alpha0;
  r.alpha = regularization_alpha(scale, o.alpha0);
  if (r.alpha > max_regularization_alpha(area, reach))
    throw InputError("regularization: alpha0 = " + std::to_string(o.alpha0) +
                         " is beyond what the solve represents in double precision on this surface",
                     "alpha0");

  // docs/math.md §9.2: H from the corrected curvature measures, walked at sites (§8.4) per slab.
  Stopwatch watch;
  r.curvature_radius = o.curvature_radius ? *o.curvature_radius : default_curvature_radius(r.size, h, voxels_from_file);
  const double spacing = o.curvature_spacing * r.curvature_radius;
  const NearSlabNormals near = problem.near_slab(curvature_halo_columns(r.curvature_radius, spacing, h));
  r.H = distributed_mean_curvature(s, near, r.curvature_radius, spacing);
  int finite = r.H.allFinite() ? 1 : 0;
  MPI_Allreduce(MPI_IN_PLACE, &finite, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  if (!finite)
    throw NumericalError(
        "regularization: the mean curvature is not finite at some vertex (is the curvature "
        "radius larger than the mesh?)");
  if (!o.h_clamp) {
    double absurd = 0.0, worst = 0.0;
    for (Eigen::Index v = 0; v < n; ++v)
      if (std::abs(r.H[v]) > 1.0 / h) absurd += 1.0, worst = std::max(worst, std::abs(r.H[v]));
    absurd = sum_over_ranks(absurd);
    MPI_Allreduce(MPI_IN_PLACE, &worst, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    check_curvature_resolvable(std::int64_t(absurd), s.num_vertices, worst, h, (hi - lo).norm() / h);
  }
  r.H *= o.h_scale;  // curvature editing (paper §4.3): scale, then clamp
  if (o.h_clamp) r.H = r.H.cwiseMax(-*o.h_clamp).cwiseMin(*o.h_clamp);
  r.curvature_seconds = watch.lap();

  // The solves: one per alpha0 tried, each later one from the last one's positions.
  const Eigen::MatrixX3d& normals = problem.vertex_normals();
  const double accuracy = o.solve_accuracy * h;
  std::vector<DistributedRegularization> solved;
  const auto solve_at = [&](double alpha) {
    const Eigen::MatrixX3d* start = solved.empty() ? nullptr : &solved.back().positions;
    solved.push_back(
        distributed_regularize_positions(s, problem.fem(), p, normals, r.H, alpha, solver, accuracy, start));
  };
  solve_at(r.alpha);
  const bool edited = o.h_scale != 1.0 || o.h_clamp.has_value();
  if (o.alpha0_auto && !edited) {
    // docs/math.md §9.4, as regularize_surface.
    // M's row sums at the owned rows.
    Eigen::VectorXd mass = Eigen::VectorXd::Zero(n);
    for (const DistributedFem::Entry& e : problem.fem().owned_entries(DistributedFem::Which::M))
      mass[Eigen::Index(e.row - s.row_begin)] += e.value;
    const auto bias_of = [&](const Eigen::MatrixX3d& q) {
      return distributed_attachment_bias(s, p, q, normals, mass, alpha_step);
    };
    r.alpha0_trials.push_back({r.alpha0, bias_of(solved.back().positions)});
    const double largest = std::min(alpha0_for_wavelength(kAutoAlpha0MinWavelength, r.size / alpha_step),
                                    max_regularization_alpha(area, reach) * scale * scale);
    for (double next = next_alpha0(r.alpha0_trials, kAttachmentBiasLimit, largest); next > 0.0;
         next = next_alpha0(r.alpha0_trials, kAttachmentBiasLimit, largest)) {
      solve_at(regularization_alpha(scale, next));
      r.alpha0_trials.push_back({next, bias_of(solved.back().positions)});
    }
    const std::size_t kept = chosen_alpha0_trial(r.alpha0_trials);
    r.alpha0 = r.alpha0_trials[kept].alpha0;
    r.alpha = regularization_alpha(scale, r.alpha0);
    solved.resize(kept + 1);
  }
  r.positions = std::move(solved.back().positions);
  r.solve_iterations = solved.back().iterations;
  r.solve_error_bound = solved.back().error_bound / h;
  r.solve_residual = solved.back().residual;
  r.solve_seconds = watch.lap();
  r.energy_before = distributed_regularization_energy(s, problem.fem(), p, normals, r.H, p);
  r.energy_after = distributed_regularization_energy(s, problem.fem(), p, normals, r.H, r.positions);
  return r;
}

}  // namespace corrlap
