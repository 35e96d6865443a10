#pragma once
// Checks and helpers shared by the linear solver backends (input validation with SolverError
// statuses, timing, config forwarding). Internal to backends/: no third-party solver header here.
#include <Eigen/Sparse>
#include <corrlap/core/config.hpp>
#include <corrlap/core/linear_solver.hpp>
#include <corrlap/core/stopwatch.hpp>
#include <cstdint>
#include <string>
#include <vector>

namespace corrlap::detail {

/// Throws SolverError(InvalidInput) when A is not square or empty, SolverError(NumericalIssue)
/// naming the entry when A holds a NaN/Inf, and SolverError(InvalidInput) when A is not symmetric
/// (relative tolerance 1e-10 on the Frobenius norm; every backend here is for symmetric systems).
void check_matrix(const Eigen::SparseMatrix<double>& A, const std::string& solver, bool check_symmetry = true);

/// ||A - A^T||_F without forming A^T or A - A^T (one int per column of scratch): one pass in column
/// order pairs each lower entry with its mirror through a cursor per column (inner indices are
/// sorted). The readable formula is (A - SparseMatrix(A.transpose())).norm(); this equals it up to
/// round-off.
double symmetry_defect(const Eigen::SparseMatrix<double>& A);

/// Throws SolverError(InvalidInput) when B has not `n` rows, SolverError(NumericalIssue) on NaN/Inf.
void check_rhs(const Eigen::MatrixXd& B, Eigen::Index n, const std::string& solver);

/// Fingerprint of a sparsity pattern (sizes and a 64-bit hash of the column lengths and row
/// indices), to check that factorize() gets the analyzed pattern. A copy of the pattern cost 4 bytes
/// per nonzero (1 GB for a heat kernel at h = 0.0125); two different patterns pass only if their
/// hashes collide, which misuse checks can live with.
struct Pattern {
  Eigen::Index rows = -1, cols = -1, nonzeros = 0;
  std::uint64_t hash = 0;
  void assign(const Eigen::SparseMatrix<double>& A);
  bool matches(const Eigen::SparseMatrix<double>& A) const;
  bool empty() const { return rows < 0; }
};

/// Throws SolverError(InvalidInput) when A's pattern differs from the analyzed one.
void check_same_pattern(const Pattern& analyzed, const Eigen::SparseMatrix<double>& A, const std::string& solver);

/// Keys every backend accepts besides its own: "solver" (consumed by make_linear_solver).
std::vector<std::string> allowed_keys(const std::vector<ParameterInfo>& options);

/// A copy of `config` without the given keys (values keep their type through key=value parsing).
Config without_keys(const Config& config, const std::vector<std::string>& drop);

/// Relative residual |A X - B|_F / |B|_F (0 when B = 0).
double relative_residual(const Eigen::SparseMatrix<double>& A, const Eigen::MatrixXd& X, const Eigen::MatrixXd& B);

}  // namespace corrlap::detail
