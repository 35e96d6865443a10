#pragma once
// The 6-connected components of the inside voxels of a range of a grid's columns, labelled run by
// run (internal: the distributed II normals). A run is a maximal interval of inside voxels along x
// in one (y, z) row; two runs are 6-adjacent when their rows are neighbours along y or z and their
// x intervals overlap.
#include <Eigen/Core>
#include <corrlap/core/voxel_grid.hpp>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace corrlap::distributed_detail {

struct RunComponents {
  int x_first = 0, x_last = -1;                       ///< the columns labelled
  Eigen::Vector3i lower = Eigen::Vector3i::Zero();    ///< the grid's lower corner (y, z of row 0)
  int rows_y = 0, rows_z = 0;                         ///< rows of the grid
  std::vector<std::size_t> row_begin;                 ///< runs of row (y, z): row_begin[r] .. row_begin[r + 1]
  std::vector<int> run_first, run_last;               ///< x extent of each run (inclusive)
  std::vector<int> run_label;                         ///< component of each run, 0 .. count - 1
  int count = 0;                                      ///< components
  std::vector<Eigen::Vector3i> box_lower, box_upper;  ///< per component: its voxels' bounding box
  std::vector<Eigen::Vector3i> representative;        ///< per component: one of its voxels

  /// The component of voxel (x, y, z), -1 when it is outside the labelled columns or not inside.
  int label_at(const Eigen::Vector3i& v) const;
};

/// The components of the inside voxels of `grid` with x in [x_first, x_last] (clipped to the box),
/// connected only through those columns.
RunComponents label_run_components(const VoxelGrid& grid, int x_first, int x_last);

}  // namespace corrlap::distributed_detail
