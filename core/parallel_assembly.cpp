#include "parallel_assembly.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <sstream>

#if defined(__linux__)
#include <sys/mman.h>
#endif

#include "error.hpp"

namespace corrlap {

AssemblyPlan::AssemblyPlan(const int* ids, std::size_t num_elements, int k, int n, const std::int8_t* signs)
    : k_(k), n_(n), num_elements_(num_elements) {
  if (k <= 0 || n < 0) throw InputError("assembly: invalid local size or matrix size");
  const std::size_t kk = std::size_t(k) * std::size_t(k);
  // Column counts of the pattern: for column c, the distinct rows coupled to it.
  // Build per-column contribution lists first (counting sort by column), then dedupe rows.
  std::vector<std::int64_t> col_count(std::size_t(n) + 1, 0);
  for (std::size_t e = 0; e < num_elements; ++e)
    for (int j = 0; j < k; ++j) {
      const int c = ids[e * k + j];
      if (c < 0 || c >= n) {
        std::ostringstream os;
        os << "assembly: element " << e << " refers to index " << c << " outside [0, " << n << ")";
        throw InputError(os.str());
      }
      col_count[std::size_t(c) + 1] += k;
    }
  for (int c = 0; c < n; ++c) col_count[std::size_t(c) + 1] += col_count[std::size_t(c)];
  // entries sorted by (column, element, j, i) via counting sort on columns; element order kept.
  // Stored directly in contributions_ (one buffer instead of two: the sort below is per column,
  // in place, each column's range being read into a thread-local buffer before it is rewritten).
  std::vector<std::int64_t> fill(col_count.begin(), col_count.end() - 1);
  contributions_.resize(std::size_t(col_count[std::size_t(n)]));
  std::int64_t* local = contributions_.data();
  for (std::size_t e = 0; e < num_elements; ++e)
    for (int j = 0; j < k; ++j) {
      const int c = ids[e * k + j];
      for (int i = 0; i < k; ++i) local[std::size_t(fill[std::size_t(c)]++)] = std::int64_t(e * kk + std::size_t(i) * k + j);
    }
  std::vector<std::int64_t>().swap(fill);
  // Per column, in parallel: sort the contributions by (row, local index) in place (the column's
  // range of contributions_ is its range of `local`), count distinct rows; then a prefix sum and
  // a parallel fill of rows and entry starts. Same layout as a sequential pass, for any thread count.
  std::vector<int> outer(std::size_t(n) + 1, 0);
  tbb::enumerable_thread_specific<std::vector<std::pair<int, std::int64_t>>> bufs;
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 1024), [&](const tbb::blocked_range<int>& r) {
    auto& buf = bufs.local();
    for (int c = r.begin(); c != r.end(); ++c) {
      const std::int64_t a0 = col_count[std::size_t(c)], a1 = col_count[std::size_t(c) + 1];
      buf.clear();
      for (std::int64_t a = a0; a < a1; ++a) {
        const std::int64_t idx = local[std::size_t(a)];
        const std::size_t e = std::size_t(idx) / kk;
        const int i = int((std::size_t(idx) % kk) / std::size_t(k));
        buf.emplace_back(ids[e * k + i], idx);
      }
      std::sort(buf.begin(), buf.end());
      int distinct = 0;
      for (std::size_t t = 0; t < buf.size(); ++t) {
        if (t == 0 || buf[t].first != buf[t - 1].first) ++distinct;
        std::int64_t sgn = 1;
        if (signs) {
          const std::size_t idx = std::size_t(buf[t].second), e = idx / kk;
          const int i = int((idx % kk) / std::size_t(k)), j = int(idx % std::size_t(k));
          sgn = std::int64_t(signs[e * k + i]) * std::int64_t(signs[e * k + j]);
        }
        contributions_[std::size_t(a0) + t] = (buf[t].second + 1) * sgn;
      }
      outer[std::size_t(c) + 1] = distinct;
    }
  });
  for (int c = 0; c < n; ++c) outer[std::size_t(c) + 1] += outer[std::size_t(c)];
  const std::size_t nnz = std::size_t(outer[std::size_t(n)]);
  std::vector<int> inner(nnz);
  start_.resize(nnz + 1);
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 1024), [&](const tbb::blocked_range<int>& r) {
    for (int c = r.begin(); c != r.end(); ++c) {
      std::size_t s = std::size_t(outer[std::size_t(c)]);
      int prev = -1;
      for (std::int64_t a = col_count[std::size_t(c)]; a < col_count[std::size_t(c) + 1]; ++a) {
        const std::int64_t cc = contributions_[std::size_t(a)];
        const std::size_t idx = std::size_t((cc > 0 ? cc : -cc) - 1), e = idx / kk;
        const int row = ids[e * k + int((idx % kk) / std::size_t(k))];
        if (a == col_count[std::size_t(c)] || row != prev) {
          inner[s] = row;
          start_[s++] = a;
          prev = row;
        }
      }
    }
  });
  start_[nnz] = std::int64_t(contributions_.size());
  pattern_.resize(n, n);
  pattern_.resizeNonZeros(Eigen::Index(inner.size()));
  std::copy(outer.begin(), outer.end(), pattern_.outerIndexPtr());
  std::copy(inner.begin(), inner.end(), pattern_.innerIndexPtr());
  std::fill(pattern_.valuePtr(), pattern_.valuePtr() + inner.size(), 0.0);
}

void advise_huge_pages(const void* p, std::size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  constexpr std::uintptr_t huge = std::uintptr_t(2) << 20;
  static const bool disabled = std::getenv("CORRLAP_NO_HUGEPAGES") != nullptr;
  if (disabled || bytes < 2 * huge) return;
  const std::uintptr_t b = (reinterpret_cast<std::uintptr_t>(p) + huge - 1) & ~(huge - 1);
  const std::uintptr_t e = (reinterpret_cast<std::uintptr_t>(p) + bytes) & ~(huge - 1);
  if (e > b) (void)madvise(reinterpret_cast<void*>(b), e - b, MADV_HUGEPAGE);  // a hint: failure is harmless
#else
  (void)p;
  (void)bytes;
#endif
}

Eigen::SparseMatrix<double> AssemblyPlan::gather(const double* locals) const {
  Eigen::SparseMatrix<double> A = pattern_;
  double* values = A.valuePtr();
  const Eigen::Index nnz = A.nonZeros();
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, nnz, 4096), [&](const tbb::blocked_range<Eigen::Index>& r) {
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
  std::vector<double> locals(plan.num_elements() * kk);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, plan.num_elements(), 1024),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      kernel(r.begin(), r.end(), locals.data() + r.begin() * kk);
                    });
  return plan.gather(locals.data());
}

}  // namespace corrlap
