#include "geometric_ordering.hpp"

#include <algorithm>
#include <limits>
#include <numeric>
#include <stdexcept>

namespace corrlap::detail {

namespace {

struct Dissection {
  const Eigen::SparseMatrix<double>& A;
  const Eigen::MatrixX3d& points;
  int leaf_size;
  std::vector<int> ids;         // the unknowns, each part a contiguous range
  std::vector<int> part;        // label of the part an unknown is in (lower halves get fresh labels)
  std::vector<int> order;       // the result, filled leaves first
  std::vector<int> separators;  // stack of pending separators (eliminated after their two halves)
  int next_label = 1;

  // Orders ids[lo, hi). Written with an explicit stack: the recursion depth is log2(n / leaf) but
  // unbalanced ties could make it deeper.
  void run(int lo, int hi) {
    struct Task {
      int lo, hi;
      int separator_begin = -1, separator_end = -1;  // >= 0: emit this separator range instead
    };
    std::vector<Task> stack{{lo, hi}};
    while (!stack.empty()) {
      const Task t = stack.back();
      stack.pop_back();
      if (t.separator_begin >= 0) {
        order.insert(order.end(), separators.begin() + t.separator_begin, separators.begin() + t.separator_end);
        separators.resize(std::size_t(t.separator_begin));
        continue;
      }
      const int split = bisect(t.lo, t.hi);
      if (split < 0) {  // a leaf, or nothing to split on (all points on one plane position)
        order.insert(order.end(), ids.begin() + t.lo, ids.begin() + t.hi);
        continue;
      }
      // ids[lo, split): lower half; ids[split, hi): upper half, whose unknowns with a neighbour in
      // the lower half are moved to its end and become the separator.
      const int lower_label = part[std::size_t(ids[std::size_t(t.lo)])];
      const auto touches_lower = [&](int v) {
        for (Eigen::SparseMatrix<double>::InnerIterator it(A, v); it; ++it)
          if (it.row() != v && part[std::size_t(it.row())] == lower_label) return true;
        return false;
      };
      const auto sep =
          std::stable_partition(ids.begin() + split, ids.begin() + t.hi, [&](int v) { return !touches_lower(v); });
      const int upper_end = int(sep - ids.begin());
      const int sep_begin = int(separators.size());
      separators.insert(separators.end(), sep, ids.begin() + t.hi);
      for (auto it = sep; it != ids.begin() + t.hi; ++it) part[std::size_t(*it)] = 0;  // out of every part
      // Stack order: lower half first, then upper half, then the separator.
      stack.push_back({0, 0, sep_begin, int(separators.size())});
      if (upper_end > split) stack.push_back({split, upper_end});
      stack.push_back({t.lo, split});
    }
  }

  // Splits ids[lo, hi) at the median of the longest side; relabels the two halves. Returns the first
  // index of the upper half, or -1 when the range is a leaf or cannot be split.
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
    const int lower_label = next_label++, upper_label = next_label++;
    for (int i = lo; i < split; ++i) part[std::size_t(ids[std::size_t(i)])] = lower_label;
    for (int i = split; i < hi; ++i) part[std::size_t(ids[std::size_t(i)])] = upper_label;
    return split;
  }
};

}  // namespace

std::vector<int> geometric_nested_dissection(const Eigen::SparseMatrix<double>& A, const Eigen::MatrixX3d& points,
                                             int leaf_size) {
  const Eigen::Index n = A.rows();
  if (A.cols() != n || points.rows() != n)
    throw std::invalid_argument("geometric_nested_dissection: A and points must have one row per unknown");
  Dissection d{A, points, std::max(1, leaf_size), {}, std::vector<int>(std::size_t(n), 0), {}, {}};
  d.ids.resize(std::size_t(n));
  std::iota(d.ids.begin(), d.ids.end(), 0);
  d.order.reserve(std::size_t(n));
  d.run(0, int(n));
  return d.order;
}

}  // namespace corrlap::detail
