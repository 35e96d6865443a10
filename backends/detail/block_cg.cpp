#include "block_cg.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <vector>

namespace corrlap::detail {

namespace {
// Row j of A X for K right-hand sides (K known at compile time: plain scalar accumulators).
template <int K>
void gather_rows(const Eigen::SparseMatrix<double>& A, const Eigen::MatrixXd& Xt, Eigen::MatrixXd& Yt,
                 Eigen::Index first, Eigen::Index last) {
  const int* outer = A.outerIndexPtr();
  const int* inner = A.innerIndexPtr();
  const double* value = A.valuePtr();
  const int* nnz = A.innerNonZeroPtr();  // null when compressed
  const double* x = Xt.data();
  for (Eigen::Index j = first; j != last; ++j) {
    const int begin = outer[j];
    const int end = nnz ? begin + nnz[j] : outer[j + 1];
    double y[K] = {};
    for (int e = begin; e < end; ++e) {
      const double* xi = x + std::ptrdiff_t(K) * inner[e];
      for (int c = 0; c < K; ++c) y[c] += value[e] * xi[c];
    }
    for (int c = 0; c < K; ++c) Yt(c, j) = y[c];
  }
}

void gather_rows_dynamic(const Eigen::SparseMatrix<double>& A, const Eigen::MatrixXd& Xt, Eigen::MatrixXd& Yt,
                         Eigen::Index first, Eigen::Index last) {
  for (Eigen::Index j = first; j != last; ++j) {
    auto y = Yt.col(j);
    y.setZero();
    for (Eigen::SparseMatrix<double>::InnerIterator it(A, j); it; ++it) y.noalias() += it.value() * Xt.col(it.row());
  }
}
}  // namespace

void symmetric_product_transposed(const Eigen::SparseMatrix<double>& A, const Eigen::MatrixXd& Xt,
                                  Eigen::MatrixXd& Yt) {
  const Eigen::Index k = Xt.rows();
  Yt.resize(k, A.cols());
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, A.cols(), 512), [&](const auto& r) {
    switch (k) {  // the study's three test functions, one and two right-hand sides
      case 1:
        gather_rows<1>(A, Xt, Yt, r.begin(), r.end());
        break;
      case 2:
        gather_rows<2>(A, Xt, Yt, r.begin(), r.end());
        break;
      case 3:
        gather_rows<3>(A, Xt, Yt, r.begin(), r.end());
        break;
      default:
        gather_rows_dynamic(A, Xt, Yt, r.begin(), r.end());
    }
  });
}

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
