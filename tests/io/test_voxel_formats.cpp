// The machine-learning, voxel-art and microscopy volume formats: numpy .npy, binvox, MagicaVoxel
// .vox and TIFF stacks. Round trips, files built byte by byte, cross-checks against files that
// numpy and tifffile write (Debian's /usr/bin/python3, skipped with a message when missing), and
// the bad inputs each reader must refuse with a named error.
#include <doctest/doctest.h>

#include <bit>
#include <corrlap/core/error.hpp>
#include <corrlap/core/memory_budget.hpp>
#include <corrlap/io/volume_io.hpp>
#include <corrlap/pipeline/load_surface.hpp>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "test_support.hpp"

using namespace corrlap;
using corrlap::test::read_text;
using corrlap::test::tmp_path;
using corrlap::test::write_text;

namespace {

std::string bytes(std::initializer_list<int> values) {
  std::string s;
  for (int v : values) s += char(v);
  return s;
}

std::string le32(std::uint32_t v) {
  return bytes({int(v & 0xff), int(v >> 8 & 0xff), int(v >> 16 & 0xff), int(v >> 24)});
}

// A volume of `type` whose value at (i, j, k) is i + 10 j + 100 k (bool: that number is odd).
VolumeData pattern(VoxelValueType type, const Eigen::Vector3i& size) {
  VolumeData v;
  v.size = size;
  v.type = type;
  const std::size_t b = value_bytes(type);
  v.bytes.resize(std::size_t(size.prod()) * b);
  std::size_t n = 0;
  for (int k = 0; k < size.z(); ++k)
    for (int j = 0; j < size.y(); ++j)
      for (int i = 0; i < size.x(); ++i, ++n) {
        const int x = i + 10 * j + 100 * k;
        std::uint8_t* at = v.bytes.data() + n * b;
        switch (type) {
          case VoxelValueType::Bool:
            *at = std::uint8_t(x % 2);
            break;
          case VoxelValueType::Int8: {
            const auto t = std::int8_t(x % 100 - 50);
            std::memcpy(at, &t, b);
            break;
          }
          case VoxelValueType::UInt8:
            *at = std::uint8_t(x % 256);
            break;
          case VoxelValueType::Int16: {
            const auto t = std::int16_t(-x);
            std::memcpy(at, &t, b);
            break;
          }
          case VoxelValueType::UInt16: {
            const auto t = std::uint16_t(x);
            std::memcpy(at, &t, b);
            break;
          }
          case VoxelValueType::Int32: {
            const auto t = std::int32_t(-x);
            std::memcpy(at, &t, b);
            break;
          }
          case VoxelValueType::UInt32: {
            const auto t = std::uint32_t(x);
            std::memcpy(at, &t, b);
            break;
          }
          case VoxelValueType::Int64: {
            const auto t = std::int64_t(-x) * (std::int64_t(1) << 40);
            std::memcpy(at, &t, b);
            break;
          }
          case VoxelValueType::UInt64: {
            const auto t = std::uint64_t(x) << 40;
            std::memcpy(at, &t, b);
            break;
          }
          case VoxelValueType::Float32: {
            const auto t = float(x) + 0.25f;
            std::memcpy(at, &t, b);
            break;
          }
          case VoxelValueType::Float64: {
            const auto t = double(x) / 3.0;
            std::memcpy(at, &t, b);
            break;
          }
        }
      }
  return v;
}

const VoxelValueType kAllTypes[] = {VoxelValueType::Bool,    VoxelValueType::Int8,   VoxelValueType::Int16,
                                    VoxelValueType::Int32,   VoxelValueType::Int64,  VoxelValueType::UInt8,
                                    VoxelValueType::UInt16,  VoxelValueType::UInt32, VoxelValueType::UInt64,
                                    VoxelValueType::Float32, VoxelValueType::Float64};

// The value at voxel (i, j, k) as a double.
double value_at(const VolumeData& v, int i, int j, int k) {
  const std::size_t n =
      (std::size_t(k) * std::size_t(v.size.y()) + std::size_t(j)) * std::size_t(v.size.x()) + std::size_t(i);
  const std::uint8_t* at = v.bytes.data() + n * value_bytes(v.type);
  double out = 0;
  auto get = [&](auto t) {
    std::memcpy(&t, at, sizeof t);
    out = double(t);
  };
  switch (v.type) {
    case VoxelValueType::Bool:
      out = *at;
      break;
    case VoxelValueType::Int8:
      get(std::int8_t{});
      break;
    case VoxelValueType::UInt8:
      get(std::uint8_t{});
      break;
    case VoxelValueType::Int16:
      get(std::int16_t{});
      break;
    case VoxelValueType::UInt16:
      get(std::uint16_t{});
      break;
    case VoxelValueType::Int32:
      get(std::int32_t{});
      break;
    case VoxelValueType::UInt32:
      get(std::uint32_t{});
      break;
    case VoxelValueType::Int64:
      get(std::int64_t{});
      break;
    case VoxelValueType::UInt64:
      get(std::uint64_t{});
      break;
    case VoxelValueType::Float32:
      get(float{});
      break;
    case VoxelValueType::Float64:
      get(double{});
      break;
  }
  return out;
}

void check_pattern(const VolumeData& v, double scale, double offset = 0.0) {
  for (int k = 0; k < v.size.z(); ++k)
    for (int j = 0; j < v.size.y(); ++j)
      for (int i = 0; i < v.size.x(); ++i) {
        CAPTURE(i);
        CAPTURE(j);
        CAPTURE(k);
        REQUIRE(value_at(v, i, j, k) == scale * (i + 10 * j + 100 * k) + offset);
      }
}

// Debian's python3 with the given modules, or a message saying why the cross-check is skipped.
bool have_python(const std::string& modules) {
  const std::string cmd = "/usr/bin/python3 -c 'import " + modules + "' >/dev/null 2>&1";
  if (std::system(cmd.c_str()) == 0) return true;
  MESSAGE("skipped: /usr/bin/python3 cannot import " << modules << " (install python3-numpy, python3-tifffile)");
  return false;
}

// Runs a python script; its assertions make the exit status nonzero.
int run_python(const std::string& name, const std::string& script) {
  const std::string path = tmp_path(name + ".py");
  write_text(path, script);
  return std::system(("/usr/bin/python3 " + path + " 2>&1").c_str());
}

void check_io_error(const std::string& path, const std::string& what) {
  CAPTURE(path);
  CHECK_THROWS_WITH_AS((void)read_volume_data(path), doctest::Contains(what.c_str()), IoError);
}

bool have_tiff() {
  const std::string path = tmp_path("voxfmt_probe.tif");
  try {
    write_volume_data(path, pattern(VoxelValueType::UInt8, {2, 2, 1}));
  } catch (const IoError& e) {
    CHECK(std::string(e.what()).find("built with libtiff (libtiff-dev)") != std::string::npos);
    MESSAGE("skipped: corrlap built without libtiff");
    return false;
  }
  return true;
}

}  // namespace

// ---- numpy ----

TEST_CASE("npy round trip: every value type, Fortran order, the shape and the values kept") {
  for (VoxelValueType type : kAllTypes) {
    CAPTURE(value_type_name(type));
    const VolumeData v = pattern(type, {3, 4, 5});
    const std::string path = tmp_path("voxfmt_round_" + value_type_name(type) + ".npy");
    write_volume_data(path, v);
    const std::string text = read_text(path);
    CHECK(text.find("'fortran_order': True, 'shape': (3, 4, 5)") != std::string::npos);
    CHECK((text.size() - v.bytes.size()) % 64 == 0);  // numpy's alignment of the values
    const VolumeData r = read_volume_data(path);
    CHECK(r.size == v.size);
    CHECK(r.type == v.type);
    CHECK(r.bytes == v.bytes);
    CHECK(r.geometry.affine().isApprox(Eigen::Matrix4d::Identity()));
  }
}

namespace {
// A .npy file of version 1.0 with the given header dict and payload.
std::string npy(const std::string& dict, const std::string& payload, int major = 1) {
  std::string header = dict + "\n";
  std::string s = "\x93NUMPY" + bytes({major, 0});
  s += major == 1 ? bytes({int(header.size() & 0xff), int(header.size() >> 8)}) : le32(std::uint32_t(header.size()));
  return s + header + payload;
}
}  // namespace

TEST_CASE("npy files built byte by byte: C order, versions 2 and 3, big-endian, a trailing axis of 1") {
  // C order (2, 3, 4) of <i2: value number n is array[i, j, k] with n = (i * 3 + j) * 4 + k.
  std::string payload;
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 4; ++k) {
        const int x = -(i + 10 * j + 100 * k);
        payload += bytes({x & 0xff, (x >> 8) & 0xff});
      }
  for (int major : {1, 2, 3}) {
    const std::string path = tmp_path("voxfmt_c" + std::to_string(major) + ".npy");
    write_text(path, npy("{'descr': '<i2', 'fortran_order': False, 'shape': (2, 3, 4), }", payload, major));
    const VolumeData v = read_volume_data(path);
    CHECK(v.type == VoxelValueType::Int16);
    CHECK(v.size == Eigen::Vector3i(2, 3, 4));
    check_pattern(v, -1.0);
  }
  // The same values big-endian, double quotes, keys in another order, and a trailing axis of 1.
  std::string swapped;
  for (std::size_t n = 0; n < payload.size(); n += 2) swapped += std::string{payload[n + 1], payload[n]};
  const std::string path = tmp_path("voxfmt_be.npy");
  write_text(path, npy("{\"shape\": (2, 3, 4, 1), \"fortran_order\": False, \"descr\": \">i2\"}", swapped));
  const VolumeData be = read_volume_data(path);
  CHECK(be.size == Eigen::Vector3i(2, 3, 4));
  check_pattern(be, -1.0);
}

TEST_CASE("a C-order npy gives the voxels of the same array in memory") {
  // Two blocks in a 6 x 5 x 4 array of doubles, C order.
  const Eigen::Vector3i size(6, 5, 4);
  std::vector<double> values(std::size_t(size.prod()), 0.0);
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 5; ++j)
      for (int k = 0; k < 4; ++k)
        if ((i < 3 && j < 2) || (i >= 4 && k >= 2 && j >= 1)) values[std::size_t((i * 5 + j) * 4 + k)] = 1.0;
  std::string payload(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(double));
  REQUIRE(std::endian::native == std::endian::little);
  const std::string path = tmp_path("voxfmt_blocks.npy");
  write_text(path, npy("{'descr': '<f8', 'fortran_order': False, 'shape': (6, 5, 4), }", payload));
  VolumeFileInput file;
  file.path = path;
  const LoadedSurface a = load_surface(file), b = load_surface(VolumeArrayInput::c_order(values, size));
  CHECK(a.mesh.num_faces() > 0);
  CHECK(a.mesh.positions == b.mesh.positions);
  CHECK(a.mesh.faces == b.mesh.faces);
}

TEST_CASE("npy files written by numpy: C and Fortran order, bool, int16, float32, big-endian, versions") {
  if (!have_python("numpy")) return;
  const std::string dir = tmp_path("voxfmt_numpy");
  std::filesystem::create_directories(dir);
  const int rc = run_python("voxfmt_numpy", R"(
import numpy as np
i, j, k = np.meshgrid(np.arange(3), np.arange(4), np.arange(5), indexing='ij')
x = i + 10 * j + 100 * k
d = ')" + dir + R"('
np.save(d + '/c_int16.npy', (-x).astype(np.int16))
np.save(d + '/f_float32.npy', np.asfortranarray(x.astype(np.float32) + 0.25))
np.save(d + '/bool.npy', (x % 2).astype(bool))
np.save(d + '/be_int32.npy', (-x).astype('>i4'))
np.save(d + '/be_f8.npy', np.asfortranarray((x / 3.0).astype('>f8')))
np.save(d + '/u64.npy', x.astype(np.uint64) << np.uint64(40))
np.save(d + '/f_uint16.npy', np.asfortranarray(x.astype(np.uint16)))
with open(d + '/v2.npy', 'wb') as f:
    np.lib.format.write_array(f, x.astype(np.int16) * -1, version=(2, 0))
with open(d + '/v3.npy', 'wb') as f:
    np.lib.format.write_array(f, x.astype(np.int16) * -1, version=(3, 0))
np.save(d + '/flat.npy', np.zeros((4, 5)))
np.save(d + '/complex.npy', np.zeros((2, 2, 2), np.complex128))
np.save(d + '/object.npy', np.array([[[None]]], dtype=object), allow_pickle=True)
np.save(d + '/half.npy', np.zeros((2, 2, 2), np.float16))
np.save(d + '/structured.npy', np.zeros((2, 2, 2), dtype=[('a', '<i4'), ('b', '<f4')]))
)");
  REQUIRE(rc == 0);
  check_pattern(read_volume_data(dir + "/c_int16.npy"), -1.0);
  check_pattern(read_volume_data(dir + "/f_float32.npy"), 1.0, 0.25);
  check_pattern(read_volume_data(dir + "/be_int32.npy"), -1.0);
  check_pattern(read_volume_data(dir + "/u64.npy"), double(std::uint64_t(1) << 40));
  check_pattern(read_volume_data(dir + "/f_uint16.npy"), 1.0);
  check_pattern(read_volume_data(dir + "/v2.npy"), -1.0);
  check_pattern(read_volume_data(dir + "/v3.npy"), -1.0);
  const VolumeData b = read_volume_data(dir + "/bool.npy");
  CHECK(b.type == VoxelValueType::Bool);
  CHECK(value_at(b, 1, 0, 0) == 1.0);
  CHECK(value_at(b, 0, 1, 0) == 0.0);
  CHECK(value_at(b, 1, 1, 1) == 1.0);
  const VolumeData f8 = read_volume_data(dir + "/be_f8.npy");
  for (int i = 0; i < 3; ++i) CHECK(value_at(f8, i, 2, 4) == (i + 20 + 400) / 3.0);
  check_io_error(dir + "/flat.npy", "shape (4, 5): a volume is a 3-D array (add an axis");
  check_io_error(dir + "/complex.npy", "complex dtype '<c16' is not supported");
  check_io_error(dir + "/object.npy", "object dtype '|O' is not supported");
  check_io_error(dir + "/half.npy", "float16 dtype '<f2' is not supported");
  check_io_error(dir + "/structured.npy", "a structured dtype");
  // numpy reads what write_npy writes: array[i, j, k] is voxel (i, j, k).
  for (VoxelValueType type : {VoxelValueType::Int16, VoxelValueType::Float64, VoxelValueType::Bool}) {
    write_volume_data(dir + "/ours_" + value_type_name(type) + ".npy", pattern(type, {3, 4, 5}));
  }
  CHECK(run_python("voxfmt_numpy_read", R"(
import numpy as np
i, j, k = np.meshgrid(np.arange(3), np.arange(4), np.arange(5), indexing='ij')
x = i + 10 * j + 100 * k
d = ')" + dir + R"('
a = np.load(d + '/ours_int16.npy'); assert a.dtype == np.int16 and a.shape == (3, 4, 5); assert (a == -x).all()
a = np.load(d + '/ours_float64.npy'); assert a.dtype == np.float64; assert (a == x / 3.0).all()
a = np.load(d + '/ours_bool.npy'); assert a.dtype == bool; assert (a == (x % 2 == 1)).all()
)") == 0);
}

TEST_CASE("bad npy files are named errors: magic, truncation, absurd shapes, dtypes, header syntax") {
  const std::string path = tmp_path("voxfmt_bad.npy");
  auto check = [&](const std::string& content, const std::string& what) {
    write_text(path, content);
    check_io_error(path, what);
  };
  const std::string eight(8, '\0');
  check("NUMPY\x01\x00", "not a numpy file (missing the \\x93NUMPY magic)");
  check("\x93NUMPY", "truncated numpy header (no version)");
  check("\x93NUMPY" + bytes({4, 0, 10, 0}), "unsupported numpy format version 4.0");
  check("\x93NUMPY" + bytes({1, 0, 100, 0}) + "{'descr'", "truncated numpy header: 100 bytes announced");
  check("\x93NUMPY" + bytes({2, 0, 0, 0, 0, 1}), "numpy header length 16777216 is above 65536");
  check(npy("{'descr': '<u1', 'fortran_order': False, 'shape': (2, 2, 2), }", "1234567"), "truncated data");
  check(npy("{'descr': '<u1', 'fortran_order': False, 'shape': (2, 2, 2), }", "123456789"), "longer than the array");
  check(npy("{'descr': '<u1', 'fortran_order': False, 'shape': (100000, 100000, 100000), }", eight),
        "dimensions are absurdly large");
  check(npy("{'descr': '<u1', 'fortran_order': False, 'shape': (0, 2, 2), }", ""), "every axis needs 1 to");
  check(npy("{'descr': '<u1', 'fortran_order': False, 'shape': (8,), }", eight), "shape (8,): a volume is a 3-D");
  check(npy("{'descr': '<U3', 'fortran_order': False, 'shape': (2, 2, 2), }", eight), "string dtype '<U3'");
  check(npy("{'descr': '<M8[s]', 'fortran_order': False, 'shape': (2, 2, 2), }", eight), "datetime dtype");
  check(npy("{'descr': '|i2', 'fortran_order': False, 'shape': (2, 2, 2), }", eight), "has no byte order");
  // A descr of zero or one character (found by the fuzzer: it used to throw std::out_of_range).
  check(npy("{'descr': '', 'fortran_order': False, 'shape': (2, 2, 2), }", eight), "unsupported dtype ''");
  check(npy("{'descr': '<', 'fortran_order': False, 'shape': (2, 2, 2), }", eight), "unsupported dtype '<'");
  check(npy("{'descr': '<u1', 'fortran_order': 0, 'shape': (2, 2, 2), }", eight),
        "'fortran_order' is not True or False");
  check(npy("{'descr': '<u1', 'fortran_order': False, 'shape': (2, 2, 2), 'x': 1}", eight), "unexpected key 'x'");
  check(npy("{'descr': '<u1', 'shape': (2, 2, 2), }", eight), "no 'fortran_order' key");
  check(npy("{'descr': '<u1', 'fortran_order': False, 'shape': (2, 2, 2) ", eight), "malformed numpy header");
  check(npy("{'descr': '<u1', 'fortran_order': False, 'shape': (2, -2, 2), }", eight),
        "expected a non-negative integer in the shape");
}

// ---- binvox ----

TEST_CASE("binvox built byte by byte: y fastest, then z, then x, and the model coordinates") {
  // dim 2: voxel number n = x * 4 + z * 2 + y. Set voxels 1 (y = 1), 2 (z = 1) and 4 (x = 1).
  const std::string path = tmp_path("voxfmt_order.binvox");
  write_text(path,
             "#binvox 1\ndim 2 2 2\ntranslate 1 2 3\nscale 4\ndata\n" + bytes({0, 1, 1, 1, 1, 1, 0, 1, 1, 1, 0, 3}));
  const VolumeData v = read_volume_data(path);
  CHECK(v.size == Eigen::Vector3i(2, 2, 2));
  CHECK(v.type == VoxelValueType::UInt8);
  CHECK(value_at(v, 0, 0, 0) == 0);
  CHECK(value_at(v, 0, 1, 0) == 1);
  CHECK(value_at(v, 0, 0, 1) == 1);
  CHECK(value_at(v, 0, 1, 1) == 0);
  CHECK(value_at(v, 1, 0, 0) == 1);
  CHECK(value_at(v, 1, 1, 1) == 0);
  // Voxel centres at translate + scale * (index + 0.5) / dim.
  CHECK(v.geometry.to_physical(Eigen::Vector3d(0, 0, 0)).isApprox(Eigen::Vector3d(2, 3, 4)));
  CHECK(v.geometry.to_physical(Eigen::Vector3d(1, 1, 1)).isApprox(Eigen::Vector3d(4, 5, 6)));
  // Without translate and scale: the unit cube.
  write_text(path, "#binvox 1\ndim 2 2 2\ndata\n" + bytes({1, 8}));
  const VolumeData unit = read_volume_data(path);
  CHECK(unit.geometry.to_physical(Eigen::Vector3d(1, 1, 1)).isApprox(Eigen::Vector3d::Constant(0.75)));
  CHECK(read_volume_as_voxels(path, {}).count() == 8);
  // Version 2: values up to 255.
  write_text(path, "#binvox 2\ndim 2 2 2\ndata\n" + bytes({7, 1, 0, 7}));
  CHECK(value_at(read_volume_data(path), 0, 0, 0) == 7);
}

TEST_CASE("binvox round trip: values 0 or 1 of any type, long runs, the geometry kept") {
  VolumeData v = pattern(VoxelValueType::Int16, {20, 20, 20});
  // Long runs (more than 255 equal voxels) in the first half.
  std::fill(v.bytes.begin(), v.bytes.begin() + std::ptrdiff_t(v.bytes.size() / 2), 0);
  v.geometry.spacing = Eigen::Vector3d::Constant(0.125);
  v.geometry.origin = Eigen::Vector3d(-1, 0.5, 3);
  const std::string path = tmp_path("voxfmt_round.binvox");
  write_volume_data(path, v);
  const VolumeData r = read_volume_data(path);
  REQUIRE(r.size == v.size);
  for (int k = 0; k < 20; ++k)
    for (int j = 0; j < 20; ++j)
      for (int i = 0; i < 20; ++i) REQUIRE(value_at(r, i, j, k) == (value_at(v, i, j, k) != 0 ? 1 : 0));
  CHECK(r.geometry.spacing.isApprox(v.geometry.spacing));
  CHECK(r.geometry.origin.isApprox(v.geometry.origin));
  VolumeData flat = pattern(VoxelValueType::UInt8, {2, 3, 2});
  CHECK_THROWS_WITH_AS(write_volume_data(path, flat), doctest::Contains("binvox grids are cubes"), IoError);
  VolumeData aniso = pattern(VoxelValueType::UInt8, {2, 2, 2});
  aniso.geometry.spacing = Eigen::Vector3d(1, 1, 2.5);
  CHECK_THROWS_WITH_AS(write_volume_data(path, aniso), doctest::Contains("anisotropic spacing"), IoError);
}

TEST_CASE("bad binvox files are named errors: magic, runs, truncation, absurd dimensions") {
  const std::string path = tmp_path("voxfmt_bad.binvox");
  auto check = [&](const std::string& content, const std::string& what) {
    write_text(path, content);
    check_io_error(path, what);
  };
  const std::string head = "#binvox 1\ndim 2 2 2\ndata\n";
  check("#binvax 1\n", "not a binvox file");
  check("#binvox 3\n", "unsupported binvox version '#binvox 3'");
  check("#binvox 1\ndim 2 2 2\n", "truncated binvox header (no 'data' line)");
  check("#binvox 1\ndata\n", "no 'dim' line");
  check("#binvox 1\ndim 2 2 3\ndata\n", "binvox grids are cubes");
  check("#binvox 1\ndim 100000 100000 100000\ndata\n", "dimensions are absurdly large");
  check("#binvox 1\ndim 2 2 2\nscale -1\ndata\n", "binvox 'scale' must be positive");
  check("#binvox 1\ndim 2 2 2\nscale nan\ndata\n", "malformed binvox 'scale' line");
  check("#binvox 1\ndim 2 2 2\ncolour 3\ndata\n", "unknown binvox header line 'colour 3'");
  check(head + bytes({1, 0, 1, 8}), "binvox run of length 0 at voxel 0");
  check(head + bytes({1, 5, 0, 5}), "binvox runs hold more voxels than dim 2^3 = 8");
  check(head + bytes({1, 8, 0}), "binvox data goes on after the last");
  check(head + bytes({1, 4, 0, 2, 1}), "binvox data ends inside a (value, count) pair");
  check(head + bytes({1, 4, 0, 2}), "truncated binvox data: 6 of 8 voxels");
  check(head + bytes({2, 8}), "binvox value 2 at voxel 0 in a version 1 file");
  check(head, "truncated data");
}

// ---- MagicaVoxel ----

namespace {
std::string chunk(const std::string& id, const std::string& content, const std::string& children = "") {
  return id + le32(std::uint32_t(content.size())) + le32(std::uint32_t(children.size())) + content + children;
}
std::string vox(const std::string& children) { return "VOX " + le32(150) + chunk("MAIN", "", children); }
std::string size_chunk(int x, int y, int z) {
  return chunk("SIZE", le32(std::uint32_t(x)) + le32(std::uint32_t(y)) + le32(std::uint32_t(z)));
}
std::string xyzi(std::initializer_list<std::array<int, 4>> voxels) {
  std::string s = le32(std::uint32_t(voxels.size()));
  for (const auto& v : voxels) s += bytes({v[0], v[1], v[2], v[3]});
  return chunk("XYZI", s);
}
}  // namespace

TEST_CASE("MagicaVoxel built byte by byte: the palette indices at their voxels, other chunks skipped") {
  const std::string path = tmp_path("voxfmt_model.vox");
  write_text(path,
             vox(chunk("PACK", le32(1)) + size_chunk(3, 4, 5) + xyzi({{0, 0, 0, 1}, {2, 3, 4, 255}, {1, 2, 3, 17}}) +
                 chunk("RGBA", std::string(1024, '\x7f')) + chunk("nTRN", "abc", chunk("nSHP", "de"))));
  const VolumeData v = read_volume_data(path);
  CHECK(v.size == Eigen::Vector3i(3, 4, 5));
  CHECK(v.type == VoxelValueType::UInt8);
  CHECK(value_at(v, 0, 0, 0) == 1);
  CHECK(value_at(v, 2, 3, 4) == 255);
  CHECK(value_at(v, 1, 2, 3) == 17);
  CHECK(value_at(v, 1, 0, 0) == 0);
  double total = 0;
  for (std::uint8_t b : v.bytes) total += b;
  CHECK(total == 1 + 255 + 17);
  VolumeReadOptions one;
  one.inside = InsideRule::label(17);
  CHECK(read_volume_as_voxels(path, one).count() == 1);
}

TEST_CASE("bad MagicaVoxel files are named errors: magic, chunk sizes, coordinates, several models") {
  const std::string path = tmp_path("voxfmt_bad.vox");
  auto check = [&](const std::string& content, const std::string& what) {
    write_text(path, content);
    check_io_error(path, what);
  };
  check("VOXX" + le32(150), "not a MagicaVoxel file");
  check("VOX " + le32(151), "unsupported MagicaVoxel version 151");
  check("VOX " + le32(150) + "MAIN", "truncated MagicaVoxel file in the MAIN chunk");
  check(vox(size_chunk(3, 4, 5) + xyzi({{3, 0, 0, 1}})), "voxel 0 at (3, 0, 0) is outside the SIZE 3 x 4 x 5");
  check(vox(size_chunk(3, 4, 5) + xyzi({{0, 0, 0, 0}})), "has colour index 0");
  check(vox(size_chunk(300, 4, 5) + xyzi({})), "each side must be 1 to 256 voxels");
  check(vox(size_chunk(0, 4, 5) + xyzi({})), "each side must be 1 to 256 voxels");
  check(vox(size_chunk(2, 2, 2) + xyzi({}) + size_chunk(2, 2, 2) + xyzi({})), "the file holds several models");
  check(vox(xyzi({})), "XYZI chunk before any SIZE chunk");
  check(vox(size_chunk(2, 2, 2)), "model without an XYZI chunk");
  check(vox(chunk("RGBA", "")), "without a SIZE chunk");
  // XYZI announcing more voxels than its bytes hold; a chunk longer than the file.
  check(vox(size_chunk(2, 2, 2) + chunk("XYZI", le32(1000000) + bytes({0, 0, 0, 1}))),
        "cannot hold the 1 000 000 voxels");
  std::string cut = vox(size_chunk(2, 2, 2) + xyzi({{0, 0, 0, 1}}));
  check(cut.substr(0, cut.size() - 2), "MAIN chunk announces");
  std::string longer = vox(size_chunk(2, 2, 2) + xyzi({{0, 0, 0, 1}}));
  longer.replace(longer.size() - 16, 4, le32(1000));  // the XYZI content size
  check(longer, "chunk 'XYZI' announces 1 000 bytes");
}

// ---- TIFF ----

TEST_CASE("TIFF round trip: a multi-page stack of every value type, a page in several strips, the page budget") {
  if (!have_tiff()) return;
  for (VoxelValueType type : kAllTypes) {
    CAPTURE(value_type_name(type));
    const VolumeData v = pattern(type, {13, 7, 5});
    const std::string path = tmp_path("voxfmt_round_" + value_type_name(type) + ".tif");
    write_volume_data(path, v);
    const VolumeData r = read_volume_data(path);
    CHECK(r.size == v.size);
    CHECK(r.type == v.type);
    CHECK(r.bytes == v.bytes);
  }
  // A large page in several strips.
  const VolumeData big = pattern(VoxelValueType::UInt16, {300, 250, 3});
  const std::string path = tmp_path("voxfmt_big.tiff");
  write_volume_data(path, big);
  CHECK(read_volume_data(path).bytes == big.bytes);
  // The page being decoded counts against the memory budget, not only the bit grid.
  struct RestoreBudget {
    ~RestoreBudget() { set_memory_budget(0); }
  } restore;
  set_memory_budget(100 * 1024);
  CHECK_THROWS_WITH_AS(read_volume_as_voxels(path, {}), doctest::Contains("one page of 300 x 250 uint16"), IoError);
}

TEST_CASE(
    "TIFF stacks written by tifffile: multi-page, strips, tiles, zlib, big-endian, ImageJ spacing, a folder in natural "
    "order") {
  if (!have_tiff() || !have_python("numpy, tifffile")) return;
  const std::string dir = tmp_path("voxfmt_tifffile");
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir + "/slices");
  std::filesystem::create_directories(dir + "/mixed");
  const int rc = run_python("voxfmt_tifffile", R"(
import numpy as np, tifffile
k, j, i = np.meshgrid(np.arange(12), np.arange(40), np.arange(35), indexing='ij')
x = i + 10 * j + 100 * k   # tifffile's arrays are [page, row, column] = voxel (i, j, k)
d = ')" + dir + R"('
tifffile.imwrite(d + '/stack.tif', x.astype(np.uint16))
tifffile.imwrite(d + '/tiled.tif', (-x).astype(np.int32), tile=(16, 16), compression='zlib')
tifffile.imwrite(d + '/zlib.tif', x.astype(np.float32), compression='zlib', rowsperstrip=7)
tifffile.imwrite(d + '/strips.tif', (x % 256).astype(np.uint8), rowsperstrip=3)
tifffile.imwrite(d + '/be.tif', x.astype('>f8'), byteorder='>')
tifffile.imwrite(d + '/imagej.tif', x.astype(np.uint16), imagej=True, resolution=(1 / 0.5, 1 / 0.25),
                 metadata={'spacing': 2.5, 'unit': 'micron'})
for n in range(12):
    tifffile.imwrite(d + '/slices/slice%d.tif' % (n + 1), x[n].astype(np.float32))
tifffile.imwrite(d + '/rgb.tif', np.zeros((4, 5, 3), np.uint8), photometric='rgb')
tifffile.imwrite(d + '/half.tif', np.zeros((2, 4, 5), np.float16))
tifffile.imwrite(d + '/mixed/a1.tif', np.zeros((4, 5), np.uint8))
tifffile.imwrite(d + '/mixed/a2.tif', np.zeros((4, 6), np.uint8))
)");
  REQUIRE(rc == 0);
  check_pattern(read_volume_data(dir + "/stack.tif"), 1.0);
  check_pattern(read_volume_data(dir + "/tiled.tif"), -1.0);
  check_pattern(read_volume_data(dir + "/zlib.tif"), 1.0);
  check_pattern(read_volume_data(dir + "/be.tif"), 1.0);
  CHECK(read_volume_data(dir + "/stack.tif").geometry.affine().isApprox(Eigen::Matrix4d::Identity()));
  // ImageJ's pixel size (resolution tags) and slice spacing.
  const VolumeData imagej = read_volume_data(dir + "/imagej.tif");
  check_pattern(imagej, 1.0);
  CHECK(imagej.geometry.spacing.isApprox(Eigen::Vector3d(0.5, 0.25, 2.5)));
  const VolumeData pb = read_volume_data(dir + "/strips.tif");
  CHECK(value_at(pb, 34, 39, 11) == (34 + 390 + 1100) % 256);
  const VolumeData slices = read_volume_data(dir + "/slices");
  CHECK(slices.size == Eigen::Vector3i(35, 40, 12));
  check_pattern(slices, 1.0);  // slice10 after slice9, not after slice1
  check_io_error(dir + "/rgb.tif", "3 samples per pixel (RGB or with alpha)");
  check_io_error(dir + "/half.tif", "16-bit floating-point samples");
  check_io_error(dir + "/mixed", "slice 'a2.tif' is 6 x 4 uint8, the first slice 5 x 4 uint8");
  // tifffile reads what write_tiff writes.
  write_volume_data(dir + "/ours.tif", pattern(VoxelValueType::Int16, {35, 40, 12}));
  write_volume_data(dir + "/ours_bool.tif", pattern(VoxelValueType::Bool, {35, 40, 12}));
  CHECK(run_python("voxfmt_tifffile_read", R"(
import numpy as np, tifffile
k, j, i = np.meshgrid(np.arange(12), np.arange(40), np.arange(35), indexing='ij')
x = i + 10 * j + 100 * k
d = ')" + dir + R"('
a = tifffile.imread(d + '/ours.tif'); assert a.dtype == np.int16 and a.shape == (12, 40, 35), a.shape; assert (a == -x).all()
a = tifffile.imread(d + '/ours_bool.tif'); assert a.dtype == bool, a.dtype; assert (a == (x % 2 == 1)).all()
)") == 0);
}

TEST_CASE("bad TIFF files are named errors: magic, truncation, an empty folder, slices of other sizes") {
  if (!have_tiff()) return;
  const std::string path = tmp_path("voxfmt_bad.tif");
  write_text(path, "II*\0garbage");
  check_io_error(path, "cannot open as TIFF");
  write_text(path, "not a tiff at all");
  check_io_error(path, "cannot open as TIFF");
  write_volume_data(path, pattern(VoxelValueType::UInt16, {64, 64, 4}));
  const std::string whole = read_text(path);
  write_text(path, whole.substr(0, whole.size() / 2));
  check_io_error(path, "the chain of pages is broken (truncated file?)");
  write_text(path, whole.substr(0, whole.size() - 3));
  check_io_error(path, "the chain of pages is broken (truncated file?)");
  const std::string empty = tmp_path("voxfmt_empty_folder");
  std::filesystem::remove_all(empty);
  std::filesystem::create_directories(empty);
  write_text(empty + "/notes.txt", "not a slice");
  check_io_error(empty, "the folder holds no .tif or .tiff slice");
  const std::string mixed = tmp_path("voxfmt_mixed_folder");
  std::filesystem::remove_all(mixed);
  std::filesystem::create_directories(mixed);
  write_volume_data(mixed + "/s01.tif", pattern(VoxelValueType::UInt8, {4, 4, 1}));
  write_volume_data(mixed + "/s02.tif", pattern(VoxelValueType::UInt16, {4, 4, 1}));
  check_io_error(mixed, "slice 's02.tif' is 4 x 4 uint16, the first slice 4 x 4 uint8");
  write_volume_data(mixed + "/s02.tif", pattern(VoxelValueType::UInt8, {4, 4, 2}));
  check_io_error(mixed, "slice 's02.tif' has several pages");
  CHECK_THROWS_WITH_AS(write_volume_data(mixed, pattern(VoxelValueType::UInt8, {4, 4, 2})),
                       doctest::Contains("is a folder; write a multi-page TIFF"), IoError);
}
