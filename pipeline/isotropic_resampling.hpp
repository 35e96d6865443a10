#pragma once
// Anisotropic voxels resampled to cubes of the finest spacing by nearest neighbour (docs/io.md,
// "Physical coordinates"): one map per axis from a resampled index to the file index it copies,
// used by load_surface on the whole volume and by the distributed front end per slab of x.
#include <Eigen/Core>
#include <array>
#include <corrlap/core/voxel_grid.hpp>
#include <corrlap/io/volume_io.hpp>
#include <corrlap/io/voxel_values.hpp>
#include <optional>
#include <string>
#include <vector>

namespace corrlap {

/// The resampling of a volume of `file_size` voxels. Both the file's voxels and the resampled ones
/// sit in the centred, padded box of read_volume_as_voxels(centered): index i along an axis is
/// the digital point i - volume_centering_shift(size) of its own size.
struct IsotropicResampling {
  Eigen::Vector3i file_size = Eigen::Vector3i::Zero();
  Eigen::Vector3i size = Eigen::Vector3i::Zero();  ///< resampled voxels per axis
  /// source[a][r]: the file index along axis a of the voxel that resampled voxel r copies (the one
  /// whose centre is nearest to r's centre); non-decreasing in r.
  std::array<std::vector<int>, 3> source;
  VolumeGeometry geometry;  ///< the resampled voxels' index -> physical map (cubes of the finest side)
  double h = 1.0;           ///< the resampled grid's step: the given one, or unit_size_grid_step(size)

  Eigen::Vector3i shift() const { return volume_centering_shift(size); }
  /// The resampled grid's box: its voxels [0, size - 1] - shift(), padded by one empty voxel.
  Eigen::Vector3i lower() const { return -Eigen::Vector3i::Ones() - shift(); }
  Eigen::Vector3i upper() const { return size - shift(); }
};

/// The map for a volume of `file_size` voxels with `geometry` (positive spacings); `h`: the grid
/// step, or none for unit_size_grid_step of the resampled size. InputError tagged "volume" when a
/// resampled side would exceed what a voxel grid holds.
IsotropicResampling isotropic_resampling(const Eigen::Vector3i& file_size, const VolumeGeometry& geometry,
                                         std::optional<double> h);

/// Sets the voxels of `out`, a box of the resampled grid (any x range, the whole y/z box), from
/// `file`, the file's voxels in their centred box over at least the file columns that out's
/// columns copy and all of y and z. Voxels of out outside the resampled volume (the padding) stay
/// as they are. InputError when `file` lacks a column out needs.
void resample_voxels(const VoxelGrid& file, const IsotropicResampling& resampling, VoxelGrid& out);

/// The voxels of read_volume_as_voxels(path, options) (centred) resampled to cubes by `resampling`,
/// those whose x lies in [x_first, x_last] (resampled digital coordinates), in a grid whose box is
/// that range clipped to the resampled box with all of its y and z, and step resampling.h. Reads the
/// file columns the range copies with read_volume_slab_as_voxels; the memory budget is checked for
/// both grids before either is allocated. InputError when the range misses the box; as
/// read_volume_slab_as_voxels for a bad file.
VoxelGrid read_resampled_volume_slab(const std::string& path, const VolumeReadOptions& options,
                                     const IsotropicResampling& resampling, int x_first, int x_last);

}  // namespace corrlap
