#include "problems.hpp"

#include <cmath>
#include <sstream>

namespace corrlap {

using SpMat = Eigen::SparseMatrix<double>;

Eigen::VectorXd solve_dirichlet(const SpMat& L, const SpMat& M, const Eigen::VectorXd& f, const std::vector<int>& fixed,
                                const Eigen::VectorXd& values, LinearSolver& solver) {
  const Eigen::Index n = L.rows();
  if (L.cols() != n || M.rows() != n || M.cols() != n || f.size() != n) {
    std::ostringstream os;
    os << "Dirichlet problem: sizes differ (L " << L.rows() << "x" << L.cols() << ", M " << M.rows() << "x"
       << M.cols() << ", f " << f.size() << ")";
    throw InputError(os.str());
  }
  if (Eigen::Index(fixed.size()) != values.size())
    throw InputError("Dirichlet problem: " + std::to_string(fixed.size()) + " fixed vertices but " +
                     std::to_string(values.size()) + " values");
  // L 1 = 0 (spec §0): without a fixed vertex -L is singular, and a Cholesky of a singular PSD
  // matrix may pass on rounding errors and return garbage, so refuse up front.
  if (fixed.empty()) throw InputError("Dirichlet problem: no fixed vertex (L 1 = 0 makes the system singular)");
  // Map every vertex to its index among the free ones (-1: fixed).
  std::vector<int> free_index(std::size_t(n), 0);
  for (std::size_t i = 0; i < fixed.size(); ++i) {
    const int v = fixed[i];
    if (v < 0 || v >= n) throw InputError("Dirichlet problem: fixed vertex " + std::to_string(v) + " out of range [0, " + std::to_string(n) + ")");
    if (free_index[std::size_t(v)] < 0) throw InputError("Dirichlet problem: vertex " + std::to_string(v) + " fixed twice");
    if (!std::isfinite(values[Eigen::Index(i)])) throw InputError("Dirichlet problem: value of vertex " + std::to_string(v) + " is not finite");
    free_index[std::size_t(v)] = -1;
  }
  int nfree = 0;
  for (auto& k : free_index)
    if (k >= 0) k = nfree++;
  if (nfree == 0) throw InputError("Dirichlet problem: every vertex is fixed");

  Eigen::VectorXd u_fixed = Eigen::VectorXd::Zero(n);
  for (std::size_t i = 0; i < fixed.size(); ++i) u_fixed[fixed[i]] = values[Eigen::Index(i)];

  // Free rows of L u = M f:  L_ff u_f = (M f)_f - L_fc u_c.  The solver gets -L_ff (SPD).
  const Eigen::VectorXd rhs_full = M * f - L * u_fixed;
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(std::size_t(L.nonZeros()));
  for (Eigen::Index j = 0; j < L.outerSize(); ++j) {
    const int fj = free_index[std::size_t(j)];
    if (fj < 0) continue;
    for (SpMat::InnerIterator it(L, j); it; ++it) {
      const int fi = free_index[std::size_t(it.row())];
      if (fi >= 0) triplets.emplace_back(fi, fj, -it.value());
    }
  }
  SpMat A(nfree, nfree);
  A.setFromTriplets(triplets.begin(), triplets.end());
  Eigen::VectorXd rhs(nfree);
  for (Eigen::Index v = 0; v < n; ++v)
    if (free_index[std::size_t(v)] >= 0) rhs[free_index[std::size_t(v)]] = -rhs_full[v];

  solver.compute(A);
  const Eigen::VectorXd u_free = solver.solve(rhs);
  Eigen::VectorXd u = u_fixed;
  for (Eigen::Index v = 0; v < n; ++v)
    if (free_index[std::size_t(v)] >= 0) u[v] = u_free[free_index[std::size_t(v)]];
  return u;
}

double mass_weighted_mean(const SpMat& M, const Eigen::VectorXd& v) {
  if (M.rows() != v.size() || M.cols() != v.size())
    throw InputError("mass-weighted mean: M is " + std::to_string(M.rows()) + "x" + std::to_string(M.cols()) +
                     ", vector has " + std::to_string(v.size()) + " entries");
  const Eigen::VectorXd ones = Eigen::VectorXd::Ones(v.size());
  const Eigen::VectorXd m1 = M * ones;  // M symmetric: 1^T M v = (M 1)^T v
  return m1.dot(v) / m1.sum();
}

Eigen::VectorXd solve_neumann_poisson(const SpMat& L, const SpMat& M, const Eigen::VectorXd& b, LinearSolver& solver,
                                      double pin_value, int pin) {
  // spec §10.4: without the compatibility projection, pinning makes a point source whose error
  // spoils the convergence rate.
  const Eigen::VectorXd compatible = b.array() - mass_weighted_mean(M, b);
  return solve_dirichlet(L, M, compatible, {pin}, Eigen::VectorXd::Constant(1, pin_value), solver);
}

PoissonErrors poisson_errors(const SpMat& M, const Eigen::VectorXd& g, const Eigen::VectorXd& f) {
  if (g.size() != f.size()) throw InputError("Poisson errors: solution and reference sizes differ");
  const Eigen::VectorXd e = (g.array() - mass_weighted_mean(M, g)) - (f.array() - mass_weighted_mean(M, f));
  PoissonErrors r;
  r.linf = e.lpNorm<Eigen::Infinity>();
  const double area = (M * Eigen::VectorXd::Ones(f.size())).sum();
  r.l2 = std::sqrt(e.dot(M * e) / area);
  return r;
}

}  // namespace corrlap
