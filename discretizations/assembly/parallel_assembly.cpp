#include "parallel_assembly.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <corrlap/discretizations/assembly/detail/huge_pages.hpp>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <sstream>

#if defined(__linux__)
#include <sys/mman.h>
#endif

#include <corrlap/core/error.hpp>

namespace corrlap {

namespace {
// Number of column blocks for the incidence counting sort: enough for every thread, few enough
// that each block's full scan of the ids stays cheap. The result does not depend on it.
int column_blocks(int n) {
  const int t = int(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  return std::max(1, std::min({t, 16, n / 4096 + 1}));
}
}  // namespace

AssemblyPlan::AssemblyPlan(const int* ids, std::size_t num_elements, int k, int n, const std::int8_t* signs)
    : k_(k), n_(n), num_elements_(num_elements) {
  if (k <= 0 || n < 0) throw InputError("assembly: invalid local size or matrix size");
  const std::size_t kk = std::size_t(k) * std::size_t(k);
  const std::size_t m = num_elements * std::size_t(k);  // (element, local index) incidences
  // Range check in parallel; the first offending incidence in element order is reported, as a
  // sequential scan would.
  const std::size_t bad = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, m, 1 << 16), m,
      [&](const tbb::blocked_range<std::size_t>& r, std::size_t acc) {
        for (std::size_t a = r.begin(); a != r.end(); ++a)
          if (ids[a] < 0 || ids[a] >= n) return std::min(acc, a);
        return acc;
      },
      [](std::size_t x, std::size_t y) { return std::min(x, y); });
  if (bad < m) {
    std::ostringstream os;
    os << "assembly: element " << bad / std::size_t(k) << " refers to index " << ids[bad] << " outside [0, " << n
       << ")";
    throw InputError(os.str());
  }
  // Column incidence: for column c, the incidences a = e k + j with ids[a] == c, ascending, by a
  // counting sort done per block of columns: every task scans all ids but counts and places only
  // its own columns, so no counter is shared (no atomic) and the layout does not depend on the
  // number of blocks or threads.
  const int P = column_blocks(n);
  auto block_begin = [&](int b) { return int(std::int64_t(n) * b / P); };
  std::vector<std::int64_t> col(std::size_t(n) + 1, 0);
  tbb::parallel_for(0, P, [&](int b) {
    const int c0 = block_begin(b), c1 = block_begin(b + 1);
    std::int64_t* count = col.data() + 1;
    for (std::size_t a = 0; a < m; ++a) {
      const int c = ids[a];
      if (c >= c0 && c < c1) ++count[c];
    }
  });
  for (int c = 0; c < n; ++c) col[std::size_t(c) + 1] += col[std::size_t(c)];
  std::vector<std::int64_t, UninitAllocator<std::int64_t>> incidence(m);
  advise_huge_pages(incidence.data(), m * sizeof(std::int64_t));
  tbb::parallel_for(0, P, [&](int b) {
    const int c0 = block_begin(b), c1 = block_begin(b + 1);
    std::vector<std::int64_t> fill(col.begin() + c0, col.begin() + c1);
    for (std::size_t a = 0; a < m; ++a) {
      const int c = ids[a];
      if (c >= c0 && c < c1) incidence[std::size_t(fill[std::size_t(c - c0)]++)] = std::int64_t(a);
    }
  });
  // Per column, in parallel: its contributions (k per incidence, so column c starts at k col[c]
  // in contributions_) sorted by (row, local entry index) -- a unique key, so the order does not
  // depend on how they were collected -- and the number of distinct rows.
  contributions_.resize(m * std::size_t(k));
  advise_huge_pages(contributions_.data(), contributions_.size() * sizeof(std::int64_t));
  pattern_.resize(n, n);  // outer index zeroed
  int* outer = pattern_.outerIndexPtr();
  tbb::enumerable_thread_specific<std::vector<std::pair<int, std::int64_t>>> bufs;
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 1024), [&](const tbb::blocked_range<int>& r) {
    auto& buf = bufs.local();
    for (int c = r.begin(); c != r.end(); ++c) {
      buf.clear();
      for (std::int64_t a = col[std::size_t(c)]; a < col[std::size_t(c) + 1]; ++a) {
        const std::size_t flat = std::size_t(incidence[std::size_t(a)]);
        const std::size_t e = flat / std::size_t(k);
        const int j = int(flat % std::size_t(k));
        for (int i = 0; i < k; ++i) buf.emplace_back(ids[e * k + i], std::int64_t(e * kk + std::size_t(i) * k + j));
      }
      std::sort(buf.begin(), buf.end());
      int distinct = 0;
      std::int64_t* dst = contributions_.data() + std::size_t(k) * std::size_t(col[std::size_t(c)]);
      for (std::size_t t = 0; t < buf.size(); ++t) {
        if (t == 0 || buf[t].first != buf[t - 1].first) ++distinct;
        std::int64_t sgn = 1;
        if (signs) {
          const std::size_t idx = std::size_t(buf[t].second), e = idx / kk;
          const int i = int((idx % kk) / std::size_t(k)), j = int(idx % std::size_t(k));
          sgn = std::int64_t(signs[e * k + i]) * std::int64_t(signs[e * k + j]);
        }
        dst[t] = (buf[t].second + 1) * sgn;
      }
      outer[c + 1] = distinct;
    }
  });
  decltype(incidence)().swap(incidence);
  for (int c = 0; c < n; ++c) outer[c + 1] += outer[c];
  const std::size_t nnz = std::size_t(outer[n]);
  pattern_.resizeNonZeros(Eigen::Index(nnz));
  int* inner = pattern_.innerIndexPtr();
  double* values = pattern_.valuePtr();
  start_.resize(nnz + 1);
  advise_huge_pages(inner, nnz * sizeof(int));
  advise_huge_pages(values, nnz * sizeof(double));
  advise_huge_pages(start_.data(), (nnz + 1) * sizeof(std::int64_t));
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 1024), [&](const tbb::blocked_range<int>& r) {
    for (int c = r.begin(); c != r.end(); ++c) {
      std::size_t s = std::size_t(outer[c]);
      int prev = -1;
      const std::int64_t a0 = std::int64_t(k) * col[std::size_t(c)], a1 = std::int64_t(k) * col[std::size_t(c) + 1];
      for (std::int64_t a = a0; a < a1; ++a) {
        const std::int64_t cc = contributions_[std::size_t(a)];
        const std::size_t idx = std::size_t((cc > 0 ? cc : -cc) - 1), e = idx / kk;
        const int row = ids[e * k + int((idx % kk) / std::size_t(k))];
        if (a == a0 || row != prev) {
          inner[s] = row;
          values[s] = 0.0;
          start_[s++] = a;
          prev = row;
        }
      }
    }
  });
  start_[nnz] = std::int64_t(contributions_.size());
}

Eigen::SparseMatrix<double> AssemblyPlan::gather(const double* locals) const {
  // A fresh matrix filled in one parallel pass (row indices copied where the values are
  // written), rather than a serial copy of the pattern followed by the values.
  const Eigen::Index nnz = pattern_.nonZeros();
  Eigen::SparseMatrix<double> A(n_, n_);
  A.resizeNonZeros(nnz);
  advise_huge_pages(A.valuePtr(), std::size_t(nnz) * sizeof(double));
  advise_huge_pages(A.innerIndexPtr(), std::size_t(nnz) * sizeof(int));
  std::copy(pattern_.outerIndexPtr(), pattern_.outerIndexPtr() + n_ + 1, A.outerIndexPtr());
  double* values = A.valuePtr();
  int* inner = A.innerIndexPtr();
  const int* pin = pattern_.innerIndexPtr();
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, nnz, 4096), [&](const tbb::blocked_range<Eigen::Index>& r) {
    std::copy(pin + r.begin(), pin + r.end(), inner + r.begin());
    for (Eigen::Index s = r.begin(); s != r.end(); ++s) {
      double sum = 0.0;
      for (std::int64_t a = start_[std::size_t(s)]; a < start_[std::size_t(s) + 1]; ++a) {
        const std::int64_t c = contributions_[std::size_t(a)];
        sum += c > 0 ? locals[c - 1] : -locals[-c - 1];
      }
      values[s] = sum;
    }
  });
  return A;
}

Eigen::SparseMatrix<double> assemble(const AssemblyPlan& plan, const LocalKernel& kernel) {
  const std::size_t kk = std::size_t(plan.local_size()) * std::size_t(plan.local_size());
  // Uninitialized: the kernel writes every value, in parallel (first touch spread over threads).
  const std::size_t count = plan.num_elements() * kk;
  std::unique_ptr<double[]> locals(new double[count]);
  advise_huge_pages(locals.get(), count * sizeof(double));
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, plan.num_elements(), 1024),
      [&](const tbb::blocked_range<std::size_t>& r) { kernel(r.begin(), r.end(), locals.get() + r.begin() * kk); });
  return plan.gather(locals.get());
}

}  // namespace corrlap
