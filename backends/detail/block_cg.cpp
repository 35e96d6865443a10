#include "block_cg.hpp"

#include <cmath>
#include <corrlap/backends/detail/symmetric_product.hpp>
#include <vector>

namespace corrlap::detail {

BlockCgResult block_conjugate_gradient(const Eigen::SparseMatrix<double>& A, const Eigen::MatrixXd& B,
                                       const Preconditioner& precondition, double tolerance, int max_iterations) {
  return block_conjugate_gradient(
      [&](const Eigen::MatrixXd& Pt, Eigen::MatrixXd& Qt) { symmetric_product_transposed(A, Pt, Qt); }, B, precondition,
      tolerance, max_iterations);
}

BlockCgResult block_conjugate_gradient(const TransposedProduct& multiply, const Eigen::MatrixXd& B,
                                       const Preconditioner& precondition, double tolerance, int max_iterations) {
  const Eigen::Index n = B.rows(), k = B.cols();
  BlockCgResult result;
  // Rows are the k columns of the system (the transposed layout of symmetric_product_transposed).
  Eigen::MatrixXd Xt = Eigen::MatrixXd::Zero(k, n);
  Eigen::MatrixXd Rt = B.transpose();  // r = b - A x with x = 0
  Eigen::MatrixXd Zt, Pt, Qt;
  precondition(Rt, Zt);
  Pt = Zt;
  Eigen::ArrayXd rz = (Rt.array() * Zt.array()).rowwise().sum();
  const Eigen::ArrayXd threshold = tolerance * tolerance * Rt.rowwise().squaredNorm().array();
  std::vector<bool> active(static_cast<std::size_t>(k), true);
  const auto update_active = [&] {
    bool any = false;
    const Eigen::ArrayXd rr = Rt.rowwise().squaredNorm().array();
    for (Eigen::Index c = 0; c < k; ++c) {
      active[std::size_t(c)] = active[std::size_t(c)] && !(rr[c] <= threshold[c]);
      any = any || active[std::size_t(c)];
    }
    return any;
  };
  bool any_active = update_active();
  int iterations = 0;
  while (any_active && iterations < max_iterations) {
    multiply(Pt, Qt);
    const Eigen::ArrayXd pq = (Pt.array() * Qt.array()).rowwise().sum();
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
    any_active = update_active();
    if (!any_active) break;
    precondition(Rt, Zt);
    const Eigen::ArrayXd rz_next = (Rt.array() * Zt.array()).rowwise().sum();
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
