// Volumes read per slab of x (read_volume_voxel_box, read_volume_slab_as_voxels): the slabs of a
// file, stitched together, are read_volume_as_voxels of the whole file bit for bit, in every format
// the distributed front end reads them from, including streams that are not x fastest (binvox, a
// C-ordered .npy) and compressed ones (.nii.gz, .vol Version 3).
#include <doctest/doctest.h>
#include <unistd.h>

#include <corrlap/core/error.hpp>
#include <corrlap/io/volume_io.hpp>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "test_support.hpp"

using namespace corrlap;
using corrlap::test::tmp_path;

namespace {

std::string scratch(const std::string& name) { return tmp_path("slabs_" + std::to_string(::getpid()) + "_" + name); }

// A blobby uint16 pattern: v(i, j, k) over 0 .. 999, inside (above 500) in several pieces that do
// not all touch the box's x ends, so that slabs hold both empty and full columns.
std::uint16_t value_at(int i, int j, int k) { return std::uint16_t((i * 37 + j * j * 11 + k * 53 + i * j * k) % 1000); }

VolumeData pattern(const Eigen::Vector3i& size, VoxelValueType type) {
  VolumeData v;
  v.size = size;
  v.type = type;
  v.bytes.resize(std::size_t(size.prod()) * value_bytes(type));
  std::size_t n = 0;
  for (int k = 0; k < size.z(); ++k)
    for (int j = 0; j < size.y(); ++j)
      for (int i = 0; i < size.x(); ++i, ++n) {
        const std::uint16_t x = value_at(i, j, k);
        if (type == VoxelValueType::UInt16)
          std::memcpy(v.bytes.data() + 2 * n, &x, 2);
        else
          v.bytes[n] = std::uint8_t(x > 500 ? 1 : 0);
      }
  return v;
}

// A C-ordered .npy (k fastest), which the writer never produces: its stream is not in index order.
void write_c_order_npy(const std::string& path, const Eigen::Vector3i& size) {
  std::string dict = "{'descr': '<u2', 'fortran_order': False, 'shape': (" + std::to_string(size.x()) + ", " +
                     std::to_string(size.y()) + ", " + std::to_string(size.z()) + "), }";
  while ((10 + dict.size() + 1) % 64 != 0) dict += ' ';
  dict += '\n';
  std::ofstream out(path, std::ios::binary);
  out.write("\x93NUMPY\x01\x00", 8);
  const std::uint16_t length = std::uint16_t(dict.size());
  out.put(char(length & 0xff)).put(char(length >> 8));
  out << dict;
  for (int i = 0; i < size.x(); ++i)
    for (int j = 0; j < size.y(); ++j)
      for (int k = 0; k < size.z(); ++k) {
        const std::uint16_t x = value_at(i, j, k);
        out.put(char(x & 0xff)).put(char(x >> 8));
      }
}

// Reads `path` whole and in slabs of `width` columns; every slab's bits, box and step are the
// whole read's, and together they hold every inside voxel once.
void check_slabs(const std::string& path, const VolumeReadOptions& options, int width) {
  CAPTURE(path);
  CAPTURE(width);
  CAPTURE(options.centered);
  VolumeGeometry whole_geometry, slab_geometry;
  const VoxelGrid whole = read_volume_as_voxels(path, options, &whole_geometry);
  const VolumeVoxelBox box = read_volume_voxel_box(path, options);
  CHECK(box.lower == whole.lower());
  CHECK(box.upper == whole.upper());
  CHECK(box.h == whole.h());
  CHECK(box.geometry.spacing == whole_geometry.spacing);
  std::int64_t inside = 0;
  bool same = true;
  for (int first = box.lower.x(); first <= box.upper.x(); first += width) {
    const VoxelGrid slab = read_volume_slab_as_voxels(path, options, first, first + width - 1, &slab_geometry);
    CHECK(slab.lower() == Eigen::Vector3i(first, whole.lower().y(), whole.lower().z()));
    CHECK(slab.upper() ==
          Eigen::Vector3i(std::min(first + width - 1, whole.upper().x()), whole.upper().y(), whole.upper().z()));
    CHECK(slab.h() == whole.h());
    CHECK(slab_geometry.origin == whole_geometry.origin);
    for (int z = slab.lower().z(); z <= slab.upper().z(); ++z)
      for (int y = slab.lower().y(); y <= slab.upper().y(); ++y)
        for (int x = slab.lower().x(); x <= slab.upper().x(); ++x)
          same = same && slab.get(x, y, z) == whole.get(x, y, z);
    inside += slab.count();
  }
  CHECK(same);
  CHECK(inside == whole.count());
  CHECK(whole.count() > 0);
}

}  // namespace

TEST_CASE("volume slabs: stitched together they are the whole read, in every streaming format") {
  const Eigen::Vector3i size(13, 9, 7);
  std::vector<std::string> files;
  const VolumeData typed = pattern(size, VoxelValueType::UInt16);
  for (const char* ext : {".nrrd", ".nii", ".nii.gz", ".npy", ".mha"}) {
    files.push_back(scratch(std::string("typed") + ext));
    write_volume_data(files.back(), typed);
  }
  // TIFF stacks when corrlap was built with libtiff.
  try {
    write_volume_data(scratch("typed.tif"), typed);
    files.push_back(scratch("typed.tif"));
  } catch (const IoError& e) {
    CHECK(std::string(e.what()).find("libtiff") != std::string::npos);
  }
  files.push_back(scratch("c_order.npy"));
  write_c_order_npy(files.back(), size);
  // uint8 formats: 255 inside, 0 outside (.vol raw and zlib, .longvol, .raw).
  Volume bytes;
  bytes.size = size;
  for (int k = 0; k < size.z(); ++k)
    for (int j = 0; j < size.y(); ++j)
      for (int i = 0; i < size.x(); ++i) bytes.values.push_back(value_at(i, j, k) > 500 ? 255 : 0);
  for (const char* ext : {".vol", ".longvol", ".raw"}) {
    files.push_back(scratch(std::string("bytes") + ext));
    write_volume(files.back(), bytes);
  }
  if (nrrd_gzip_supported()) {
    files.push_back(scratch("bytes_v3.vol"));
    write_volume(files.back(), bytes, VolumeWriteOptions{.compressed = true});
  }
  // binvox: a cube of 0/1 values, stored y fastest.
  const std::string binvox = scratch("cube.binvox");
  write_volume_data(binvox, pattern(Eigen::Vector3i(8, 8, 8), VoxelValueType::UInt8));

  VolumeReadOptions options;
  options.inside = InsideRule::above(500.0);
  options.raw_dimensions = size;
  for (const bool centered : {false, true}) {
    options.centered = centered;
    options.h = centered ? 0.0 : 0.25;
    for (const std::string& file : files) {
      // The uint8 files hold 255 inside, 0 outside.
      VolumeReadOptions read = options;
      if (file.find("bytes") != std::string::npos) read.inside = InsideRule::above(127.0);
      for (const int width : {1, 3, 6}) check_slabs(file, read, width);
    }
    VolumeReadOptions binary = options;
    binary.inside = InsideRule::nonzero();
    for (const int width : {1, 5}) check_slabs(binvox, binary, width);
  }
  for (const std::string& file : files) std::remove(file.c_str());
  std::remove(binvox.c_str());
}

TEST_CASE("volume slabs: a slab outside the box, an empty slab, a bad file") {
  const std::string path = scratch("empty_ends.nrrd");
  VolumeData v;
  v.size = Eigen::Vector3i(6, 3, 3);
  v.bytes.assign(54, 0);
  v.bytes[std::size_t((1 * 3 + 1) * 6 + 2)] = 9;  // one voxel inside, at x = 2
  write_volume_data(path, v);
  VolumeReadOptions options;
  const VolumeVoxelBox box = read_volume_voxel_box(path, options);
  CHECK(box.lower == Eigen::Vector3i(-1, -1, -1));
  CHECK(box.upper == Eigen::Vector3i(6, 3, 3));
  CHECK(box.size == v.size);
  // A slab without any voxel inside is no error (the volume is not empty elsewhere).
  CHECK(read_volume_slab_as_voxels(path, options, 4, 9).count() == 0);
  CHECK(read_volume_slab_as_voxels(path, options, 4, 9).upper().x() == 6);
  CHECK(read_volume_slab_as_voxels(path, options, -5, 2).count() == 1);
  CHECK_THROWS_WITH_AS((void)read_volume_slab_as_voxels(path, options, 7, 9),
                       doctest::Contains("the slab of x [7, 9] is outside the voxel box's x range [-1, 6]"),
                       InputError);
  CHECK_THROWS_AS((void)read_volume_slab_as_voxels(path, options, 3, 2), InputError);
  // A truncated file fails at the header for the box and for every slab alike.
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 6 3 3\nencoding: raw\n\n" << std::string(10, '\0');
  }
  CHECK_THROWS_WITH_AS((void)read_volume_voxel_box(path, options), doctest::Contains("truncated"), IoError);
  CHECK_THROWS_WITH_AS((void)read_volume_slab_as_voxels(path, options, 0, 1), doctest::Contains("truncated"), IoError);
  std::remove(path.c_str());
}
