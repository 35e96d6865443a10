#include "symmetric_product.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstddef>

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

// Row j of A X for any number of right-hand sides, handed to store(j, row) (a column of Yt, or a
// row of a column-major Y).
template <class Store>
void gather_rows_dynamic(const Eigen::SparseMatrix<double>& A, const Eigen::MatrixXd& Xt, Eigen::Index first,
                         Eigen::Index last, const Store& store) {
  Eigen::VectorXd y(Xt.rows());
  for (Eigen::Index j = first; j != last; ++j) {
    y.setZero();
    for (Eigen::SparseMatrix<double>::InnerIterator it(A, j); it; ++it) y.noalias() += it.value() * Xt.col(it.row());
    store(j, y);
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
        gather_rows_dynamic(A, Xt, r.begin(), r.end(),
                            [&](Eigen::Index j, const Eigen::VectorXd& y) { Yt.col(j) = y; });
    }
  });
}

void symmetric_times(const Eigen::SparseMatrix<double>& A, const Eigen::MatrixXd& X, Eigen::MatrixXd& Y,
                     SymmetricProductWorkspace& workspace) {
  workspace.Xt = X.transpose();  // each row of X that a column of A gathers is contiguous
  Y.resize(A.rows(), X.cols());
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, A.cols(), 512), [&](const auto& r) {
    gather_rows_dynamic(A, workspace.Xt, r.begin(), r.end(),
                        [&](Eigen::Index j, const Eigen::VectorXd& y) { Y.row(j) = y.transpose(); });
  });
}

Eigen::MatrixXd symmetric_times(const Eigen::SparseMatrix<double>& A, const Eigen::MatrixXd& X) {
  Eigen::MatrixXd Y;
  SymmetricProductWorkspace workspace;
  symmetric_times(A, X, Y, workspace);
  return Y;
}

}  // namespace corrlap::detail
