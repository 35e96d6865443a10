#pragma once
// Problems shared by every backend: Dirichlet conditions and the pure-Neumann Poisson problem of
// spec §10.4 on a closed surface. L is negative semi-definite (spec §0); the systems handed to the
// LinearSolver are the SPD matrices -L restricted to the free vertices.
#include <vector>

#include <Eigen/Core>
#include <Eigen/Sparse>

#include <corrlap/core/linear_solver.hpp>

namespace corrlap {

/// Solves L u = M f on the free vertices with u[fixed[i]] = values[i]. Throws InputError for
/// out-of-range or repeated vertices, a size mismatch, or no free vertex; SolverError from the
/// solver (e.g. not positive definite when a connected component has no fixed vertex). No fixed
/// vertex at all is an InputError (L 1 = 0 makes the system singular).
Eigen::VectorXd solve_dirichlet(const Eigen::SparseMatrix<double>& L, const Eigen::SparseMatrix<double>& M,
                                const Eigen::VectorXd& f, const std::vector<int>& fixed,
                                const Eigen::VectorXd& values, LinearSolver& solver);

/// M-weighted mean 1^T M v / 1^T M 1.
double mass_weighted_mean(const Eigen::SparseMatrix<double>& M, const Eigen::VectorXd& v);

/// Pure-Neumann Poisson problem of spec §10.4: given b (samples of the Laplacian), project it onto
/// the compatible right-hand sides (b <- b - mean_M(b) 1), solve L g = M b with vertex `pin`
/// fixed to `pin_value`, and return g.
Eigen::VectorXd solve_neumann_poisson(const Eigen::SparseMatrix<double>& L, const Eigen::SparseMatrix<double>& M,
                                      const Eigen::VectorXd& b, LinearSolver& solver, double pin_value = 0.0,
                                      int pin = 0);

/// Errors of spec §10.4: e = (g - mean_M g) - (f - mean_M f); L_inf = max |e|,
/// L_2 = sqrt(e^T M e / 1^T M 1).
struct PoissonErrors {
  double linf = 0.0;
  double l2 = 0.0;
};
PoissonErrors poisson_errors(const Eigen::SparseMatrix<double>& M, const Eigen::VectorXd& g, const Eigen::VectorXd& f);

}  // namespace corrlap
