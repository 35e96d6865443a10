#pragma once
// Problems shared by every backend: Dirichlet conditions, the pure-Neumann Poisson problem of
// docs/math.md §10.4 on a closed surface (backward evaluation) and the forward evaluation of docs/math.md §10.3,
// with their error norms. L is negative semi-definite (docs/math.md §0); the systems handed to the
// LinearSolver are SPD: -L restricted to the free vertices, or M - dt L.
#include <Eigen/Core>
#include <Eigen/Sparse>
#include <corrlap/core/discretization.hpp>
#include <corrlap/core/linear_solver.hpp>
#include <corrlap/problems/test_functions.hpp>
#include <vector>

namespace corrlap {

/// Solves L u = M f on the free vertices with u[fixed[i]] = values[i]. Throws InputError for
/// out-of-range or repeated vertices, a size mismatch, or no free vertex; SolverError from the
/// solver (e.g. not positive definite when a connected component has no fixed vertex). No fixed
/// vertex at all is an InputError (L 1 = 0 makes the system singular). `positions` (#V x 3, the
/// vertices'), when given, is the solver's ordering hint (LinearSolver::set_positions); the same
/// holds for the functions below.
Eigen::VectorXd solve_dirichlet(const Eigen::SparseMatrix<double>& L, const Eigen::SparseMatrix<double>& M,
                                const Eigen::VectorXd& f, const std::vector<int>& fixed, const Eigen::VectorXd& values,
                                LinearSolver& solver, const Eigen::MatrixX3d* positions = nullptr);

/// The SPD matrix solve_neumann_poisson factorizes: -L without row and column `pin` ((#V-1) x
/// (#V-1), the rows and columns after `pin` shifted up by one). Built in place, without triplets.
Eigen::SparseMatrix<double> pinned_system(const Eigen::SparseMatrix<double>& L, int pin = 0);

/// M-weighted mean 1^T M v / 1^T M 1.
double mass_weighted_mean(const Eigen::SparseMatrix<double>& M, const Eigen::VectorXd& v);

/// Pure-Neumann Poisson problem of docs/math.md §10.4: given b (samples of the Laplacian), project it onto
/// the compatible right-hand sides (b <- b - mean_M(b) 1), solve L g = M b with vertex `pin`
/// fixed to `pin_value`, and return g.
Eigen::VectorXd solve_neumann_poisson(const Eigen::SparseMatrix<double>& L, const Eigen::SparseMatrix<double>& M,
                                      const Eigen::VectorXd& b, LinearSolver& solver, double pin_value = 0.0,
                                      int pin = 0, const Eigen::MatrixX3d* positions = nullptr);

/// solve_neumann_poisson for several right-hand sides at once (#V x k columns of B, one pin value
/// per column): one factorization, k solves. Column j equals solve_neumann_poisson(L, M, B.col(j),
/// solver, pin_values[j], pin) up to the rounding of the multi-column solve.
Eigen::MatrixXd solve_neumann_poisson_columns(const Eigen::SparseMatrix<double>& L,
                                              const Eigen::SparseMatrix<double>& M, const Eigen::MatrixXd& B,
                                              LinearSolver& solver, const Eigen::VectorXd& pin_values, int pin = 0,
                                              const Eigen::MatrixX3d* positions = nullptr);

/// Norms of an error vector e of docs/math.md §10.3/§10.4: L_inf = max |e|, L_2 = sqrt(e^T M e / 1^T M 1).
struct ErrorNorms {
  double linf = 0.0;
  double l2 = 0.0;
};
using PoissonErrors = ErrorNorms;
ErrorNorms error_norms(const Eigen::SparseMatrix<double>& M, const Eigen::VectorXd& e);

/// Backward errors of docs/math.md §10.4, the mean removed: norms of e = (g - mean_M g) - (f - mean_M f).
PoissonErrors poisson_errors(const Eigen::SparseMatrix<double>& M, const Eigen::VectorXd& g, const Eigen::VectorXd& f);

/// Relative residual |L g - M b_c| / |M b_c| of the solved system, b_c = b - mean_M(b) (the
/// compatible right-hand side), over the free rows (row `pin` excluded). The same for every backend.
double neumann_residual(const Eigen::SparseMatrix<double>& L, const Eigen::SparseMatrix<double>& M,
                        const Eigen::VectorXd& b, const Eigen::VectorXd& g, int pin = 0);

/// Backward (Poisson) evaluation of docs/math.md §10.4 with a test function of docs/math.md §10.2 on the unit sphere.
struct PoissonResult {
  Eigen::VectorXd f;      ///< #V exact solution u(q_v)
  Eigen::VectorXd b;      ///< #V right-hand side Delta u(q_v), before the compatibility projection
  Eigen::VectorXd g;      ///< #V computed solution, g[0] = f[0]
  double residual = 0.0;  ///< neumann_residual of the solve
  PoissonErrors errors;   ///< poisson_errors(M, g, f)
};
/// Samples u and Delta u at q_v = (x_v - c)/|x_v - c| (`positions` #V x 3, the mesh's), solves
/// L g = M b with vertex 0 pinned to u(q_0) and measures the error. `ops.L` and `ops.M` are #V x #V
/// (L negative semi-definite). The errors measure the discretization only when the surface
/// approximates the unit sphere of centre c. Throws InputError on size mismatches, SolverError.
PoissonResult solve_poisson(const Operators& ops, const Eigen::MatrixX3d& positions, const TestFunction& function,
                            LinearSolver& solver, const Eigen::Vector3d& center = Eigen::Vector3d::Zero());

/// Forward evaluation of docs/math.md §10.3: X = (M - dt L)^{-1} L u, an approximation of Delta u. dt = 0 is
/// the naive M^{-1} L u (which does not converge); docs/math.md's diffused variant uses dt = 0.035 h.
/// `solver` factorizes M - dt L (SPD since L is negative semi-definite). Throws InputError for
/// dt < 0 or size mismatches, SolverError.
Eigen::VectorXd forward_laplacian(const Eigen::SparseMatrix<double>& L, const Eigen::SparseMatrix<double>& M,
                                  const Eigen::VectorXd& u, LinearSolver& solver, double dt = 0.0,
                                  const Eigen::MatrixX3d* positions = nullptr);

/// Norms of forward_laplacian(u) - Delta u for a test function sampled as in solve_poisson.
ErrorNorms forward_error(const Operators& ops, const Eigen::MatrixX3d& positions, const TestFunction& function,
                         LinearSolver& solver, double dt = 0.0,
                         const Eigen::Vector3d& center = Eigen::Vector3d::Zero());

}  // namespace corrlap
