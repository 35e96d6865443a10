#pragma once
// Block Lanczos for the largest eigenvalues of an operator S that is self-adjoint in the M inner
// product (internal; the engine of the shift-invert eigen solver, backends/spectra_eigs.cpp).
// With S = (K - sigma M)^{-1} M the largest theta = 1 / (mu - sigma) are the mu nearest sigma.
//
// Why blocks: a single-vector Lanczos (Spectra) orthogonalizes each new vector against the whole
// basis with matrix-vector products, which stream the basis from memory once per vector, the
// largest part of a large solve (docs/backends.md, "Why blocks"). A block of b vectors does the same work as
// matrix-matrix products (one pass over the basis per block) and its b-column solves run as BLAS-3
// in CHOLMOD. A block also sees up to b copies of a multiple eigenvalue at once, where one vector
// sees the extra copies only through rounding.
//
// Method: full reorthogonalization (classical Gram-Schmidt twice in the M inner product), new
// blocks M-orthonormalized by Cholesky QR twice, Rayleigh-Ritz on the projected matrix
// T = V^T M S V, thick restart (the best Ritz vectors kept) when the basis is full. The M-image of
// the newest block is carried along (updated by the QR factor, not recomputed): three products
// with M per block step.
#include <Eigen/Core>
#include <Eigen/Sparse>
#include <functional>

namespace corrlap::detail {

struct BlockLanczosOptions {
  int block_size = 16;
  int max_basis = 0;  ///< 0: max(3 nev, nev + 8 block_size), at most n
  int max_restarts = 100;
  double tolerance = 1e-10;  ///< a pair converges when |S x - theta x|_M <= tolerance |theta|
  int wanted = 0;            ///< the first `wanted` pairs must converge (0: all nev)
  unsigned seed = 12345;     ///< of the random start block (fixed: reproducible results)
  /// Optional: called after each Rayleigh-Ritz step (once the basis holds nev + block_size vectors)
  /// with the nev largest Ritz values and their residual norms; true ends the run early with those
  /// pairs (`stopped`). For a question the first pairs answer before they converge.
  std::function<bool(const Eigen::VectorXd& theta, const Eigen::VectorXd& residuals)> stop;
};

struct BlockLanczosResult {
  Eigen::VectorXd theta;      ///< nev largest eigenvalues of S, descending
  Eigen::MatrixXd vectors;    ///< n x nev, M-orthonormal
  Eigen::VectorXd residuals;  ///< |S x - theta x|_M of each pair
  int restarts = 0;
  int block_steps = 0;
  bool converged = false;  ///< false: the basis lost rank or the restarts ran out (use another method)
  bool stopped = false;    ///< ended by options.stop before converging
};

/// `apply` maps the M-image B = M X of an n x b block X to S X (n = M.rows()): the caller's S is
/// (K - sigma M)^{-1} M, whose M X the iteration has at hand. Needs nev + block_size < n.
BlockLanczosResult block_lanczos(const std::function<Eigen::MatrixXd(const Eigen::MatrixXd&)>& apply,
                                 const Eigen::SparseMatrix<double>& M, int nev, const BlockLanczosOptions& options);

}  // namespace corrlap::detail
