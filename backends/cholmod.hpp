#pragma once
// CHOLMOD (SuiteSparse) sparse Cholesky behind the LinearSolver contract ("cholmod").
// One cholmod_common per instance (instances may be used from different threads at once);
// the symbolic analysis is kept and reused by every factorize() on the same pattern.
// No SuiteSparse header leaks from here (pimpl).
#include <corrlap/core/linear_solver.hpp>
#include <memory>

namespace corrlap {

class CholmodSolver : public LinearSolver {
 public:
  CholmodSolver();
  ~CholmodSolver() override;

  std::string name() const override { return "cholmod"; }
  std::vector<ParameterInfo> options() const override;
  void configure(const Config& options) override;
  void set_positions(const Eigen::MatrixX3d& positions) override;
  void analyze(const Eigen::SparseMatrix<double>& A) override;
  void factorize(const Eigen::SparseMatrix<double>& A) override;
  Eigen::MatrixXd solve(const Eigen::MatrixXd& B) override;
  const SolverReport& info() const override;

  /// Number of symbolic analyses done so far (refactorizations must not add any).
  int analysis_count() const;
  /// True when the current factor is supernodal (the "auto" choice is CHOLMOD's).
  bool is_supernodal() const;
  /// Ordering used in the last analysis ("geometric", "amd", "metis", "nesdis", ...).
  std::string ordering_used() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace corrlap
