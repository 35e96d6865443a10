#include "heat_kernel_lattice.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <climits>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/discretizations/assembly/detail/huge_pages.hpp>
#include <corrlap/discretizations/detail/heat_kernel_inputs.hpp>
#include <new>
#include <numbers>
#include <sstream>

namespace corrlap {

namespace {

// Rows per block: blocks are the unit of parallel work and of storage, fixed so that the sums do
// not depend on the thread count; 1024 rows of ~2000 entries are ~12 MB, large enough for huge pages.
constexpr Eigen::Index kBlockRows = 1024;
// Cells are at least half the lattice cut-off radius wide: neighbours lie within +-2 cells.
constexpr int kCellReach = 2;
constexpr std::int64_t kMaxCells = std::int64_t(1) << 26;

// Points bucketed in a dense grid of cubic cells over their lattice coordinates, cells in x-major
// order, each cell's points in ascending index order.
struct LatticeCells {
  int size = 1;  // cell width in lattice units
  std::array<int, 3> lower{}, dims{};
  std::vector<std::int32_t> begin;   // cell c holds sorted entries [begin[c], begin[c + 1])
  std::vector<std::int32_t> index;   // point of each sorted entry
  std::vector<std::int32_t> coords;  // its lattice coordinates, 3 per entry (contiguous for the scan)

  std::int64_t cell_id(int cx, int cy, int cz) const { return (std::int64_t(cx) * dims[1] + cy) * dims[2] + cz; }
  std::array<int, 3> cell_of(const std::int32_t* k) const {
    return {(k[0] - lower[0]) / size, (k[1] - lower[1]) / size, (k[2] - lower[2]) / size};
  }
};

// Lattice coordinates (3 per point) of points within 1e-6 step of origin + step Z^3, or empty.
std::vector<std::int32_t> lattice_coordinates(const Eigen::MatrixX3d& x, double step) {
  const Eigen::Index n = x.rows();
  std::vector<std::int32_t> k(3 * std::size_t(n));
  bool ok = true;
  for (Eigen::Index i = 0; i < n && ok; ++i)
    for (int a = 0; a < 3; ++a) {
      const double u = (x(i, a) - x(0, a)) / step;
      if (!(std::abs(u) < double(1 << 28))) {
        ok = false;
        break;
      }
      const double r = std::round(u);
      if (std::abs(u - r) > 1e-6) {
        ok = false;
        break;
      }
      k[3 * std::size_t(i) + std::size_t(a)] = std::int32_t(r);
    }
  if (!ok) k.clear();
  return k;
}

std::optional<LatticeCells> bucket(const std::vector<std::int32_t>& k, Eigen::Index n, int size) {
  LatticeCells g;
  g.size = size;
  std::array<int, 3> upper{};
  for (int a = 0; a < 3; ++a) {
    g.lower[std::size_t(a)] = INT_MAX;
    upper[std::size_t(a)] = INT_MIN;
  }
  for (Eigen::Index i = 0; i < n; ++i)
    for (std::size_t a = 0; a < 3; ++a) {
      g.lower[a] = std::min(g.lower[a], k[3 * std::size_t(i) + a]);
      upper[a] = std::max(upper[a], k[3 * std::size_t(i) + a]);
    }
  std::int64_t cells = 1;
  for (std::size_t a = 0; a < 3; ++a) {
    g.dims[a] = (upper[a] - g.lower[a]) / size + 1;
    cells *= g.dims[a];
    if (cells > kMaxCells) return std::nullopt;  // points too sparse for a dense grid: use the readable one
  }
  // Counting sort by cell: stable, so each cell keeps ascending point order.
  std::vector<std::int32_t> cell(static_cast<std::size_t>(n));
  g.begin.assign(std::size_t(cells) + 1, 0);
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto c = g.cell_of(&k[3 * std::size_t(i)]);
    cell[std::size_t(i)] = std::int32_t(g.cell_id(c[0], c[1], c[2]));
    ++g.begin[std::size_t(cell[std::size_t(i)]) + 1];
  }
  for (std::size_t c = 0; c < std::size_t(cells); ++c) g.begin[c + 1] += g.begin[c];
  std::vector<std::int32_t> fill(g.begin.begin(), g.begin.end() - 1);
  g.index.resize(std::size_t(n));
  g.coords.resize(3 * std::size_t(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    const std::int32_t e = fill[std::size_t(cell[std::size_t(i)])]++;
    g.index[std::size_t(e)] = std::int32_t(i);
    for (std::size_t a = 0; a < 3; ++a) g.coords[3 * std::size_t(e) + a] = k[3 * std::size_t(i) + a];
  }
  return g;
}

// Appends the neighbours r != i of point i with |k_r - k_i|^2 <= max_m (columns and squared
// distances), in cell-scan order.
void lattice_neighbours(const LatticeCells& g, const std::int32_t* ki, std::int32_t i, int max_m,
                        std::vector<std::int32_t>& columns, std::vector<std::uint16_t>& kernel) {
  const auto c = g.cell_of(ki);
  const int z0 = std::max(c[2] - kCellReach, 0), z1 = std::min(c[2] + kCellReach, g.dims[2] - 1);
  for (int cx = std::max(c[0] - kCellReach, 0); cx <= std::min(c[0] + kCellReach, g.dims[0] - 1); ++cx)
    for (int cy = std::max(c[1] - kCellReach, 0); cy <= std::min(c[1] + kCellReach, g.dims[1] - 1); ++cy) {
      // The cells (cx, cy, z0..z1) are consecutive in x-major order: one run of entries.
      const std::int32_t first = g.begin[std::size_t(g.cell_id(cx, cy, z0))];
      const std::int32_t last = g.begin[std::size_t(g.cell_id(cx, cy, z1)) + 1];
      const std::size_t base = columns.size();
      columns.resize(base + std::size_t(last - first));
      kernel.resize(base + std::size_t(last - first));
      std::size_t n = base;
      for (std::int32_t e = first; e < last; ++e) {
        const std::int32_t* kr = &g.coords[3 * std::size_t(e)];
        const int dx = kr[0] - ki[0], dy = kr[1] - ki[1], dz = kr[2] - ki[2];
        const int m = dx * dx + dy * dy + dz * dz;
        const std::int32_t r = g.index[std::size_t(e)];
        columns[n] = r;
        kernel[n] = std::uint16_t(m);
        n += std::size_t((m <= max_m) & (r != i));  // branch-free: about half the candidates are rejected
      }
      columns.resize(n);
      kernel.resize(n);
    }
}

// to = from, in to's storage when it is large enough (recycled), else in fresh storage on huge
// pages with 1/8 to spare: the same block of the next centre's surface has a few more entries or a
// few less, and should fit.
template <class T>
void copy_into(std::vector<T>& to, const std::vector<T>& from) {
  if (to.capacity() < from.size()) {
    std::vector<T> fresh;
    const std::size_t capacity = from.size() + from.size() / 8;
    fresh.reserve(capacity);
    advise_huge_pages(fresh.data(), capacity * sizeof(T));
    to.swap(fresh);
  }
  to.assign(from.begin(), from.end());
}

// Row s of L X for K right-hand sides (K known at compile time: plain scalar accumulators):
// mu_s sum_r g(m_sr) (mu_r x_r) + L_ss x_s, with Xm = X^T scaled by mu.
template <int K>
void multiply_rows(const double* table, const std::uint32_t* offset, const std::int32_t* column,
                   const std::uint16_t* kernel, Eigen::Index first, Eigen::Index count, const double* mu,
                   const double* diagonal, const double* Xm, const double* Xt, double* Yt, int k) {
  const int kk = K > 0 ? K : k;
  std::array<double, 16> acc{};
  for (Eigen::Index s = 0; s < count; ++s) {
    const Eigen::Index row = first + s;
    if constexpr (K > 0) {
      double y[K] = {};
      for (std::uint32_t e = offset[s]; e < offset[s + 1]; ++e) {
        const double g = table[kernel[e]];
        const double* x = Xm + std::ptrdiff_t(K) * column[e];
        for (int c = 0; c < K; ++c) y[c] += g * x[c];
      }
      for (int c = 0; c < K; ++c) Yt[K * row + c] = mu[row] * y[c] + diagonal[row] * Xt[K * row + c];
    } else {
      for (int c0 = 0; c0 < kk; c0 += 16) {  // 16 columns at a time
        const int width = std::min(16, kk - c0);
        acc.fill(0.0);
        for (std::uint32_t e = offset[s]; e < offset[s + 1]; ++e) {
          const double g = table[kernel[e]];
          const double* x = Xm + std::ptrdiff_t(kk) * column[e] + c0;
          for (int c = 0; c < width; ++c) acc[std::size_t(c)] += g * x[c];
        }
        for (int c = 0; c < width; ++c)
          Yt[kk * row + c0 + c] = mu[row] * acc[std::size_t(c)] + diagonal[row] * Xt[kk * row + c0 + c];
      }
    }
  }
}

}  // namespace

std::optional<LatticeHeatKernel> LatticeHeatKernel::build(const Eigen::MatrixX3d& points, const Eigen::VectorXd& mu,
                                                          double t, double cutoff, double step,
                                                          LatticeHeatKernel* recycle) {
  const Eigen::Index n = points.rows();
  detail::check_heat_kernel_inputs(points, t, cutoff);  // the readable one's errors
  if (!(step > 0.0) || !std::isfinite(step)) throw InputError("heat kernel: lattice step must be a positive number");
  detail::check_heat_kernel_measures(mu, n);
  if (n > INT_MAX) return std::nullopt;

  // Coupled pairs: m step^2 < R^2 (heat_kernel.cpp's |x_r - x_s|^2 < R^2 on lattice distances).
  const double R = cutoff * std::sqrt(2.0 * t);
  const double R2 = R * R, q = step * step;
  const double m_bound = std::floor(R2 / q);
  if (!(m_bound < 65536.0)) return std::nullopt;  // the table would not fit 16-bit indices
  int max_m = int(m_bound);
  while (max_m >= 0 && !(double(max_m) * q < R2)) --max_m;
  while (double(max_m + 1) * q < R2)
    if (++max_m > 65535) return std::nullopt;
  // max_m = -1: nothing is coupled (R below the lattice step), every row holds its diagonal only.

  const std::vector<std::int32_t> k = lattice_coordinates(points, step);
  if (k.empty()) return std::nullopt;
  const int cell = std::max(1, int(std::ceil(std::sqrt(double(std::max(max_m, 0))) / kCellReach)));
  const std::optional<LatticeCells> grid = bucket(k, n, cell);
  if (!grid) return std::nullopt;

  LatticeHeatKernel L;
  L.mu_ = mu;
  const double c = 1.0 / (4.0 * std::numbers::pi * t * t);  // docs/math.md §6: 1 / (t (4 pi t)^{d/2}), d = 2
  L.table_.resize(std::size_t(max_m + 1));
  for (int m = 0; m <= max_m; ++m) L.table_[std::size_t(m)] = c * std::exp(-double(m) * q / (4.0 * t));
  L.diagonal_.resize(n);
  const Eigen::Index num_blocks = (n + kBlockRows - 1) / kBlockRows;
  if (recycle != nullptr) {
    L.blocks_.swap(recycle->blocks_);  // storage only: every block's contents are overwritten below
    *recycle = LatticeHeatKernel();
  }
  L.blocks_.resize(std::size_t(num_blocks));

  struct Scratch {
    std::vector<std::int32_t> columns;
    std::vector<std::uint16_t> kernel;
  };
  tbb::enumerable_thread_specific<Scratch> scratch;
  std::atomic<bool> out_of_memory{false};  // set from worker threads
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, num_blocks, 1), [&](const auto& range) {
    Scratch& s = scratch.local();
    for (Eigen::Index b = range.begin(); b != range.end(); ++b) {
      Block& block = L.blocks_[std::size_t(b)];
      block.first = b * kBlockRows;
      block.count = std::min(kBlockRows, n - block.first);
      s.columns.clear();
      s.kernel.clear();
      try {
        block.offset.resize(std::size_t(block.count) + 1);
        block.offset[0] = 0;
        for (Eigen::Index r = 0; r < block.count; ++r) {
          const Eigen::Index i = block.first + r;
          const std::size_t begin = s.columns.size();
          lattice_neighbours(*grid, &k[3 * std::size_t(i)], std::int32_t(i), max_m, s.columns, s.kernel);
          double row_sum = 0.0;  // sum_r mu_r g(m_ir), in the stored order
          for (std::size_t e = begin; e < s.columns.size(); ++e) row_sum += mu[s.columns[e]] * L.table_[s.kernel[e]];
          L.diagonal_[i] = -mu[i] * row_sum;
          if (s.columns.size() > std::size_t(UINT32_MAX)) throw std::bad_alloc();
          block.offset[std::size_t(r) + 1] = std::uint32_t(s.columns.size());
        }
        copy_into(block.column, s.columns);
        copy_into(block.kernel, s.kernel);
      } catch (const std::bad_alloc&) {
        out_of_memory = true;  // reported below, outside the parallel region
      }
    }
  });
  if (out_of_memory) {
    std::ostringstream os;
    os << "heat kernel: the compact lattice kernel on " << n << " points does not fit in memory (cut-off radius " << R
       << ", " << max_m + 1 << " kernel values)";
    throw NumericalError(os.str());
  }
  L.nonzeros_ = n;
  for (const Block& b : L.blocks_) L.nonzeros_ += std::int64_t(b.column.size());
  return L;
}

std::size_t LatticeHeatKernel::memory_bytes() const {
  std::size_t bytes = std::size_t(mu_.size() + diagonal_.size()) * sizeof(double) + table_.size() * sizeof(double);
  for (const Block& b : blocks_)
    bytes += b.offset.size() * sizeof(std::uint32_t) + b.column.size() * sizeof(std::int32_t) +
             b.kernel.size() * sizeof(std::uint16_t);
  return bytes;
}

void LatticeHeatKernel::multiply_transposed(const Eigen::MatrixXd& Xt, Eigen::MatrixXd& Yt) const {
  const Eigen::Index n = rows(), k = Xt.rows();
  if (Xt.cols() != n)
    throw InputError("heat kernel: product with " + std::to_string(Xt.cols()) + " values for " + std::to_string(n) +
                     " points");
  const Eigen::MatrixXd Xm = Xt * mu_.asDiagonal();  // column r scaled by mu_r: g(m) is all that remains per entry
  Yt.resize(k, n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks_.size(), 1), [&](const auto& range) {
    for (std::size_t b = range.begin(); b != range.end(); ++b) {
      const Block& B = blocks_[b];
      const auto run = [&]<int K>() {
        multiply_rows<K>(table_.data(), B.offset.data(), B.column.data(), B.kernel.data(), B.first, B.count, mu_.data(),
                         diagonal_.data(), Xm.data(), Xt.data(), Yt.data(), int(k));
      };
      switch (k) {  // the study's three test functions, one and two right-hand sides
        case 1:
          run.template operator()<1>();
          break;
        case 2:
          run.template operator()<2>();
          break;
        case 3:
          run.template operator()<3>();
          break;
        default:
          run.template operator()<0>();
      }
    }
  });
}

Eigen::SparseMatrix<double> LatticeHeatKernel::to_sparse() const {
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(std::size_t(nonzeros_));
  for (const Block& B : blocks_)
    for (Eigen::Index s = 0; s < B.count; ++s) {
      const Eigen::Index row = B.first + s;
      for (std::uint32_t e = B.offset[std::size_t(s)]; e < B.offset[std::size_t(s) + 1]; ++e)
        entries.emplace_back(int(row), B.column[e], mu_[row] * mu_[B.column[e]] * table_[B.kernel[e]]);
      entries.emplace_back(int(row), int(row), diagonal_[row]);
    }
  Eigen::SparseMatrix<double> L(rows(), rows());
  L.setFromTriplets(entries.begin(), entries.end());
  return L;
}

}  // namespace corrlap
