#include "parallel_assembly.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <sstream>

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
  std::vector<std::int64_t> fill(col_count.begin(), col_count.end() - 1);
  std::vector<std::int64_t> local(std::size_t(col_count[std::size_t(n)]));
  for (std::size_t e = 0; e < num_elements; ++e)
    for (int j = 0; j < k; ++j) {
      const int c = ids[e * k + j];
      for (int i = 0; i < k; ++i) local[std::size_t(fill[std::size_t(c)]++)] = std::int64_t(e * kk + std::size_t(i) * k + j);
    }
  // Per column: sort contributions by (row, local index) to get distinct rows in order.
  std::vector<int> outer(std::size_t(n) + 1, 0);
  std::vector<int> inner;
  inner.reserve(local.size() / 2);
  start_.reserve(local.size() / 2 + 1);
  contributions_.resize(local.size());
  std::int64_t out = 0;
  std::vector<std::pair<int, std::int64_t>> buf;
  for (int c = 0; c < n; ++c) {
    buf.clear();
    for (std::int64_t a = col_count[std::size_t(c)]; a < col_count[std::size_t(c) + 1]; ++a) {
      const std::int64_t idx = local[std::size_t(a)];
      const std::size_t e = std::size_t(idx) / kk;
      const int i = int((std::size_t(idx) % kk) / std::size_t(k));
      buf.emplace_back(ids[e * k + i], idx);
    }
    std::sort(buf.begin(), buf.end());
    for (std::size_t b = 0; b < buf.size(); ++b) {
      if (b == 0 || buf[b].first != buf[b - 1].first) {
        inner.push_back(buf[b].first);
        start_.push_back(out);
      }
      std::int64_t sgn = 1;
      if (signs) {
        const std::size_t idx = std::size_t(buf[b].second), e = idx / kk;
        const int i = int((idx % kk) / std::size_t(k)), j = int(idx % std::size_t(k));
        sgn = std::int64_t(signs[e * k + i]) * std::int64_t(signs[e * k + j]);
      }
      contributions_[std::size_t(out++)] = (buf[b].second + 1) * sgn;
    }
    outer[std::size_t(c) + 1] = int(inner.size());
  }
  start_.push_back(out);
  pattern_.resize(n, n);
  pattern_.resizeNonZeros(Eigen::Index(inner.size()));
  std::copy(outer.begin(), outer.end(), pattern_.outerIndexPtr());
  std::copy(inner.begin(), inner.end(), pattern_.innerIndexPtr());
  std::fill(pattern_.valuePtr(), pattern_.valuePtr() + inner.size(), 0.0);
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
