#pragma once
// Dense bit storage of a box of voxels (docs/math.md §0, §1.2).
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace corrlap {

namespace detail {
/// Allocator for large zero-filled bit buffers: calloc hands out fresh kernel pages that are
/// already zero, and default construction writes nothing (calloc implicitly creates the trivial
/// objects with value 0). Pages that stay all-zero (the outside of a shape) are then never
/// written, so they cost neither a page clear nor memory. Copies construct values as usual.
template <class T>
struct ZeroFilledAllocator {
  static_assert(std::is_trivial_v<T>);
  using value_type = T;
  ZeroFilledAllocator() = default;
  template <class U>
  ZeroFilledAllocator(const ZeroFilledAllocator<U>&) noexcept {}
  T* allocate(std::size_t n) {
    void* p = std::calloc(n == 0 ? 1 : n, sizeof(T));
    if (!p) throw std::bad_alloc();
    return static_cast<T*>(p);
  }
  void deallocate(T* p, std::size_t) noexcept { std::free(p); }
  template <class U>
  void construct(U*) noexcept {}  // keep calloc's zeros
  template <class U, class A0, class... A>
  void construct(U* p, A0&& a0, A&&... a) {
    ::new (static_cast<void*>(p)) U(std::forward<A0>(a0), std::forward<A>(a)...);
  }
  friend bool operator==(const ZeroFilledAllocator&, const ZeroFilledAllocator&) noexcept { return true; }
};
}  // namespace detail

/// A box [lower, upper] (inclusive, on each axis) of digital points z in Z^3 with one bit per
/// voxel ("inside"). Voxel z sits at world position h * z (docs/math.md §0).
/// Storage: each (y, z) row of voxels is padded to whole 64-bit words, x fastest, so that
/// transitions along every axis can be found 64 voxels at a time.
class VoxelGrid {
 public:
  VoxelGrid() = default;
  /// Throws InputError for an empty or absurdly large box, or h <= 0.
  VoxelGrid(const Eigen::Vector3i& lower, const Eigen::Vector3i& upper, double h);

  const Eigen::Vector3i& lower() const { return lower_; }
  const Eigen::Vector3i& upper() const { return upper_; }
  Eigen::Vector3i size() const { return upper_ - lower_ + Eigen::Vector3i::Ones(); }
  double h() const { return h_; }
  bool empty_box() const { return words_.empty(); }

  bool in_box(int x, int y, int z) const {
    return x >= lower_.x() && x <= upper_.x() && y >= lower_.y() && y <= upper_.y() && z >= lower_.z() &&
           z <= upper_.z();
  }
  /// False outside the box.
  bool get(int x, int y, int z) const {
    if (!in_box(x, y, z)) return false;
    const int lx = x - lower_.x();
    return (row(y, z)[lx >> 6] >> (lx & 63)) & 1u;
  }
  void set(int x, int y, int z, bool value);

  /// Number of inside voxels.
  std::int64_t count() const;

  std::size_t words_per_row() const { return words_per_row_; }
  const std::uint64_t* row(int y, int z) const { return words_.data() + row_offset(y, z); }
  std::uint64_t* row(int y, int z) { return words_.data() + row_offset(y, z); }
  std::size_t memory_bytes() const { return words_.size() * sizeof(std::uint64_t); }
  /// The bytes a grid of that many voxels per axis holds (rows of whole words), computed in
  /// double so that a size check can come before the multiplication overflows.
  static double bytes_for(const Eigen::Vector3i& size) {
    return double((std::int64_t(size.x()) + 63) / 64) * double(size.y()) * double(size.z()) * sizeof(std::uint64_t);
  }

 private:
  std::size_t row_offset(int y, int z) const {
    return (static_cast<std::size_t>(z - lower_.z()) * static_cast<std::size_t>(size().y()) +
            static_cast<std::size_t>(y - lower_.y())) *
           words_per_row_;
  }
  Eigen::Vector3i lower_ = Eigen::Vector3i::Zero();
  Eigen::Vector3i upper_ = -Eigen::Vector3i::Ones();
  double h_ = 1.0;
  std::size_t words_per_row_ = 0;
  std::vector<std::uint64_t, detail::ZeroFilledAllocator<std::uint64_t>> words_;
};

}  // namespace corrlap
