#pragma once
// Preconditioned conjugate gradient behind the LinearSolver contract ("cg").
// Preconditioners: none, jacobi (diagonal), ichol (Eigen's incomplete Cholesky with AMD ordering).
// analyze() records the pattern, factorize() keeps A and builds the preconditioner, solve()
// iterates on every right-hand side at once, one parallel pass over A per iteration
// (detail/block_cg.hpp).
// Non-convergence throws SolverError(NoConvergence) unless on_no_convergence = "warn", in which
// case info().status is NoConvergence and info().message explains it.
#include <corrlap/core/linear_solver.hpp>
#include <functional>
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

/// A symmetric positive definite n x n operator known by its product (Spectra's operator concept),
/// for operators too large to store as a matrix (the heat kernel's compact lattice form).
struct SymmetricOperator {
  Eigen::Index rows = 0;
  /// Yt = (A X)^T for Xt = X^T (k by rows): the transposed layout keeps a row's k values together.
  std::function<void(const Eigen::MatrixXd& Xt, Eigen::MatrixXd& Yt)> multiply_transposed;
  Eigen::VectorXd diagonal;  ///< diag(A) (> 0): the Jacobi preconditioner, unless one is given below
  /// Optional preconditioner, Zt = (P^{-1} R)^T for Rt = R^T (k by rows), P symmetric positive
  /// definite and fixed (a factorization, not an inner iteration). When set, `diagonal` may be empty.
  std::function<void(const Eigen::MatrixXd& Rt, Eigen::MatrixXd& Zt)> precondition_transposed;
  /// Optional, for an operator whose rows are split over processes (MPI ranks), each calling
  /// conjugate_gradient with its own rows of B: sums k per-column partial inner products over them
  /// in place, so that every process takes the same steps (give max_iterations: its default
  /// depends on the local rows).
  std::function<void(Eigen::ArrayXd& sums)> sum_over_parts;
};

/// Solves A X = B (#rows by k) with the "cg" backend's iteration and checks (Jacobi or the operator's
/// preconditioner,
/// every column in one product per iteration, the true residual checked at the end). Options:
/// tolerance (1e-10), max_iterations (0: 2 n) and on_no_convergence (error | warn: return the last
/// finite iterate with status NoConvergence in `report`), as for "cg"; other keys are InputErrors.
/// preconditioned_tolerance (0: off): a column also stops when sqrt(r^T P^{-1} r) of its recurrence
/// residual is at most this (absolute; it bounds the error in A's norm); the true residual is then
/// the caller's to check in that norm (one more application of P^{-1}), not checked here. Throws
/// SolverError (NotPositiveDefinite, NoConvergence) like the backend; `report` gets iterations,
/// residual and solve time.
Eigen::MatrixXd conjugate_gradient(const SymmetricOperator& A, const Eigen::MatrixXd& B, const Config& options = {},
                                   SolverReport* report = nullptr);

}  // namespace corrlap
