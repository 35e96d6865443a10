#pragma once
// Products of a symmetric sparse matrix with a block of vectors (internal to backends/): the block
// CG of the "cg" backend and the block Lanczos of the eigen solver spend much of their time here.
#include <Eigen/Core>
#include <Eigen/Sparse>

namespace corrlap::detail {

/// Yt = (A X)^T for a symmetric n x n A stored with both triangles, column-major; Xt = X^T is
/// k x n. Because A = A^T, row j of A X is column j of A dotted with X: the rows are independent
/// and run in parallel (TBB), each summed in storage order, so the result does not depend on the
/// thread count. Equals the readable (A * X).transpose() up to the order of the sums. The
/// transposed layout makes each row of X that a column of A gathers contiguous.
void symmetric_product_transposed(const Eigen::SparseMatrix<double>& A, const Eigen::MatrixXd& Xt, Eigen::MatrixXd& Yt);

/// Y = A X (n x b, column-major) for a symmetric A: the same row gathers as
/// symmetric_product_transposed, from X^T, written straight into Y; equal to A * X entry by entry
/// when A is exactly symmetric (the same products summed in the same order). `workspace` keeps X^T
/// between calls: fresh pages of a large block (96 MB at 753 K unknowns and b = 16) cost more than
/// the product.
struct SymmetricProductWorkspace {
  Eigen::MatrixXd Xt;
};
void symmetric_times(const Eigen::SparseMatrix<double>& A, const Eigen::MatrixXd& X, Eigen::MatrixXd& Y,
                     SymmetricProductWorkspace& workspace);
Eigen::MatrixXd symmetric_times(const Eigen::SparseMatrix<double>& A, const Eigen::MatrixXd& X);

}  // namespace corrlap::detail
