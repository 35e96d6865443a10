#include "isotropic_resampling.hpp"

#include <algorithm>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/core/memory_budget.hpp>
#include <cstdint>
#include <limits>
#include <sstream>

namespace corrlap {

namespace {

std::string describe_size(const Eigen::Vector3i& size) {
  return std::to_string(size.x()) + "x" + std::to_string(size.y()) + "x" + std::to_string(size.z());
}

}  // namespace

// Nearest neighbour: the digitization and the paper's defaults need cubic voxels, nearest neighbour
// invents no value, and a part one voxel thick stays at least one voxel thick.
IsotropicResampling isotropic_resampling(const Eigen::Vector3i& file_size, const VolumeGeometry& geometry,
                                         std::optional<double> h) {
  IsotropicResampling r;
  r.file_size = file_size;
  const double fine = geometry.spacing.minCoeff();
  for (int a = 0; a < 3; ++a) {
    const double ratio = geometry.spacing[a] / fine;
    const double n = std::round(double(file_size[a]) * ratio);
    if (!(n < double(std::numeric_limits<int>::max() - 2))) {
      std::ostringstream os;
      os << "volume: resampling the voxels to cubes of " << fine << " gives " << n << " voxels along axis " << a
         << ", more than a voxel grid holds";
      throw InputError(os.str(), "volume");
    }
    r.size[a] = std::max(1, int(n));
    auto& s = r.source[std::size_t(a)];
    s.resize(std::size_t(r.size[a]));
    // Resampled voxel k covers [k, k + 1) / ratio - 1/2 in file indices; its centre's nearest voxel:
    for (int k = 0; k < r.size[a]; ++k)
      s[std::size_t(k)] = std::min(file_size[a] - 1, int(std::floor((k + 0.5) / ratio)));
  }
  // Resampled voxel k's centre is at file index (k + 1/2) / ratio - 1/2: the same physical box.
  r.geometry = geometry;
  const Eigen::Vector3d half_offset = 0.5 * (Eigen::Vector3d::Constant(fine) - geometry.spacing);
  r.geometry.origin += geometry.direction * half_offset;
  r.geometry.spacing = Eigen::Vector3d::Constant(fine);
  r.h = h ? *h : unit_size_grid_step(r.size);
  return r;
}

void resample_voxels(const VoxelGrid& file, const IsotropicResampling& resampling, VoxelGrid& out) {
  const Eigen::Vector3i file_shift = volume_centering_shift(resampling.file_size), shift = resampling.shift();
  // The resampled indices of out's box that lie in the volume, and the file's digital points they copy.
  Eigen::Vector3i first, last;
  for (int a = 0; a < 3; ++a) {
    first[a] = std::max(0, out.lower()[a] + shift[a]);
    last[a] = std::min(resampling.size[a] - 1, out.upper()[a] + shift[a]);
    if (first[a] > last[a]) return;
    const auto& s = resampling.source[std::size_t(a)];
    const int from = s[std::size_t(first[a])] - file_shift[a], to = s[std::size_t(last[a])] - file_shift[a];
    if (from < file.lower()[a] || to > file.upper()[a])
      throw InputError("resampled voxels: the file's voxels [" + std::to_string(file.lower()[a]) + ", " +
                       std::to_string(file.upper()[a]) + "] along axis " + std::to_string(a) + " lack [" +
                       std::to_string(from) + ", " + std::to_string(to) + "]");
  }
  const auto& sx = resampling.source[0];
  const auto& sy = resampling.source[1];
  const auto& sz = resampling.source[2];
  const int file_x0 = file.lower().x() + file_shift.x(), out_x0 = out.lower().x() + shift.x();
  for (int z = first.z(); z <= last.z(); ++z)
    for (int y = first.y(); y <= last.y(); ++y) {
      const std::uint64_t* in = file.row(sy[std::size_t(y)] - file_shift.y(), sz[std::size_t(z)] - file_shift.z());
      std::uint64_t* row = out.row(y - shift.y(), z - shift.z());
      for (int x = first.x(); x <= last.x(); ++x) {
        const int from = sx[std::size_t(x)] - file_x0, to = x - out_x0;
        if ((in[from >> 6] >> (from & 63)) & 1u) row[to >> 6] |= std::uint64_t{1} << (to & 63);
      }
    }
}

VoxelGrid read_resampled_volume_slab(const std::string& path, const VolumeReadOptions& options,
                                     const IsotropicResampling& resampling, int x_first, int x_last) {
  Eigen::Vector3i lower = resampling.lower(), upper = resampling.upper();
  if (x_first > upper.x() || x_last < lower.x() || x_first > x_last)
    throw InputError("volume '" + path + "': the slab of x [" + std::to_string(x_first) + ", " +
                     std::to_string(x_last) + "] is outside the resampled voxel box's x range [" +
                     std::to_string(lower.x()) + ", " + std::to_string(upper.x()) + "]");
  lower.x() = std::max(lower.x(), x_first);
  upper.x() = std::min(upper.x(), x_last);
  const int shift = resampling.shift().x();
  const int first = std::max(0, lower.x() + shift), last = std::min(resampling.size.x() - 1, upper.x() + shift);
  if (first > last) return VoxelGrid(lower, upper, resampling.h);  // padding columns only
  // The file columns these resampled columns copy, in the file's centred box.
  const int file_shift = volume_centering_shift(resampling.file_size).x();
  const int file_first = resampling.source[0][std::size_t(first)] - file_shift;
  const int file_last = resampling.source[0][std::size_t(last)] - file_shift;
  const Eigen::Vector3i size = upper - lower + Eigen::Vector3i::Ones();
  const Eigen::Vector3i file_size(file_last - file_first + 1, resampling.file_size.y() + 2,
                                  resampling.file_size.z() + 2);
  check_memory_budget(VoxelGrid::bytes_for(size) + VoxelGrid::bytes_for(file_size),
                      "volume '" + path + "': a slab of " + describe_size(size) + " resampled voxels and the file's " +
                          describe_size(file_size) + " voxels it copies",
                      "use fewer voxels per slab (more ranks)");
  VoxelGrid out(lower, upper, resampling.h);
  VolumeReadOptions file_options = options;
  file_options.centered = true;
  const VoxelGrid file = read_volume_slab_as_voxels(path, file_options, file_first, file_last);
  resample_voxels(file, resampling, out);
  return out;
}

}  // namespace corrlap
