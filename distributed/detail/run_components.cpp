#include "run_components.hpp"

#include <algorithm>
#include <numeric>

namespace corrlap::distributed_detail {

namespace {

int find_root(std::vector<int>& parent, int a) {
  while (parent[std::size_t(a)] != a) {
    parent[std::size_t(a)] = parent[std::size_t(parent[std::size_t(a)])];  // path halving
    a = parent[std::size_t(a)];
  }
  return a;
}

}  // namespace

int RunComponents::label_at(const Eigen::Vector3i& v) const {
  if (v.x() < x_first || v.x() > x_last) return -1;
  const int y = v.y() - lower.y(), z = v.z() - lower.z();
  if (y < 0 || y >= rows_y || z < 0 || z >= rows_z) return -1;
  const std::size_t r = std::size_t(z) * std::size_t(rows_y) + std::size_t(y);
  // The last run of the row that starts at or before x.
  const auto begin = run_first.begin() + std::ptrdiff_t(row_begin[r]);
  const auto end = run_first.begin() + std::ptrdiff_t(row_begin[r + 1]);
  const auto it = std::upper_bound(begin, end, v.x());
  if (it == begin) return -1;
  const std::size_t i = std::size_t(it - run_first.begin()) - 1;
  return v.x() <= run_last[i] ? run_label[i] : -1;
}

RunComponents label_run_components(const VoxelGrid& grid, int x_first, int x_last) {
  RunComponents c;
  c.x_first = std::max(x_first, grid.lower().x());
  c.x_last = std::min(x_last, grid.upper().x());
  c.lower = grid.lower();
  c.rows_y = grid.size().y();
  c.rows_z = grid.size().z();
  const std::size_t rows = std::size_t(c.rows_y) * std::size_t(c.rows_z);
  c.row_begin.assign(rows + 1, 0);
  // 1. The runs of each row.
  for (int z = 0; z < c.rows_z; ++z)
    for (int y = 0; y < c.rows_y; ++y) {
      const std::size_t r = std::size_t(z) * std::size_t(c.rows_y) + std::size_t(y);
      c.row_begin[r] = c.run_first.size();
      int x = c.x_first;
      while (x <= c.x_last) {
        if (!grid.get(x, y + c.lower.y(), z + c.lower.z())) {
          ++x;
          continue;
        }
        const int first = x;
        while (x <= c.x_last && grid.get(x, y + c.lower.y(), z + c.lower.z())) ++x;
        c.run_first.push_back(first);
        c.run_last.push_back(x - 1);
      }
    }
  c.row_begin[rows] = c.run_first.size();
  // 2. Union of the overlapping runs of the rows before along y and along z.
  const int runs = int(c.run_first.size());
  std::vector<int> parent(static_cast<std::size_t>(runs));
  std::iota(parent.begin(), parent.end(), 0);
  auto join_rows = [&](std::size_t a, std::size_t b) {
    std::size_t i = c.row_begin[a], j = c.row_begin[b];
    while (i < c.row_begin[a + 1] && j < c.row_begin[b + 1]) {
      if (c.run_first[i] <= c.run_last[j] && c.run_first[j] <= c.run_last[i]) {
        const int ra = find_root(parent, int(i)), rb = find_root(parent, int(j));
        if (ra != rb) parent[std::size_t(std::max(ra, rb))] = std::min(ra, rb);
      }
      // Advance the run that ends first: it overlaps nothing further in the other row.
      if (c.run_last[i] < c.run_last[j])
        ++i;
      else
        ++j;
    }
  };
  for (int z = 0; z < c.rows_z; ++z)
    for (int y = 0; y < c.rows_y; ++y) {
      const std::size_t r = std::size_t(z) * std::size_t(c.rows_y) + std::size_t(y);
      if (y > 0) join_rows(r, r - 1);
      if (z > 0) join_rows(r, r - std::size_t(c.rows_y));
    }
  // 3. Compact labels in order of each component's first run, bounding boxes, representatives.
  c.run_label.assign(std::size_t(runs), -1);
  std::vector<int> label_of_root(std::size_t(runs), -1);
  for (int z = 0; z < c.rows_z; ++z)
    for (int y = 0; y < c.rows_y; ++y) {
      const std::size_t r = std::size_t(z) * std::size_t(c.rows_y) + std::size_t(y);
      for (std::size_t i = c.row_begin[r]; i < c.row_begin[r + 1]; ++i) {
        const int root = find_root(parent, int(i));
        int& label = label_of_root[std::size_t(root)];
        const Eigen::Vector3i first(c.run_first[i], y + c.lower.y(), z + c.lower.z());
        const Eigen::Vector3i last(c.run_last[i], y + c.lower.y(), z + c.lower.z());
        if (label < 0) {
          label = c.count++;
          c.box_lower.push_back(first);
          c.box_upper.push_back(last);
          c.representative.push_back(first);
        } else {
          c.box_lower[std::size_t(label)] = c.box_lower[std::size_t(label)].cwiseMin(first);
          c.box_upper[std::size_t(label)] = c.box_upper[std::size_t(label)].cwiseMax(last);
        }
        c.run_label[i] = label;
      }
    }
  return c;
}

}  // namespace corrlap::distributed_detail
