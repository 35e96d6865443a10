#pragma once
// Preconditioned conjugate gradient on every column of a right-hand side at once. Internal to
// backends/ (the "cg" backend, iterative.cpp).
#include <Eigen/Core>
#include <Eigen/Sparse>
#include <functional>

namespace corrlap::detail {

/// Zt = P^{-1} Rt for k residuals stored as the rows of Rt (k x n).
using Preconditioner = std::function<void(const Eigen::MatrixXd& Rt, Eigen::MatrixXd& Zt)>;

/// For rows split over processes (each holds its own rows of every vector): sums the k per-column
/// partial inner products over them, in place. Empty: one process holds every row.
using ColumnSums = std::function<void(Eigen::ArrayXd& sums)>;

struct BlockCgResult {
  Eigen::MatrixXd X;                   ///< n x k solution (the last iterate when not converged)
  int iterations = 0;                  ///< of the slowest column
  bool converged = false;              ///< every column reached a stopping test (recurrence residual)
  Eigen::Index breakdown_column = -1;  ///< column with p^T A p <= 0 (A not positive definite), or -1
  double breakdown_value = 0.0;        ///< that p^T A p
};

/// Solves A X = B (A symmetric positive definite, both triangles stored) by preconditioned CG from
/// X = 0 (Saad, Iterative Methods for Sparse Linear Systems, 2nd ed., Algorithm 9.1), every column
/// with its own step lengths but one pass over A per iteration for all of them: the heat kernel's
/// ~2000 entries per row make that pass the cost of an iteration. A column stops when its
/// recurrence residual is <= tolerance |b|; iteration stops when every column has, at
/// max_iterations, or at a breakdown (p^T A p <= 0 in a column not yet converged).
BlockCgResult block_conjugate_gradient(const Eigen::SparseMatrix<double>& A, const Eigen::MatrixXd& B,
                                       const Preconditioner& precondition, double tolerance, int max_iterations,
                                       double preconditioned_tolerance = 0.0);

/// Qt = (A P)^T for Pt = P^T (k x n): an operator known only by its product.
using TransposedProduct = std::function<void(const Eigen::MatrixXd& Pt, Eigen::MatrixXd& Qt)>;

/// The same iteration on an operator given by its product (the matrix overload passes
/// symmetric_product_transposed). With preconditioned_tolerance > 0 a column also stops when the
/// preconditioned norm of its recurrence residual, sqrt(r^T P^{-1} r), is at most that (absolute):
/// the quantity CG has at hand that bounds the error in A's norm (|e|_A^2 = r^T A^{-1} r).
/// With `sum_over_parts` the inner products are summed over the processes, which then take the same
/// steps and stop together.
BlockCgResult block_conjugate_gradient(const TransposedProduct& multiply, const Eigen::MatrixXd& B,
                                       const Preconditioner& precondition, double tolerance, int max_iterations,
                                       double preconditioned_tolerance = 0.0, const ColumnSums& sum_over_parts = {});

}  // namespace corrlap::detail
