#pragma once
// regularize_surface (regularization/regularize_surface.hpp) on the distributed front end: the
// mean curvature per slab, the normal equations solved over the ranks and the automatic alpha0's
// trials, every vector at the owned vertices (docs/distributed.md, "Regularizing per slab").
#include <Eigen/Core>
#include <corrlap/backends/petsc.hpp>
#include <corrlap/regularization/regularize_surface.hpp>
#include <string>
#include <vector>

#include "distributed_problem.hpp"

namespace corrlap {

struct DistributedRegularizedSurface {
  Eigen::MatrixX3d positions;  ///< num_owned x 3: p' at the owned vertices (world units)
  Eigen::VectorXd H;           ///< num_owned: the mean curvature used, after the edits
  double size = 1.0, curvature_radius = 0.0, alpha0 = 10.0, alpha = 0.0;
  std::vector<Alpha0Trial> alpha0_trials;  ///< as RegularizedSurface::alpha0_trials
  int solve_iterations = 0;                ///< CG iterations of the solve kept
  double solve_error_bound = 0.0;          ///< in steps of h, as RegularizedSurface's
  double solve_residual = 0.0;
  double curvature_seconds = 0.0, solve_seconds = 0.0;
  RegularizationEnergy energy_before, energy_after;  ///< at the input and at the result
};

/// regularize_surface(mesh, normals, options) of the whole surface, at the owned vertices of
/// `problem`: its method ("fem", consistent mass lumped) and normals, H walked at sites per slab
/// (distributed_curvature.hpp), the normal equations by distributed_regularize_positions with
/// `solver` (a direct petsc solver), alpha0 chosen as docs/math.md §9.4 with
/// distributed_attachment_bias. `voxels_from_file`: the curvature radius's default as for voxels
/// read from a file (default_curvature_radius). Equal to the serial result to the solve's
/// accuracy (to rounding with solve_accuracy 0).
///
/// Throws InputError, on every rank alike, for options the serial regularize_surface refuses, and
/// for what is not distributed (another method or method parameters, a solver other than petsc,
/// principal curvature edits): the caller then runs the serial front end. NumericalError as
/// regularize_surface for a non-finite H; SolverError from the solve. Collective.
DistributedRegularizedSurface distributed_regularize_surface(const DistributedProblem& problem,
                                                             const RegularizationOptions& options,
                                                             bool voxels_from_file, PetscLinearSolver& solver);

}  // namespace corrlap
