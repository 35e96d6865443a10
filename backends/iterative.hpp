#pragma once
// Preconditioned conjugate gradient behind the LinearSolver contract ("cg").
// Preconditioners: none, jacobi (diagonal), ichol (Eigen's incomplete Cholesky with AMD ordering).
// analyze() records the pattern, factorize() keeps A and builds the preconditioner, solve()
// iterates on every right-hand side at once, one parallel pass over A per iteration
// (detail/block_cg.hpp).
// Non-convergence throws SolverError(NoConvergence) unless on_no_convergence = "warn", in which
// case info().status is NoConvergence and info().message explains it.
#include <corrlap/core/linear_solver.hpp>
#include <memory>

namespace corrlap {

class ConjugateGradientSolver : public LinearSolver {
 public:
  ConjugateGradientSolver();
  ~ConjugateGradientSolver() override;

  std::string name() const override { return "cg"; }
  std::vector<ParameterInfo> options() const override;
  void configure(const Config& options) override;
  void analyze(const Eigen::SparseMatrix<double>& A) override;
  void factorize(const Eigen::SparseMatrix<double>& A) override;
  void factorize_owned(Eigen::SparseMatrix<double>&& A) override;
  Eigen::MatrixXd solve(const Eigen::MatrixXd& B) override;
  const SolverReport& info() const override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace corrlap
