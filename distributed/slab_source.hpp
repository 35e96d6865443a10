#pragma once
// Where a rank's slab of voxels comes from (docs/distributed.md, "Volumes per slab and the halo"):
// the distributed surface is built from any source that can hand out the voxels of a range of x
// columns over the whole y/z box, with the same bits as the serial grid there.
#include <Eigen/Core>
#include <corrlap/core/voxel_grid.hpp>
#include <corrlap/io/volume_io.hpp>
#include <corrlap/pipeline/isotropic_resampling.hpp>
#include <corrlap/surface/implicit_shape.hpp>
#include <functional>
#include <string>

namespace corrlap {

/// The whole grid's box and step, and the voxels of any range of its x columns.
struct SlabSource {
  Eigen::Vector3i lower = Eigen::Vector3i::Zero(), upper = -Eigen::Vector3i::Ones();  ///< whole box
  double h = 1.0;                                                                     ///< grid step
  /// voxels(x_first, x_last): the voxels with x in that range clipped to the box, all of y and z,
  /// each with its bit in the whole grid; the grid's box is the clipped range times the box's y/z.
  std::function<VoxelGrid(int x_first, int x_last)> voxels;
};

/// digitize(shape, params) per slab (digitize_x_range). `shape` must outlive the source.
SlabSource implicit_slab_source(const ImplicitShape& shape, const DigitizationParams& params);

/// read_volume_as_voxels(path, options) per slab (read_volume_slab_as_voxels): the box and step
/// come from the header, read here; each slab reads the file again, keeping only its bits. Throws as
/// read_volume for a bad header.
SlabSource volume_slab_source(const std::string& path, const VolumeReadOptions& options);

/// load_surface's voxels of an anisotropic volume file per slab: read_volume_as_voxels(path,
/// options) (centred) resampled to cubes by `resampling` (isotropic_resampling of the file's size
/// and geometry), the resampled box and step. Each slab reads the file columns its columns copy
/// (read_resampled_volume_slab).
SlabSource resampled_volume_slab_source(const std::string& path, const VolumeReadOptions& options,
                                        const IsotropicResampling& resampling);

/// source.voxels(x_first, x_last) on every rank of MPI_COMM_WORLD (collective): when it throws on
/// some ranks only (a memory limit crossed by the widest slab), the others throw too, an InputError
/// naming the failure, instead of waiting for them in the next collective call.
VoxelGrid collective_slab_voxels(const SlabSource& source, int x_first, int x_last);

}  // namespace corrlap
