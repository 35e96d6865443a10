#pragma once
// Gauss digitization of part of the reference's box (docs/math.md §1.2), for front ends that never
// hold the whole grid (distributed/: one slab of x per MPI rank).
#include <corrlap/core/voxel_grid.hpp>

#include "implicit_shape.hpp"

namespace corrlap {

/// The voxels of digitize(shape, params) whose x lies in [x_first, x_last] (clipped to the box), in
/// a grid whose box is that slab times the whole box in y and z. Every voxel gets the bit of
/// digitize(): both decide each voxel by the same exact evaluation. Throws InputError when the
/// clipped range is empty.
VoxelGrid digitize_x_range(const ImplicitShape& shape, const DigitizationParams& params, int x_first, int x_last);

}  // namespace corrlap
