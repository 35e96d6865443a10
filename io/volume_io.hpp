#pragma once
// Volumes and their conversion to voxel sets by an inside rule (io/voxel_values.hpp).
// Formats, chosen by extension: DGtal .vol and .longvol, raw uint8 (.raw), NRRD (.nrrd, .nhdr),
// NIfTI-1/2 (.nii, .nii.gz), MetaImage (.mha, .mhd), numpy (.npy), binvox, MagicaVoxel (.vox) and
// TIFF stacks (.tif, .tiff, a folder of slices); what each reads and writes: docs/io.md. Every
// reader streams into a sink (io/detail/volume_stream.hpp), one reader per file.
#include <Eigen/Core>
#include <corrlap/core/voxel_grid.hpp>
#include <corrlap/io/voxel_values.hpp>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace corrlap {

/// A dense uint8 volume, x fastest.
struct Volume {
  Eigen::Vector3i size = Eigen::Vector3i::Zero();
  std::vector<std::uint8_t> values;
  std::uint8_t at(int x, int y, int z) const {
    return values[(std::size_t(z) * std::size_t(size.y()) + std::size_t(y)) * std::size_t(size.x()) + std::size_t(x)];
  }
};

/// A volume as its file holds it: the values in their own type (native byte order), i fastest,
/// and the file's voxel-to-physical map.
struct VolumeData {
  Eigen::Vector3i size = Eigen::Vector3i::Zero();
  VoxelValueType type = VoxelValueType::UInt8;
  std::vector<std::uint8_t> bytes;  ///< size.prod() * value_bytes(type)
  VolumeGeometry geometry;
};

struct VolumeReadOptions {
  /// read_volume_as_voxels: which values are inside (default: every nonzero value).
  InsideRule inside;
  /// Grid step given to the voxel grid; 0: unit_size_grid_step (the longest side spans 2).
  double h = 1.0;
  std::optional<Eigen::Vector3i> raw_dimensions;  ///< required for .raw
  /// read_volume_as_voxels: file voxel (x, y, z) becomes the digital point (x, y, z) - shift with
  /// shift = volume_centering_shift(size), so that the volume's centre is at the origin (within
  /// half a voxel: voxel centres sit at h Z^3). False: the corner voxel at the origin.
  bool centered = false;
};

/// Reads by extension. Throws IoError naming the file and the problem (missing header field,
/// truncated data, absurd dimensions, a value that is not an integer in 0..255...).
Volume read_volume(const std::string& path, const VolumeReadOptions& options = {});
/// Reads by extension, the values in their own type, with the file's geometry. Throws as read_volume.
VolumeData read_volume_data(const std::string& path, const VolumeReadOptions& options = {});
struct VolumeWriteOptions {
  /// .vol and .longvol only: Version 3, the voxels as one zlib stream (DGtal's VolWriter with compression);
  /// needs zlib. Otherwise Version 2, raw bytes.
  bool compressed = false;
};

/// Writes by extension (.vol, .longvol, .raw, .nrrd). NRRD is written as uint8, raw encoding.
void write_volume(const std::string& path, const Volume& volume, const VolumeWriteOptions& options = {});
/// Writes by extension, the values in their own type, with the geometry where the format has one
/// (.nrrd, .nii/.nii.gz, .mha/.mhd, .npy, .tif/.tiff; .binvox for 0/1 values). IoError naming the
/// file otherwise.
void write_volume_data(const std::string& path, const VolumeData& volume);
/// True when corrlap was built with zlib: NRRD files with "encoding: gzip" and .vol Version 3 files
/// can be read (and .vol Version 3 written).
bool nrrd_gzip_supported();

/// Voxels with value > threshold; the box is [0, size-1] padded by one empty voxel on every side
/// so that the surface is closed. Throws InputError for an empty or full volume.
VoxelGrid threshold_volume(const Volume& volume, double threshold, double h);
/// 2 / (the longest side in voxels): the step at which the volume's longest side spans 2, the world
/// units of the unit-sized shapes the paper's defaults are stated for (II radius, curvature radius).
double unit_size_grid_step(const Eigen::Vector3i& size);
/// (size - 1) / 2 per axis (integer division): the digital point of the volume's middle voxel.
Eigen::Vector3i volume_centering_shift(const Eigen::Vector3i& size);
/// The voxels whose values are inside by options.inside (for a uint8 volume and the rule
/// InsideRule::above(t): the same voxels as threshold_volume(read_volume(path), t, h)), with
/// options.h (0: unit_size_grid_step of the volume), shifted by volume_centering_shift when
/// options.centered; streamed: the values are decided into the grid as they are read or inflated,
/// so memory is the bit grid (1 bit per voxel) plus the compressed bytes of a compressed file,
/// never the volume's values. `geometry`, when given, receives the file's voxel-to-physical map.
/// Throws as read_volume (and IoError for a NaN value), and InputError when no voxel is inside.
VoxelGrid read_volume_as_voxels(const std::string& path, const VolumeReadOptions& options,
                                VolumeGeometry* geometry = nullptr);
/// The box and step of read_volume_as_voxels(path, options)'s grid, from the file's header only (the
/// reader stops before the first value): the volume's `size`, its box [lower, upper] (the volume
/// shifted as options.centered says and padded by one empty voxel on every side), the step h and the
/// file's geometry. Throws as read_volume for a bad header.
struct VolumeVoxelBox {
  Eigen::Vector3i size = Eigen::Vector3i::Zero(), lower = Eigen::Vector3i::Zero(), upper = -Eigen::Vector3i::Ones();
  double h = 1.0;
  VolumeGeometry geometry;
};
VolumeVoxelBox read_volume_voxel_box(const std::string& path, const VolumeReadOptions& options);
/// The voxels of read_volume_as_voxels(path, options) whose x lies in [x_first, x_last] (digital
/// coordinates, after the centering shift), in a grid whose box is that range clipped to the
/// volume's box, with all of its y and z: the same bits, h and geometry. One slab per MPI rank
/// (distributed/slab_source.hpp). Every value of the file is still read and decided (a bad or NaN
/// value anywhere fails on every slab alike), but memory is the slab's bit grid (limits checked
/// before it is allocated) plus, for a compressed file, its compressed bytes. MagicaVoxel files
/// (at most 256^3 voxels) hold their dense values while read, as read_volume_as_voxels does. A slab
/// with no voxel inside is no error (the volume may be empty only there); InputError when the range
/// misses the box.
VoxelGrid read_volume_slab_as_voxels(const std::string& path, const VolumeReadOptions& options, int x_first, int x_last,
                                     VolumeGeometry* geometry = nullptr);
/// 255 inside, 0 outside, over the grid's box.
Volume voxels_to_volume(const VoxelGrid& grid);

}  // namespace corrlap
