#pragma once
// Eigen solvers for the generalized symmetric problem L u = lambda M u (docs/math.md §10.5), k smallest
// |lambda|. L is negative semi-definite (docs/math.md §0); results are reported as mu = -lambda >= 0,
// ascending (the docs/math.md §12.3 convention), with M-orthonormal eigenvectors.
//
// "shift-invert": Spectra's SymGEigsShiftSolver (shift-invert Lanczos on K = -L, B = M) whose
//   operator (K - sigma M)^{-1} is applied by ANY registered LinearSolver (config key "solver",
//   default cholmod; the remaining keys go to that solver). The shift sigma < 0 sits slightly
//   below 0 so that K - sigma M is positive definite although L is singular (constant kernel);
//   since every mu >= 0 > sigma, the eigenvalues nearest sigma are exactly the smallest ones.
//   Problems with n <= dense_threshold use the dense solver instead.
// "dense": Eigen's GeneralizedSelfAdjointEigenSolver on dense copies (small n only).
#include <corrlap/core/linear_solver.hpp>
#include <memory>

namespace corrlap {

class ShiftInvertEigenSolver : public EigenSolver {
 public:
  ShiftInvertEigenSolver();
  ~ShiftInvertEigenSolver() override;
  std::string name() const override { return "shift-invert"; }
  std::vector<ParameterInfo> options() const override;
  void configure(const Config& options) override;
  /// Passed on to the linear solver of (K - sigma M)^{-1}.
  void set_positions(const Eigen::MatrixX3d& positions) override;
  EigenResult solve(const Eigen::SparseMatrix<double>& L, const Eigen::SparseMatrix<double>& M, int k) override;

  /// Report of the inner linear solver after the last solve (timings of its factorization).
  SolverReport linear_solver_report() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

class DenseEigenSolver : public EigenSolver {
 public:
  std::string name() const override { return "dense"; }
  std::vector<ParameterInfo> options() const override;
  void configure(const Config& options) override;
  EigenResult solve(const Eigen::SparseMatrix<double>& L, const Eigen::SparseMatrix<double>& M, int k) override;

 private:
  int max_n_ = 6000;
};

}  // namespace corrlap
