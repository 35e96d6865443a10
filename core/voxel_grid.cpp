#include "voxel_grid.hpp"

#include <sys/mman.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <sstream>

#include "error.hpp"
#include "memory_budget.hpp"

namespace corrlap {

namespace {
// 2^37 voxels = 16 GiB of bits: beyond that the box is certainly a mistake on a 24 GiB machine.
constexpr double kMaxVoxels = 137438953472.0;
}  // namespace

VoxelGrid::VoxelGrid(const Eigen::Vector3i& lower, const Eigen::Vector3i& upper, double h)
    : lower_(lower), upper_(upper), h_(h) {
  if (!(h > 0.0) || !std::isfinite(h)) {
    std::ostringstream os;
    os << "voxel grid: grid step h must be positive and finite (got " << h << ")";
    throw InputError(os.str());
  }
  const Eigen::Vector3i n = size();
  if ((n.array() <= 0).any()) {
    std::ostringstream os;
    os << "voxel grid: empty box [" << lower.transpose() << "] .. [" << upper.transpose() << "]";
    throw InputError(os.str());
  }
  const double total = double(n.x()) * double(n.y()) * double(n.z());
  if (total > kMaxVoxels) {
    std::ostringstream os;
    os << "voxel grid: box of " << n.x() << "x" << n.y() << "x" << n.z()
       << " voxels is too large (limit 2^37 voxels); use a larger grid step or a smaller box";
    throw InputError(os.str());
  }
  words_per_row_ = (static_cast<std::size_t>(n.x()) + 63) / 64;
  const std::size_t words = words_per_row_ * static_cast<std::size_t>(n.y()) * static_cast<std::size_t>(n.z());
  {
    std::ostringstream what;
    what << "voxel grid: a box of " << n.x() << "x" << n.y() << "x" << n.z() << " voxels";
    check_memory_budget(bytes_for(n), what.str(), "use a larger grid step or a smaller box");
  }
  // All zero without writing (see ZeroFilledAllocator): digitization then touches only the pages
  // holding inside voxels.
  words_.resize(words);
}

void VoxelGrid::set(int x, int y, int z, bool value) {
  if (!in_box(x, y, z)) {
    std::ostringstream os;
    os << "voxel grid: voxel (" << x << "," << y << "," << z << ") is outside the box";
    throw InputError(os.str());
  }
  const int lx = x - lower_.x();
  std::uint64_t& w = row(y, z)[lx >> 6];
  const std::uint64_t bit = std::uint64_t{1} << (lx & 63);
  w = value ? (w | bit) : (w & ~bit);
}

std::int64_t VoxelGrid::count() const {
  std::int64_t c = 0;
  for (std::uint64_t w : words_) c += std::popcount(w);
  return c;
}

}  // namespace corrlap
