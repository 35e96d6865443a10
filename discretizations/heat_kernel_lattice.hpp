#pragma once
// The heat-kernel Laplacian of heat_kernel.hpp in compact form, for points on a cubic lattice
// (surfel centres of a digital surface lie on the lattice of step h/2).
//
// Equals: heat_kernel_matrix(points, mu, t, cutoff, HeatKernelForm::Symmetric, HeatKernelStorage::Full)
// (docs/math.md §6), entry for entry up to rounding, without storing its values:
//   L[s][r] = mu(s) mu(r) g(m_sr),  g(m) = exp(-m step^2 / (4t)) / (4 pi t^2),  L[s][s] = -sum_{r != s} L[s][r],
// where m_sr = |k_s - k_r|^2 is the integer squared distance of the lattice coordinates k (x = origin
// + step k). g takes one of at most (cutoff sqrt(2t) / step)^2 values, so each stored entry is a
// 4-byte column and a 2-byte index into a table of g: 6 bytes instead of the 12 of a CSC entry, and
// no exp per entry. The heat kernel couples ~2000 surfels per row at h = 0.0125 (docs/math.md §6):
// its products are memory-bound, and this halves the memory they stream.
//
// Only the product is available (Spectra's operator concept): for the forward study's Jacobi CG
// (studies/study.cpp). Anything that needs the matrix (a factorization, an eigen solver) uses
// heat_kernel_matrix. Differences from it: the cut-off test m step^2 < (cutoff sqrt(2t))^2 on exact
// lattice distances (a pair at exactly the cut-off, up to rounding, may be coupled by one and not
// by the other), and the order of the sums.
#include <Eigen/Core>
#include <Eigen/Sparse>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

namespace corrlap {

class LatticeHeatKernel {
 public:
  /// The kernel on `points` (#P by 3) with measures `mu` (#P, > 0) when every point lies within
  /// 1e-6 step of the lattice origin + step Z^3 (origin = the first point) and the table fits in
  /// 16-bit indices; std::nullopt otherwise (use heat_kernel_matrix). Throws InputError on bad
  /// inputs (as heat_kernel_matrix) and NumericalError when the entries do not fit in memory.
  ///
  /// `recycle` (optional): a kernel no longer needed whose storage is reused where large enough.
  /// Fresh memory costs a page fault and the zeroing of every page on first touch (a large part of a
  /// study unit: bench/RESULTS.md, "corrlap study"); a study builds one kernel per centre, of about
  /// the same size.
  static std::optional<LatticeHeatKernel> build(const Eigen::MatrixX3d& points, const Eigen::VectorXd& mu, double t,
                                                double cutoff, double step, LatticeHeatKernel* recycle = nullptr);

  Eigen::Index rows() const { return Eigen::Index(mu_.size()); }
  /// Stored entries, the diagonal included (= heat_kernel_matrix(...).nonZeros()).
  std::int64_t nonzeros() const { return nonzeros_; }
  /// Bytes held by the entries and the per-row data.
  std::size_t memory_bytes() const;
  /// The diagonal of L (#P).
  const Eigen::VectorXd& diagonal() const { return diagonal_; }
  /// Yt = (L X)^T for Xt = X^T (k by #P). Rows in parallel (TBB), each summed in a fixed order:
  /// the result does not depend on the thread count.
  void multiply_transposed(const Eigen::MatrixXd& Xt, Eigen::MatrixXd& Yt) const;
  /// L as a sparse matrix (Full storage, rows sorted): for tests and small inputs.
  Eigen::SparseMatrix<double> to_sparse() const;

 private:
  LatticeHeatKernel() = default;
  // Rows [first, first + count) of L: row s's off-diagonal entries are
  // column[offset[s - first] .. offset[s - first + 1]) with kernel values table_[kernel[...]].
  struct Block {
    Eigen::Index first = 0, count = 0;
    std::vector<std::uint32_t> offset;
    std::vector<std::int32_t> column;
    std::vector<std::uint16_t> kernel;
  };
  Eigen::VectorXd mu_, diagonal_;
  std::vector<double> table_;  // g(m), m = 0 .. table_.size() - 1
  std::vector<Block> blocks_;
  std::int64_t nonzeros_ = 0;
};

}  // namespace corrlap
