#pragma once
// The Poisson problem of `corrlap solve` (docs/math.md §10.4: L g = M b with the compatibility
// projection and vertex 0 pinned) on a DistributedFem, solved by the petsc backend with any of its
// options (MUMPS's Cholesky by default, CG + GAMG or hypre, ...). The right-hand side, the solution
// and the error norms live on the owned vertices of each rank.
#include <Eigen/Core>
#include <corrlap/backends/petsc.hpp>
#include <corrlap/core/linear_solver.hpp>
#include <corrlap/problems/problems.hpp>
#include <corrlap/problems/test_functions.hpp>

#include "distributed_fem.hpp"

namespace corrlap {

struct DistributedPoissonResult {
  Eigen::VectorXd g;      ///< num_owned: the solution at this rank's owned vertices, g = f at vertex 0
  double residual = 0.0;  ///< |L g - M b_c| / |M b_c| without the pinned row (neumann_residual)
  ErrorNorms errors;      ///< poisson_errors: g against the exact f, both M-mean-free
  SolverReport report;    ///< the solver's: times, iterations, its residual on the pinned system, status
};

/// solve_poisson (problems.hpp) on the distributed operators: b = Delta f at the radial projections
/// of the owned vertices onto the unit sphere around `center`. `solver` is configured by the caller
/// (so that a bad option fails before the assembly) and keeps the pinned matrix for more solves.
/// A failure is the solver's SolverError, thrown on every rank. Collective.
DistributedPoissonResult distributed_solve_poisson(const DistributedSurface& surface, const DistributedFem& fem,
                                                   const TestFunction& function, PetscLinearSolver& solver,
                                                   const Eigen::Vector3d& center = Eigen::Vector3d::Zero());

/// The values of the owned vertices of every rank (#owned each), on rank 0 in serial vertex order
/// (#V); empty on the other ranks. Collective. For checks on small surfaces: the commands write
/// per rank (distributed_mesh_output.hpp).
Eigen::VectorXd gather_on_rank0(const DistributedSurface& surface, const Eigen::VectorXd& owned_values);

}  // namespace corrlap
