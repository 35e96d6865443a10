#include "solver_support.hpp"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>

namespace corrlap::detail {

namespace {
// Columns are split into this many blocks, whatever the thread count: per-block results combined
// in block order do not depend on how TBB schedules the blocks.
constexpr Eigen::Index kColumnBlocks = 64;

Eigen::Index block_begin(Eigen::Index n, Eigen::Index b) { return n * b / kColumnBlocks; }

// f(j) summed over the columns of each block, in parallel; one sum per block.
template <class PerColumn>
std::vector<double> column_block_sums(const Eigen::SparseMatrix<double>& A, const PerColumn& f) {
  const Eigen::Index n = A.outerSize();
  std::vector<double> sums(static_cast<std::size_t>(kColumnBlocks), 0.0);
  tbb::parallel_for(Eigen::Index(0), kColumnBlocks, [&](Eigen::Index b) {
    double s = 0.0;
    for (Eigen::Index j = block_begin(n, b); j < block_begin(n, b + 1); ++j) s += f(j);
    sums[std::size_t(b)] = s;
  });
  return sums;
}
}  // namespace

void check_matrix(const Eigen::SparseMatrix<double>& A, const std::string& solver, bool check_symmetry) {
  if (A.rows() != A.cols() || A.rows() == 0) {
    std::ostringstream os;
    os << solver << ": matrix must be square and non-empty, got " << A.rows() << " x " << A.cols();
    throw SolverError(SolverStatus::InvalidInput, os.str());
  }
  // One parallel pass: squared norms per fixed block of columns (summed in block order, so the
  // norm does not depend on the thread count); a NaN or infinity makes its block's sum non-finite.
  const std::vector<double> squares = column_block_sums(A, [&](Eigen::Index j) {
    double sum = 0.0;
    for (Eigen::SparseMatrix<double>::InnerIterator it(A, j); it; ++it) sum += it.value() * it.value();
    return sum;
  });
  double norm2 = 0.0;
  for (const double b : squares) norm2 += b;
  if (!std::isfinite(norm2))  // find the entry to name (the rare path)
    for (Eigen::Index j = 0; j < A.outerSize(); ++j)
      for (Eigen::SparseMatrix<double>::InnerIterator it(A, j); it; ++it)
        if (!std::isfinite(it.value())) {
          std::ostringstream os;
          os << solver << ": matrix entry (" << it.row() << ", " << it.col() << ") is " << it.value();
          throw SolverError(SolverStatus::NumericalIssue, os.str());
        }
  if (check_symmetry) {
    // A copy-free check: the heat kernel's matrices have ~2000 entries per row, and forming A^T
    // and A - A^T doubled the memory of a solve (bench/RESULTS.md, "corrlap study").
    const double norm = std::sqrt(norm2);  // large finite entries may still overflow the sum
    if (!std::isfinite(norm)) throw SolverError(SolverStatus::NumericalIssue, solver + ": the matrix norm overflows");
    const double diff = symmetry_defect(A);
    if (diff > 1e-10 * norm) {
      std::ostringstream os;
      os << solver << ": matrix is not symmetric (|A - A^T| / |A| = " << diff / norm << ")";
      throw SolverError(SolverStatus::InvalidInput, os.str());
    }
  }
}

double symmetry_defect(const Eigen::SparseMatrix<double>& A) {
  if (A.rows() != A.cols()) return std::numeric_limits<double>::infinity();
  if (!A.isCompressed()) {
    Eigen::SparseMatrix<double> compressed = A;
    compressed.makeCompressed();
    return symmetry_defect(compressed);
  }
  const Eigen::Index n = A.outerSize();
  const int* outer = A.outerIndexPtr();
  const int* inner = A.innerIndexPtr();
  const double* value = A.valuePtr();
  // Each pair {(i, j), (j, i)}, i > j, is counted once, by the block of columns holding j:
  //  - the lower entries (i, j) of the block's columns, in ascending j, meet their mirrors (j, i)
  //    in column i in ascending row order j. A cursor per column i walks its rows from the
  //    block's first column j0 on (started by a binary search); rows it skips have no mirror;
  //  - then the upper entries (r, i), r < i, with rows r in the block that no cursor reached
  //    have no mirror either.
  // Blocks run in parallel, each with its own cursors; their sums are added in block order.
  struct Cursors {
    std::vector<int> position, block;
  };
  tbb::enumerable_thread_specific<Cursors> scratch([n] {
    return Cursors{std::vector<int>(std::size_t(n)), std::vector<int>(std::size_t(n), -1)};
  });
  // The block's sum; `sweep`: also the unreached upper entries. `reached` counts the upper entries
  // the cursors met (matched or skipped), `upper` the upper entries of the block's columns.
  struct BlockResult {
    double sum = 0.0;
    std::int64_t reached = 0, upper = 0;
  };
  const auto block_defect = [&](Eigen::Index b, bool sweep) {
    Cursors& cur = scratch.local();
    const int j0 = int(block_begin(n, b)), j1 = int(block_begin(n, b + 1));
    const auto start = [&](int i) {  // first entry of column i with row >= j0
      if (cur.block[std::size_t(i)] != int(b) + (sweep ? int(kColumnBlocks) : 0)) {
        cur.block[std::size_t(i)] = int(b) + (sweep ? int(kColumnBlocks) : 0);
        cur.position[std::size_t(i)] = int(std::lower_bound(inner + outer[i], inner + outer[i + 1], j0) - inner);
      }
      return cur.position[std::size_t(i)];
    };
    BlockResult r;
    for (int j = j0; j < j1; ++j)
      for (int k = outer[j]; k < outer[j + 1]; ++k) {
        const int i = inner[k];
        r.upper += i < j;
        if (i <= j) continue;  // the upper part is met through the cursors
        int c = start(i);
        for (; c < outer[i + 1] && inner[c] < j; ++c, ++r.reached) r.sum += 2.0 * value[c] * value[c];
        if (c < outer[i + 1] && inner[c] == j) {
          const double d = value[k] - value[c];
          r.sum += 2.0 * d * d;  // (i, j) and (j, i)
          ++c;
          ++r.reached;
        } else {
          r.sum += 2.0 * value[k] * value[k];  // (i, j) without mirror
        }
        cur.position[std::size_t(i)] = c;
      }
    if (sweep)  // upper entries (r, i) with r in [j0, j1), r < i, that no cursor reached
      for (int i = j0 + 1; i < int(n); ++i)
        for (int c = start(i); c < outer[i + 1] && inner[c] < std::min(j1, i); ++c) r.sum += 2.0 * value[c] * value[c];
    return r;
  };
  std::vector<BlockResult> blocks(static_cast<std::size_t>(kColumnBlocks));
  tbb::parallel_for(Eigen::Index(0), kColumnBlocks,
                    [&](Eigen::Index b) { blocks[std::size_t(b)] = block_defect(b, false); });
  std::int64_t reached = 0, upper = 0;
  for (const BlockResult& r : blocks) {
    reached += r.reached;
    upper += r.upper;
  }
  // Every upper entry reached (the usual case, a symmetric pattern): nothing left to sweep. Else
  // the blocks again with the sweep (the counts are integers: the test is exact).
  if (reached != upper)
    tbb::parallel_for(Eigen::Index(0), kColumnBlocks,
                      [&](Eigen::Index b) { blocks[std::size_t(b)] = block_defect(b, true); });
  double sum = 0.0;
  for (const BlockResult& r : blocks) sum += r.sum;  // in block order: independent of the threads
  return std::sqrt(sum);
}

void check_rhs(const Eigen::MatrixXd& B, Eigen::Index n, const std::string& solver) {
  if (B.rows() != n) {
    std::ostringstream os;
    os << solver << ": right-hand side has " << B.rows() << " rows, the factored matrix has " << n;
    throw SolverError(SolverStatus::InvalidInput, os.str());
  }
  for (Eigen::Index j = 0; j < B.cols(); ++j)
    for (Eigen::Index i = 0; i < B.rows(); ++i)
      if (!std::isfinite(B(i, j))) {
        std::ostringstream os;
        os << solver << ": right-hand side entry (" << i << ", " << j << ") is " << B(i, j);
        throw SolverError(SolverStatus::NumericalIssue, os.str());
      }
}

namespace {
// FNV-1a over the 32-bit words of the pattern, column by column: the column lengths, then the row
// indices. Stored entries are walked through the column lengths, so an uncompressed matrix hashes
// like its compressed form without a copy.
std::uint64_t pattern_hash(const Eigen::SparseMatrix<double>& A) {
  constexpr std::uint64_t kBasis = 1469598103934665603ull, kPrime = 1099511628211ull;
  const auto mix = [](std::uint64_t& h, std::uint64_t w) {
    h ^= w;
    h *= kPrime;
  };
  // One FNV-1a hash per fixed block of columns (in parallel), then a hash of the block hashes.
  const Eigen::Index n = A.outerSize();
  std::vector<std::uint64_t> blocks(static_cast<std::size_t>(kColumnBlocks));
  tbb::parallel_for(Eigen::Index(0), kColumnBlocks, [&](Eigen::Index b) {
    std::uint64_t h = kBasis;
    const int* nnz = A.innerNonZeroPtr();
    for (Eigen::Index j = block_begin(n, b); j < block_begin(n, b + 1); ++j) {
      const Eigen::Index begin = A.outerIndexPtr()[j];
      const Eigen::Index count = nnz ? nnz[j] : A.outerIndexPtr()[j + 1] - begin;
      mix(h, std::uint32_t(count));
      const int* rows = A.innerIndexPtr() + begin;
      for (Eigen::Index e = 0; e < count; ++e) mix(h, std::uint32_t(rows[e]));
    }
    blocks[std::size_t(b)] = h;
  });
  std::uint64_t h = kBasis;
  for (const std::uint64_t b : blocks) mix(h, b);
  return h;
}
}  // namespace

void Pattern::assign(const Eigen::SparseMatrix<double>& A) {
  rows = A.rows();
  cols = A.cols();
  nonzeros = A.nonZeros();
  hash = pattern_hash(A);
}

bool Pattern::matches(const Eigen::SparseMatrix<double>& A) const {
  return A.rows() == rows && A.cols() == cols && A.nonZeros() == nonzeros && pattern_hash(A) == hash;
}

void check_same_pattern(const Pattern& analyzed, const Eigen::SparseMatrix<double>& A, const std::string& solver) {
  if (analyzed.empty()) throw SolverError(SolverStatus::NotAnalyzed, solver + ": factorize() called before analyze()");
  if (!analyzed.matches(A)) {
    std::ostringstream os;
    os << solver << ": factorize() got a matrix (" << A.rows() << " x " << A.cols() << ", " << A.nonZeros()
       << " nonzeros) whose sparsity pattern differs from the analyzed one (" << analyzed.rows << " x " << analyzed.cols
       << ", " << analyzed.nonzeros << " nonzeros); call analyze() again";
    throw SolverError(SolverStatus::InvalidInput, os.str());
  }
}

std::vector<std::string> allowed_keys(const std::vector<ParameterInfo>& options) {
  std::vector<std::string> keys{"solver"};
  for (const auto& o : options) keys.push_back(o.name);
  return keys;
}

Config without_keys(const Config& config, const std::vector<std::string>& drop) {
  std::vector<std::string> items;
  for (const auto& k : config.keys())
    if (std::find(drop.begin(), drop.end(), k) == drop.end()) items.push_back(k + "=" + config.get_string(k, ""));
  return Config::from_key_values(items);
}

double relative_residual(const Eigen::SparseMatrix<double>& A, const Eigen::MatrixXd& X, const Eigen::MatrixXd& B) {
  const double nb = B.norm();
  const double nr = (A * X - B).norm();
  return nb > 0 ? nr / nb : nr;
}

}  // namespace corrlap::detail
