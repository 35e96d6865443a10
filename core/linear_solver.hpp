#pragma once
// The LinearSolver contract (Eigen's analyze / factorize / solve / info pattern) for symmetric
// positive (semi-)definite sparse systems, and the EigenSolver contract for L u = lambda M u.
#include <Eigen/Core>
#include <Eigen/Sparse>
#include <string>
#include <vector>

#include "config.hpp"
#include "error.hpp"

namespace corrlap {

/// The linear solver used when none is named, by the library (make_linear_solver, the shift-invert
/// eigen solver) and by the CLI alike: CHOLMOD's supernodal Cholesky (bench/bench_solvers.cpp
/// compares it with the other backends).
inline constexpr const char* kDefaultLinearSolver = "cholmod";
/// The eigen solver used when none is named: shift-invert Lanczos (docs/math.md §10.5).
inline constexpr const char* kDefaultEigenSolver = "shift-invert";

enum class SolverStatus {
  Success,
  NotAnalyzed,          ///< factorize/solve called before analyze/factorize
  NotPositiveDefinite,  ///< a non-positive pivot (the message names the column)
  NumericalIssue,       ///< NaN/Inf in input or factor
  NoConvergence,        ///< iterative solver hit its iteration limit
  InvalidInput,         ///< dimension mismatch, non-square matrix...
  OutOfMemory,
};
const char* to_string(SolverStatus status);

/// Outcome and timings of the last phase of a solver.
struct SolverReport {
  SolverStatus status = SolverStatus::NotAnalyzed;
  std::string message;
  int iterations = 0;     ///< iterative solvers
  double residual = 0.0;  ///< relative residual |Ax-b|/|b| of the last solve
  double analyze_seconds = 0.0, factorize_seconds = 0.0, solve_seconds = 0.0;
  /// Direct solvers, after analyze(): the elimination order used ("amd", "geometric", ...), the
  /// entries of the factor and the flops of a factorization (0 when the backend does not say).
  std::string ordering;
  double factor_nonzeros = 0.0, factor_flops = 0.0;
};

/// Raised when a solver phase fails; carries the backend status.
class SolverError : public NumericalError {
 public:
  SolverError(SolverStatus status, const std::string& message) : NumericalError(message), status_(status) {}
  SolverStatus status() const { return status_; }

 private:
  SolverStatus status_;
};

class LinearSolver {
 public:
  virtual ~LinearSolver() = default;
  virtual std::string name() const = 0;
  /// Options this backend accepts (name, default, meaning).
  virtual std::vector<ParameterInfo> options() const = 0;
  /// Applies options; unknown keys are InputErrors listing the valid ones.
  virtual void configure(const Config& options) = 0;
  /// Optional hint for the next analyze(): a point per unknown (#unknowns x 3), e.g. the vertex
  /// positions of the mesh the system lives on. Direct solvers use it to order the elimination
  /// (cholmod: geometric nested dissection, 4x fewer flops than AMD at 10^6 unknowns); the others
  /// ignore it. A hint whose row count differs from the next matrix's is ignored; an empty matrix
  /// clears it.
  virtual void set_positions(const Eigen::MatrixX3d& /*positions*/) {}
  /// Symbolic analysis of the pattern of A (reusable for matrices with the same pattern).
  virtual void analyze(const Eigen::SparseMatrix<double>& A) = 0;
  /// Numeric factorization of A (same pattern as the analyzed one). Throws SolverError.
  virtual void factorize(const Eigen::SparseMatrix<double>& A) = 0;
  /// factorize() of a matrix the caller gives away (A is left empty). A backend that must keep the
  /// matrix until solve() (cg) keeps this one instead of a copy: the heat kernel's ~2000 entries
  /// per row made that copy the memory peak of a study. The default factorizes and drops A.
  virtual void factorize_owned(Eigen::SparseMatrix<double>&& A) {
    factorize(A);
    A = Eigen::SparseMatrix<double>();
  }
  /// analyze + factorize.
  void compute(const Eigen::SparseMatrix<double>& A) {
    analyze(A);
    factorize(A);
  }
  /// analyze + factorize_owned: compute(std::move(A)) leaves A empty.
  void compute(Eigen::SparseMatrix<double>&& A) {
    analyze(A);
    factorize_owned(std::move(A));
  }
  /// Solves A X = B for every column of B. Throws SolverError.
  virtual Eigen::MatrixXd solve(const Eigen::MatrixXd& B) = 0;
  /// Report of the last phase.
  virtual const SolverReport& info() const = 0;
};

/// Result of a generalized symmetric eigenproblem.
struct EigenResult {
  Eigen::VectorXd values;   ///< ascending
  Eigen::MatrixXd vectors;  ///< one column per value, M-orthonormal
  int iterations = 0;
  std::string method;  ///< how it was computed ("dense", "lanczos"), for reports
};

/// Computes the k eigenpairs of L u = lambda M u of smallest |lambda|.
class EigenSolver {
 public:
  virtual ~EigenSolver() = default;
  virtual std::string name() const = 0;
  virtual std::vector<ParameterInfo> options() const = 0;
  virtual void configure(const Config& options) = 0;
  /// Optional ordering hint for the linear solves (LinearSolver::set_positions): a point per unknown.
  virtual void set_positions(const Eigen::MatrixX3d& /*positions*/) {}
  virtual EigenResult solve(const Eigen::SparseMatrix<double>& L, const Eigen::SparseMatrix<double>& M, int k) = 0;
};

}  // namespace corrlap
