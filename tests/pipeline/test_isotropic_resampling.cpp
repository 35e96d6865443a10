// Anisotropic voxels resampled to cubes (pipeline/isotropic_resampling.hpp): the map copies the file
// voxel whose centre is nearest, load_surface's grid is that copy, and the slabs of the distributed
// front end (read_resampled_volume_slab) stitch into load_surface's grid bit for bit.
#include <doctest/doctest.h>

#include <algorithm>
#include <corrlap/core/error.hpp>
#include <corrlap/io/volume_io.hpp>
#include <corrlap/pipeline/isotropic_resampling.hpp>
#include <corrlap/pipeline/load_surface.hpp>
#include <cstdint>
#include <string>
#include <vector>

#include "test_support.hpp"

using namespace corrlap;

namespace {

// Spacings as integer multiples of a unit that is a power of two, so that their ratios are exact
// fractions num[a] / min(num) and ties between two file voxels really happen.
struct Spacing {
  Eigen::Vector3i num;
  double unit;
  Eigen::Vector3d spacing() const { return num.cast<double>() * unit; }
};

const Spacing kSpacings[] = {
    {{2, 2, 5}, 0.5},   // 1 x 1 x 2.5: a coarse z, ties at every other cube
    {{3, 1, 1}, 1.0},   // 3 x 1 x 1: each file column copied into three
    {{3, 2, 5}, 0.25},  // 0.75 x 0.5 x 1.25: three ratios, none of them 1 but y's
    {{4, 7, 4}, 0.25},  // 1 x 1.75 x 1: a ratio of 7 / 4
};

// The file index nearest to cube k's centre along an axis of ratio p / q, in integers: the centre
// lies at (k + 1/2) q / p - 1/2 file indices, and a tie goes to the higher index.
int nearest_file_index(int k, int p, int q, int file_size) {
  return std::min(file_size - 1, ((2 * k + 1) * q) / (2 * p));
}
// round(n p / q), halves away from zero.
int resampled_size(int n, int p, int q) { return std::max(1, (2 * n * p + q) / (2 * q)); }

// A volume whose neighbouring voxels often differ, so that a voxel copied from the wrong file
// index shows.
VolumeData scattered_volume(const Eigen::Vector3i& size, const Eigen::Vector3d& spacing) {
  VolumeData v;
  v.size = size;
  v.bytes.assign(std::size_t(size.prod()), 0);
  for (int z = 0; z < size.z(); ++z)
    for (int y = 0; y < size.y(); ++y)
      for (int x = 0; x < size.x(); ++x) {
        const unsigned hash = (unsigned(x) * 73856093u) ^ (unsigned(y) * 19349663u) ^ (unsigned(z) * 83492791u);
        v.bytes[std::size_t(x + size.x() * (y + size.y() * z))] = std::uint8_t(hash % 3 == 0 ? 200 : 10);
      }
  v.geometry.spacing = spacing;
  v.geometry.origin = Eigen::Vector3d(-4.0, 2.5, 11.0);
  return v;
}

bool file_value_inside(const VolumeData& v, int x, int y, int z) {
  return v.bytes[std::size_t(x + v.size.x() * (y + v.size.y() * z))] > 100;
}

VolumeFileInput file_input(const std::string& path) {
  VolumeFileInput in;
  in.path = path;
  in.inside = InsideRule::above(100.0);
  return in;
}

}  // namespace

TEST_CASE("isotropic resampling: each cube copies the file voxel whose centre is nearest, the box is kept") {
  const Eigen::Vector3i file_size(7, 5, 6);
  for (const Spacing& s : kSpacings) {
    CAPTURE(s.num.transpose());
    VolumeGeometry g;
    g.spacing = s.spacing();
    g.origin = Eigen::Vector3d(1.0, -2.0, 3.0);
    const IsotropicResampling r = isotropic_resampling(file_size, g, std::nullopt);
    const int q = s.num.minCoeff();
    for (int a = 0; a < 3; ++a) {
      REQUIRE(r.size[a] == resampled_size(file_size[a], s.num[a], q));
      REQUIRE(r.source[std::size_t(a)].size() == std::size_t(r.size[a]));
      for (int k = 0; k < r.size[a]; ++k)
        CHECK(r.source[std::size_t(a)][std::size_t(k)] == nearest_file_index(k, s.num[a], q, file_size[a]));
    }
    // Cubes of the finest side; cube 0's centre half a cube inside the file's first voxel's outer face.
    const double fine = s.unit * q;
    CHECK(r.geometry.spacing == Eigen::Vector3d::Constant(fine));
    const Eigen::Vector3d box_start = g.origin - 0.5 * g.spacing;
    CHECK((r.geometry.origin - (box_start + Eigen::Vector3d::Constant(0.5 * fine))).norm() < 1e-12);
    CHECK(r.h == unit_size_grid_step(r.size));
    CHECK(isotropic_resampling(file_size, g, 0.125).h == 0.125);
    CHECK(r.lower() == -Eigen::Vector3i::Ones() - volume_centering_shift(r.size));
    CHECK(r.upper() == r.size - volume_centering_shift(r.size));
  }
  VolumeGeometry huge;
  huge.spacing = Eigen::Vector3d(1e-9, 1.0, 1.0);
  CHECK_THROWS_AS((void)isotropic_resampling(Eigen::Vector3i(4, 4, 4), huge, std::nullopt), InputError);
}

TEST_CASE("load_surface's grid of an anisotropic volume is the nearest file voxel of every cube") {
  const Eigen::Vector3i file_size(9, 6, 7);
  for (const Spacing& s : kSpacings) {
    CAPTURE(s.num.transpose());
    const VolumeData v = scattered_volume(file_size, s.spacing());
    const std::string path = test::tmp_path("isotropic_resampling.nrrd");
    write_volume_data(path, v);
    const LoadedSurface loaded = load_surface(file_input(path));
    const VoxelGrid& grid = *loaded.grid;
    const int q = s.num.minCoeff();
    Eigen::Vector3i m;
    for (int a = 0; a < 3; ++a) m[a] = resampled_size(file_size[a], s.num[a], q);
    const Eigen::Vector3i shift = volume_centering_shift(m);
    REQUIRE(grid.lower() == -Eigen::Vector3i::Ones() - shift);
    REQUIRE(grid.upper() == m - shift);
    CHECK(grid.h() == unit_size_grid_step(m));
    int wrong = 0;
    for (int z = -1; z <= m.z(); ++z)
      for (int y = -1; y <= m.y(); ++y)
        for (int x = -1; x <= m.x(); ++x) {
          const bool padding = x < 0 || y < 0 || z < 0 || x >= m.x() || y >= m.y() || z >= m.z();
          const bool expected = !padding && file_value_inside(v, nearest_file_index(x, s.num.x(), q, file_size.x()),
                                                              nearest_file_index(y, s.num.y(), q, file_size.y()),
                                                              nearest_file_index(z, s.num.z(), q, file_size.z()));
          if (grid.get(x - shift.x(), y - shift.y(), z - shift.z()) != expected) ++wrong;
        }
    CHECK(wrong == 0);
    // The frame: volume_voxel_frame of the resampled box, cubes of the finest side.
    CHECK(loaded.frame.shift() == shift.cast<double>());
    REQUIRE(loaded.frame.geometry());
    CHECK(loaded.frame.geometry()->spacing == Eigen::Vector3d::Constant(s.unit * q));
    CHECK(loaded.anisotropy == double(s.num.maxCoeff()) / q);
  }
}

TEST_CASE("read_resampled_volume_slab: the slabs of resampled columns stitch into load_surface's grid") {
  const Eigen::Vector3i file_size(9, 6, 7);
  for (const Spacing& s : kSpacings) {
    CAPTURE(s.num.transpose());
    const VolumeData v = scattered_volume(file_size, s.spacing());
    const std::string path = test::tmp_path("isotropic_resampling_slabs.nrrd");
    write_volume_data(path, v);
    const LoadedSurface loaded = load_surface(file_input(path));
    const VoxelGrid& whole = *loaded.grid;
    const IsotropicResampling r = isotropic_resampling(file_size, v.geometry, std::nullopt);
    VolumeReadOptions options;
    options.inside = InsideRule::above(100.0);
    options.h = 0.0;
    options.centered = true;
    for (int width : {1, 2, 3, 5}) {
      CAPTURE(width);
      // Ranges that start before the box and end after it: clipped.
      for (int first = whole.lower().x() - (width - 1); first <= whole.upper().x(); first += width) {
        CAPTURE(first);
        const VoxelGrid slab = read_resampled_volume_slab(path, options, r, first, first + width - 1);
        REQUIRE(slab.lower() ==
                Eigen::Vector3i(std::max(first, whole.lower().x()), whole.lower().y(), whole.lower().z()));
        REQUIRE(slab.upper() ==
                Eigen::Vector3i(std::min(first + width - 1, whole.upper().x()), whole.upper().y(), whole.upper().z()));
        CHECK(slab.h() == whole.h());
        int wrong = 0;
        for (int z = slab.lower().z(); z <= slab.upper().z(); ++z)
          for (int y = slab.lower().y(); y <= slab.upper().y(); ++y)
            for (int x = slab.lower().x(); x <= slab.upper().x(); ++x)
              if (slab.get(x, y, z) != whole.get(x, y, z)) ++wrong;
        CHECK(wrong == 0);
      }
    }
    CHECK_THROWS_AS((void)read_resampled_volume_slab(path, options, r, whole.upper().x() + 1, whole.upper().x() + 3),
                    InputError);
    CHECK_THROWS_AS((void)read_resampled_volume_slab(path, options, r, 2, 1), InputError);
  }
}
