#include "block_cg.hpp"

#include <cmath>
#include <corrlap/backends/detail/symmetric_product.hpp>
#include <vector>

namespace corrlap::detail {

BlockCgResult block_conjugate_gradient(const Eigen::SparseMatrix<double>& A, const Eigen::MatrixXd& B,
                                       const Preconditioner& precondition, double tolerance, int max_iterations,
                                       double preconditioned_tolerance) {
  return block_conjugate_gradient(
      [&](const Eigen::MatrixXd& Pt, Eigen::MatrixXd& Qt) { symmetric_product_transposed(A, Pt, Qt); }, B, precondition,
      tolerance, max_iterations, preconditioned_tolerance);
}

BlockCgResult block_conjugate_gradient(const TransposedProduct& multiply, const Eigen::MatrixXd& B,
                                       const Preconditioner& precondition, double tolerance, int max_iterations,
                                       double preconditioned_tolerance, const ColumnSums& sum_over_parts) {
  // Per-column inner products of the rows held here, summed over the processes that hold the rest.
  const auto summed = [&](Eigen::ArrayXd sums) {
    if (sum_over_parts) sum_over_parts(sums);
    return sums;
  };
  const Eigen::Index n = B.rows(), k = B.cols();
  BlockCgResult result;
  // Rows are the k columns of the system (the transposed layout of symmetric_product_transposed).
  Eigen::MatrixXd Xt = Eigen::MatrixXd::Zero(k, n);
  Eigen::MatrixXd Rt = B.transpose();  // r = b - A x with x = 0
  Eigen::MatrixXd Zt, Pt, Qt;
  precondition(Rt, Zt);
  Pt = Zt;
  Eigen::ArrayXd rz = summed((Rt.array() * Zt.array()).rowwise().sum());
  const Eigen::ArrayXd threshold = tolerance * tolerance * summed(Rt.rowwise().squaredNorm().array());
  const double rz_threshold = preconditioned_tolerance * preconditioned_tolerance;
  std::vector<bool> active(static_cast<std::size_t>(k), true);
  // rz: r^T P^{-1} r of the current residual (the preconditioned test reads it, no extra work).
  const auto update_active = [&](const Eigen::ArrayXd& rz_now) {
    bool any = false;
    const Eigen::ArrayXd rr = summed(Rt.rowwise().squaredNorm().array());
    for (Eigen::Index c = 0; c < k; ++c) {
      const bool small = rr[c] <= threshold[c] || (preconditioned_tolerance > 0.0 && rz_now[c] <= rz_threshold);
      active[std::size_t(c)] = active[std::size_t(c)] && !small;
      any = any || active[std::size_t(c)];
    }
    return any;
  };
  bool any_active = update_active(rz);
  int iterations = 0;
  while (any_active && iterations < max_iterations) {
    multiply(Pt, Qt);
    const Eigen::ArrayXd pq = summed((Pt.array() * Qt.array()).rowwise().sum());
    Eigen::ArrayXd alpha = Eigen::ArrayXd::Zero(k);
    for (Eigen::Index c = 0; c < k; ++c) {
      if (!active[std::size_t(c)]) continue;
      if (!(pq[c] > 0.0)) {  // A is not positive definite along p (or p is NaN)
        result.breakdown_column = c;
        result.breakdown_value = pq[c];
        break;
      }
      alpha[c] = rz[c] / pq[c];
    }
    if (result.breakdown_column >= 0) break;
    Xt += alpha.matrix().asDiagonal() * Pt;  // frozen columns have alpha = 0
    Rt -= alpha.matrix().asDiagonal() * Qt;
    ++iterations;
    // The plain test needs no preconditioner application; the preconditioned one needs this
    // iteration's z (the next iteration's, so no extra work when it goes on).
    if (preconditioned_tolerance <= 0.0 && !update_active(rz)) {
      any_active = false;
      break;
    }
    precondition(Rt, Zt);
    const Eigen::ArrayXd rz_next = summed((Rt.array() * Zt.array()).rowwise().sum());
    if (preconditioned_tolerance > 0.0 && !update_active(rz_next)) {
      any_active = false;
      break;
    }
    Eigen::ArrayXd beta = Eigen::ArrayXd::Zero(k);
    for (Eigen::Index c = 0; c < k; ++c)
      if (active[std::size_t(c)]) beta[c] = rz_next[c] / rz[c];
    Pt = Zt + beta.matrix().asDiagonal() * Pt;
    rz = rz_next;
  }
  result.X = Xt.transpose();
  result.iterations = iterations;
  result.converged = !any_active;
  return result;
}

}  // namespace corrlap::detail
