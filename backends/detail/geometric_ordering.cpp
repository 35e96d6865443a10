#include "geometric_ordering.hpp"

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <atomic>
#include <limits>
#include <numeric>
#include <stdexcept>

namespace corrlap::detail {

namespace {

// Parts above this many unknowns order their two halves as parallel tasks.
constexpr int kParallelPart = 50000;
// Ties could make the splits unbalanced; past this depth a part is a leaf.
constexpr int kMaxDepth = 256;

struct Dissection {
  const Eigen::SparseMatrix<double>& A;
  const Eigen::MatrixX3d& points;
  int leaf_size;
  std::vector<int> ids;    // the unknowns; every part is a contiguous range ids[lo, hi)
  std::vector<int> part;   // label of the part an unknown is in: 1 + the first index of its range
  std::vector<int> order;  // the result

  // Labels are read for the neighbours of a part while the tasks of other parts relabel theirs; a
  // label is unique to one live range, so those writes never change what a part reads, but they
  // are still concurrent accesses, hence atomic (relaxed).
  int label(int v) const { return std::atomic_ref<const int>(part[std::size_t(v)]).load(std::memory_order_relaxed); }
  void relabel(int v, int l) { std::atomic_ref<int>(part[std::size_t(v)]).store(l, std::memory_order_relaxed); }

  // Orders ids[lo, hi) into order[out, out + hi - lo): lower half, upper half, then the separator.
  void run(int lo, int hi, int out, int depth) {
    const int split = depth < kMaxDepth ? bisect(lo, hi) : -1;
    if (split < 0) {  // a leaf, or nothing to split on
      std::copy(ids.begin() + lo, ids.begin() + hi, order.begin() + out);
      return;
    }
    // ids[lo, split): lower half; ids[split, hi): upper half, whose unknowns with a neighbour in
    // the lower half are moved to its end and become the separator.
    const int lower_label = lo + 1;
    const auto touches_lower = [&](int v) {
      for (Eigen::SparseMatrix<double>::InnerIterator it(A, v); it; ++it)
        if (it.row() != v && label(int(it.row())) == lower_label) return true;
      return false;
    };
    const auto sep =
        std::stable_partition(ids.begin() + split, ids.begin() + hi, [&](int v) { return !touches_lower(v); });
    const int upper_end = int(sep - ids.begin());
    for (auto it = sep; it != ids.begin() + hi; ++it) relabel(*it, 0);  // out of every part
    const int lower_size = split - lo, upper_size = upper_end - split;
    std::copy(sep, ids.begin() + hi, order.begin() + out + lower_size + upper_size);
    const auto lower = [&] { run(lo, split, out, depth + 1); };
    const auto upper = [&] {
      if (upper_size > 0) run(split, upper_end, out + lower_size, depth + 1);
    };
    if (hi - lo > kParallelPart) {
      tbb::parallel_invoke(lower, upper);
    } else {
      lower();
      upper();
    }
  }

  // Splits ids[lo, hi) at the median of the longest side and labels the two halves (lo + 1 and
  // split + 1). Returns the first index of the upper half, or -1 when the range is a leaf or
  // cannot be split.
  int bisect(int lo, int hi) {
    if (hi - lo <= leaf_size) return -1;
    Eigen::Array3d low = Eigen::Array3d::Constant(std::numeric_limits<double>::infinity()), high = -low;
    for (int i = lo; i < hi; ++i) {
      const Eigen::Array3d p = points.row(ids[std::size_t(i)]).transpose().array();
      low = low.min(p);
      high = high.max(p);
    }
    int axis = 0;
    if (!((high - low).maxCoeff(&axis) > 0.0)) return -1;  // every point at one place
    const auto coordinate = [&](int v) { return points(v, axis); };
    const int mid = lo + (hi - lo) / 2;
    std::nth_element(ids.begin() + lo, ids.begin() + mid, ids.begin() + hi,
                     [&](int a, int b) { return coordinate(a) < coordinate(b); });
    const double cut = coordinate(ids[std::size_t(mid)]);
    // Strictly below the cut: lower half; the median's plane goes up.
    auto upper = std::partition(ids.begin() + lo, ids.begin() + hi, [&](int v) { return coordinate(v) < cut; });
    int split = int(upper - ids.begin());
    if (split == lo)  // more than half on the lowest plane: that plane is the lower half
      split = int(std::partition(ids.begin() + lo, ids.begin() + hi, [&](int v) { return coordinate(v) <= cut; }) -
                  ids.begin());
    if (split == lo || split == hi) return -1;
    for (int i = lo; i < split; ++i) relabel(ids[std::size_t(i)], lo + 1);
    for (int i = split; i < hi; ++i) relabel(ids[std::size_t(i)], split + 1);
    return split;
  }
};

}  // namespace

std::vector<int> geometric_nested_dissection(const Eigen::SparseMatrix<double>& A, const Eigen::MatrixX3d& points,
                                             int leaf_size) {
  const Eigen::Index n = A.rows();
  if (A.cols() != n || points.rows() != n)
    throw std::invalid_argument("geometric_nested_dissection: A and points must have one row per unknown");
  Dissection d{
      A, points, std::max(1, leaf_size), {}, std::vector<int>(std::size_t(n), 0), std::vector<int>(std::size_t(n), 0)};
  d.ids.resize(std::size_t(n));
  std::iota(d.ids.begin(), d.ids.end(), 0);
  d.run(0, int(n), 0, 0);
  return d.order;
}

}  // namespace corrlap::detail
