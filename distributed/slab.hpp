#pragma once
// The slabs of the distributed front end: the digitization box cut along x into one slab of voxel
// columns per MPI rank (docs/distributed.md).
#include <Eigen/Core>

namespace corrlap {

/// Voxel columns x in [first, last] (absolute digital coordinates) of one rank. Rank r of P gets
/// the columns lower.x + floor(n r / P) .. lower.x + floor(n (r + 1) / P) - 1 of the n columns of
/// the box, so every rank has at least one column when n >= P.
///
/// Ownership: a surfel belongs to the rank whose slab holds the x of its lower voxel
/// (Surfel::lower_voxel), i.e. of its Khalimsky coordinate kc_x in [2 first + 1, 2 last + 2]: the
/// rank owns the surfels tangent to x in its columns and the x-surfels between its last column and
/// the next rank's first one.
struct Slab {
  int first = 0, last = -1;
  int columns() const { return last - first + 1; }
};

/// Slab of `rank` among `ranks` for the box [lower, upper]. Throws InputError when the box has
/// fewer columns than ranks.
Slab slab_of(const Eigen::Vector3i& lower, const Eigen::Vector3i& upper, int rank, int ranks);

}  // namespace corrlap
