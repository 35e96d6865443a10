#pragma once
// The pieces of extract_surface that a caller holding only part of the grid needs (the distributed
// front end, distributed/): the surfels in the reference's face order, and the corners of a surfel.
#include <Eigen/Core>
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/core/voxel_grid.hpp>
#include <vector>

namespace corrlap {

/// The surfels of extract_surface(grid) in its face order (docs/math.md §1.4: sorted by
/// (positive, kc_x, kc_y, kc_z)), without building the mesh. Empty when the grid has no surfel.
std::vector<Surfel> extract_surfels(const VoxelGrid& grid);

/// Pointel of corner c (0..3) of surfel s, in extract_surface's corner order (docs/math.md §1.4).
/// A pointel Q is the corner shared by the voxels Q - 1 + d, d in {0,1}^3; at grid step h it sits
/// at pointel_coordinate(Q, h) on each axis.
Eigen::Vector3i surfel_corner_pointel(const Surfel& s, int c);

/// Whether extract_surface examines pointel Q for a split into several vertices (docs/math.md §1.4,
/// manifold sheets): a pinched configuration of the 8 voxels around it, or Q on the box's faces.
/// Needs the voxels Q - 1 + d of `grid`; when it is false, Q is exactly one vertex of the mesh.
bool pointel_may_split(const VoxelGrid& grid, const Eigen::Vector3i& q);

/// World coordinate of a pointel index on one axis: (Q - 1/2) h, the bits extract_surface writes.
inline double pointel_coordinate(int q, double h) { return (double(2 * q - 1) * 0.5) * h; }

}  // namespace corrlap
