#include "block_lanczos.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <corrlap/backends/detail/symmetric_product.hpp>
#include <random>
#include <vector>

namespace corrlap::detail {

namespace {

using Matrix = Eigen::MatrixXd;
using SpMat = Eigen::SparseMatrix<double>;

// The tall products below (n rows against a basis of a few hundred columns) are most of the
// iteration's arithmetic. They run on fixed blocks of rows in parallel, each block one serial BLAS
// call (the iteration keeps OpenBLAS on one thread: detail/blas_threads.hpp); sums over the blocks
// are taken in block order, so the result does not depend on the number of threads.
constexpr Eigen::Index kRowBlock = 8192;

Eigen::Index row_blocks(Eigen::Index n) { return (n + kRowBlock - 1) / kRowBlock; }

/// V^T X (V: n x p, X: n x b): the p x b sum over row blocks of V_rows^T X_rows.
Matrix transpose_times(const Eigen::Ref<const Matrix>& V, const Matrix& X) {
  const Eigen::Index n = V.rows(), blocks = row_blocks(n);
  std::vector<Matrix> partial(static_cast<std::size_t>(blocks));
  tbb::parallel_for(Eigen::Index(0), blocks, [&](Eigen::Index i) {
    const Eigen::Index first = i * kRowBlock, count = std::min(kRowBlock, n - first);
    partial[std::size_t(i)].noalias() = V.middleRows(first, count).transpose() * X.middleRows(first, count);
  });
  Matrix sum = Matrix::Zero(V.cols(), X.cols());
  for (const Matrix& p : partial) sum += p;
  return sum;
}

/// W -= V P, row block by row block.
void subtract_times(Matrix& W, const Eigen::Ref<const Matrix>& V, const Matrix& P) {
  const Eigen::Index n = V.rows();
  tbb::parallel_for(Eigen::Index(0), row_blocks(n), [&](Eigen::Index i) {
    const Eigen::Index first = i * kRowBlock, count = std::min(kRowBlock, n - first);
    W.middleRows(first, count).noalias() -= V.middleRows(first, count) * P;
  });
}

/// W <- W U^{-1} for an upper triangular U, row block by row block.
void divide_by_upper(Matrix& W, const Matrix& U) {
  tbb::parallel_for(Eigen::Index(0), row_blocks(W.rows()), [&](Eigen::Index i) {
    const Eigen::Index first = i * kRowBlock, count = std::min(kRowBlock, W.rows() - first);
    auto rows = W.middleRows(first, count);
    U.triangularView<Eigen::Upper>().solveInPlace<Eigen::OnTheRight>(rows);
  });
}

/// W = Q R with Q^T M Q = I (Cholesky QR, twice: one pass leaves an orthogonality error of about
/// eps * cond(W)^2, the second brings it to eps). MW = M W on entry and M Q on return (updated
/// with R, not recomputed). False when W is (numerically) rank deficient.
bool m_orthonormalize(Matrix& W, Matrix& MW, Matrix& R) {
  R = Matrix::Identity(W.cols(), W.cols());
  for (int pass = 0; pass < 2; ++pass) {
    const Matrix G = transpose_times(W, MW);
    Eigen::LLT<Matrix> llt(0.5 * (G + G.transpose()));
    if (llt.info() != Eigen::Success) return false;
    const Matrix U = llt.matrixU();
    // A pivot far below the largest: the block has (almost) lost a direction.
    const double largest = U.diagonal().cwiseAbs().maxCoeff();
    if (!(U.diagonal().cwiseAbs().minCoeff() > 1e-10 * largest)) return false;
    divide_by_upper(W, U);  // W U^{-1}
    divide_by_upper(MW, U);
    R = U * R;
  }
  return true;
}

/// W <- W - V (V^T M W) in two passes (classical Gram-Schmidt with reorthogonalization): the first
/// against the columns from `local` on, the second against all of V. Returns the sum of the
/// coefficients, the column block of T = V^T M S V when W = S V_j; MW = M W on return.
/// Why a local first pass is enough: in exact arithmetic S V_j is M-orthogonal to every block but
/// V_{j-1} and V_j (T is block tridiagonal), so the large components, whose cancellation needs the
/// second pass, are all local; the full pass removes what rounding left elsewhere. It halves the
/// streaming of the basis, the larger part of a block step. Right after a thick restart the new
/// block couples to every kept Ritz vector, and `local` is 0.
Matrix project_out(const SpMat& M, const Eigen::Ref<const Matrix>& V, Eigen::Index local, Matrix& W, Matrix& MW,
                   SymmetricProductWorkspace& scratch) {
  Matrix coefficients = Matrix::Zero(V.cols(), W.cols());
  for (int pass = 0; pass < 2; ++pass) {
    const Eigen::Index from = pass == 0 ? local : 0;
    const auto part = V.middleCols(from, V.cols() - from);
    symmetric_times(M, W, MW, scratch);
    const Matrix P = transpose_times(part, MW);
    subtract_times(W, part, P);
    coefficients.middleRows(from, V.cols() - from) += P;
  }
  symmetric_times(M, W, MW, scratch);
  return coefficients;
}

/// The first `keep` columns of V become V Y (Y: used x keep), in place: row blocks are independent,
/// so a block-sized buffer per block replaces an n x keep temporary (whose fresh pages cost as much
/// as the product at 188 K unknowns).
void rotate_basis(Matrix& V, int used, const Matrix& Y, int keep) {
  const Eigen::Index n = V.rows();
  tbb::parallel_for(Eigen::Index(0), row_blocks(n), [&](Eigen::Index i) {
    const Eigen::Index first = i * kRowBlock, count = std::min(kRowBlock, n - first);
    const Matrix rows_product = V.block(first, 0, count, used) * Y.leftCols(keep);
    V.block(first, 0, count, keep) = rows_product;
  });
}

/// V Y (V: n x p, Y: p x q), row block by row block.
Matrix times(const Eigen::Ref<const Matrix>& V, const Eigen::Ref<const Matrix>& Y) {
  Matrix result(V.rows(), Y.cols());
  tbb::parallel_for(Eigen::Index(0), row_blocks(V.rows()), [&](Eigen::Index i) {
    const Eigen::Index first = i * kRowBlock, count = std::min(kRowBlock, V.rows() - first);
    result.middleRows(first, count).noalias() = V.middleRows(first, count) * Y;
  });
  return result;
}

}  // namespace

BlockLanczosResult block_lanczos(const std::function<Matrix(const Matrix&)>& apply, const SpMat& M, int nev,
                                 const BlockLanczosOptions& options) {
  const Eigen::Index n = M.rows();
  const int b = std::max(1, options.block_size);
  BlockLanczosResult result;
  if (nev < 1 || nev + b >= n) return result;  // too small for blocks: the caller goes another way
  const int max_basis = int(std::min<Eigen::Index>(
      n, options.max_basis > 0 ? std::max(options.max_basis, nev + 2 * b) : std::max(3 * nev, nev + 8 * b)));

  Matrix V(n, max_basis);                         // M-orthonormal basis, the first `used` columns
  Matrix T = Matrix::Zero(max_basis, max_basis);  // V^T M S V, filled block column by block column
  std::mt19937 rng(options.seed);
  std::normal_distribution<double> normal;
  Matrix block(n, b), R;
  for (Eigen::Index j = 0; j < b; ++j)
    for (Eigen::Index i = 0; i < n; ++i) block(i, j) = normal(rng);
  SymmetricProductWorkspace scratch;  // of symmetric_times, kept between calls
  Matrix M_block;                     // M times the newest block, carried along
  symmetric_times(M, block, M_block, scratch);
  if (!m_orthonormalize(block, M_block, R)) return result;
  V.leftCols(b) = block;
  int used = b;
  bool restarted = false;  // the newest block is the first after a thick restart
  const int wanted = options.wanted > 0 ? std::min(options.wanted, nev) : nev;

  for (;;) {
    // Next block: S applied to the newest block, made M-orthogonal to the whole basis.
    const int first = used - b;
    Matrix W = apply(M_block);
    ++result.block_steps;
    T.block(0, first, used, b) =
        project_out(M, V.leftCols(used), restarted ? 0 : std::max(0, first - b), W, M_block, scratch);
    restarted = false;
    if (!m_orthonormalize(W, M_block, R)) return result;  // an invariant subspace or a breakdown

    // Rayleigh-Ritz: S V = V T + W R E^T, so the residual of a Ritz pair (theta, V y) is |R y_last|.
    const Matrix Ts = 0.5 * (T.topLeftCorner(used, used) + T.topLeftCorner(used, used).transpose());
    Eigen::SelfAdjointEigenSolver<Matrix> ritz(Ts);
    if (ritz.info() != Eigen::Success) return result;
    // Descending theta: the eigen solver's order reversed.
    const Eigen::VectorXd theta = ritz.eigenvalues().reverse();
    const Matrix Y = ritz.eigenvectors().rowwise().reverse();
    if (used >= nev + b) {
      // Only the pairs asked for must converge; the guard pairs beyond them are upper bounds in mu
      // (Ritz values of the largest theta are below the true ones) and are dropped by the caller.
      const Eigen::VectorXd residuals = (R * Y.bottomRows(b).leftCols(nev)).colwise().norm().transpose();
      bool all = true;
      for (int i = 0; i < wanted && all; ++i) all = residuals[i] <= options.tolerance * std::abs(theta[i]);
      const bool stop = !all && options.stop && options.stop(theta.head(nev), residuals);
      if (all || stop) {
        result.theta = theta.head(nev);
        result.residuals = residuals;
        result.vectors = times(V.leftCols(used), Y.leftCols(nev));
        result.converged = all;
        result.stopped = stop;
        return result;
      }
    }
    if (used + b <= max_basis) {
      V.middleCols(used, b) = W;
      T.block(used, first, b, b) = R;
      used += b;
      continue;
    }
    // Thick restart: keep the best Ritz vectors, whose projected matrix is diag(theta); the new
    // block couples to them through R y_last (the residual directions).
    if (result.restarts++ >= options.max_restarts) return result;
    const int keep = std::min(used - b, std::max(nev + b, (used + nev) / 2));
    rotate_basis(V, used, Y, keep);
    V.middleCols(keep, b) = W;
    T.setZero();
    T.topLeftCorner(keep, keep).diagonal() = theta.head(keep);
    const Matrix coupling = R * Y.bottomRows(b).leftCols(keep);  // b x keep
    T.block(keep, 0, b, keep) = coupling;
    T.block(0, keep, keep, b) = coupling.transpose();
    used = keep + b;
    restarted = true;
    // The next projection recomputes T's newest column block (rows 0..used) from scratch, so the
    // coupling entered above in the upper part is overwritten by its recomputed value.
  }
}

}  // namespace corrlap::detail
