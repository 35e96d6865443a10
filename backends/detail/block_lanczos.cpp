#include "block_lanczos.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <random>

namespace corrlap::detail {

namespace {

using Matrix = Eigen::MatrixXd;

/// W = Q R with Q^T M Q = I (Cholesky QR, twice: one pass leaves an orthogonality error of about
/// eps * cond(W)^2, the second brings it to eps). False when W is (numerically) rank deficient.
bool m_orthonormalize(const Eigen::SparseMatrix<double>& M, Matrix& W, Matrix& R) {
  R = Matrix::Identity(W.cols(), W.cols());
  for (int pass = 0; pass < 2; ++pass) {
    const Matrix G = W.transpose() * (M * W);
    Eigen::LLT<Matrix> llt(0.5 * (G + G.transpose()));
    if (llt.info() != Eigen::Success) return false;
    const Matrix U = llt.matrixU();
    // A pivot far below the largest: the block has (almost) lost a direction.
    const double largest = U.diagonal().cwiseAbs().maxCoeff();
    if (!(U.diagonal().cwiseAbs().minCoeff() > 1e-10 * largest)) return false;
    W = llt.matrixU().solve<Eigen::OnTheRight>(W);  // W U^{-1}
    R = U * R;
  }
  return true;
}

/// W <- W - V (V^T M W), twice (classical Gram-Schmidt with reorthogonalization); returns the sum of
/// the coefficients, the column block of T = V^T M S V when W = S V_j.
Matrix project_out(const Eigen::SparseMatrix<double>& M, const Eigen::Ref<const Matrix>& V, Matrix& W) {
  Matrix coefficients = Matrix::Zero(V.cols(), W.cols());
  for (int pass = 0; pass < 2; ++pass) {
    const Matrix P = V.transpose() * (M * W);
    W.noalias() -= V * P;
    coefficients += P;
  }
  return coefficients;
}

}  // namespace

BlockLanczosResult block_lanczos(const std::function<Matrix(const Matrix&)>& apply,
                                 const Eigen::SparseMatrix<double>& M, int nev, const BlockLanczosOptions& options) {
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
  if (!m_orthonormalize(M, block, R)) return result;
  V.leftCols(b) = block;
  int used = b;

  for (;;) {
    // Next block: S applied to the newest block, made M-orthogonal to the whole basis.
    const int first = used - b;
    Matrix W = apply(V.middleCols(first, b));
    ++result.block_steps;
    T.block(0, first, used, b) = project_out(M, V.leftCols(used), W);
    if (!m_orthonormalize(M, W, R)) return result;  // an invariant subspace or a breakdown

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
      const int wanted = options.wanted > 0 ? std::min(options.wanted, nev) : nev;
      const Matrix residuals = R * Y.bottomRows(b).leftCols(wanted);
      bool all = true;
      for (int i = 0; i < wanted && all; ++i) all = residuals.col(i).norm() <= options.tolerance * std::abs(theta[i]);
      if (all) {
        result.theta = theta.head(nev);
        result.vectors = V.leftCols(used) * Y.leftCols(nev);
        result.converged = true;
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
    const Matrix kept = V.leftCols(used) * Y.leftCols(keep);
    V.leftCols(keep) = kept;
    V.middleCols(keep, b) = W;
    T.setZero();
    T.topLeftCorner(keep, keep).diagonal() = theta.head(keep);
    const Matrix coupling = R * Y.bottomRows(b).leftCols(keep);  // b x keep
    T.block(keep, 0, b, keep) = coupling;
    T.block(0, keep, keep, b) = coupling.transpose();
    used = keep + b;
    // The next projection recomputes T's newest column block (rows 0..used) from scratch, so the
    // coupling entered above in the upper part is overwritten by its recomputed value.
  }
}

}  // namespace corrlap::detail
