#pragma once
// Eigen's simplicial Cholesky factorizations behind the LinearSolver contract:
// "eigen-ldlt" (SimplicialLDLT) and "eigen-llt" (SimplicialLLT). AMD ordering.
#include <corrlap/core/linear_solver.hpp>
#include <memory>

namespace corrlap {

class EigenDirectSolver : public LinearSolver {
 public:
  enum class Kind { LDLT, LLT };
  explicit EigenDirectSolver(Kind kind);
  ~EigenDirectSolver() override;

  std::string name() const override;
  std::vector<ParameterInfo> options() const override;
  void configure(const Config& options) override;
  void analyze(const Eigen::SparseMatrix<double>& A) override;
  void factorize(const Eigen::SparseMatrix<double>& A) override;
  Eigen::MatrixXd solve(const Eigen::MatrixXd& B) override;
  const SolverReport& info() const override;

  /// Number of symbolic analyses done so far (refactorizations must not add any).
  int analysis_count() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace corrlap
