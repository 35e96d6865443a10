// Regression tests of the reliability probe (ASan/UBSan, libFuzzer, hand-made files): announced
// counts and sizes are checked in 64 bits against what the file can hold before anything is
// allocated or looped over, and values read from a file are converted to integers only through a
// checked helper. Small hand-made inputs live in tests/data/bad_inputs/ (see its README.md).
#include <doctest/doctest.h>

#include <corrlap/core/error.hpp>
#include <corrlap/core/stopwatch.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/io/text_io.hpp>
#include <corrlap/io/volume_io.hpp>
#include <cstdint>
#include <cstring>
#include <limits>

#include "test_support.hpp"

using namespace corrlap;
using corrlap::test::tmp_path;
using corrlap::test::write_text;

namespace {

std::string bad_input(const std::string& name) { return corrlap::test::reference_dir() + "/bad_inputs/" + name; }

// Runs read, expects an InputError whose message contains every fragment; returns the seconds taken.
template <class F>
double expect_error(F&& read, const std::vector<std::string>& fragments) {
  const Stopwatch watch;
  bool threw = false;
  try {
    read();
  } catch (const InputError& e) {
    threw = true;
    const std::string m = e.what();
    CAPTURE(m);
    for (const auto& f : fragments) {
      CAPTURE(f);
      CHECK(m.find(f) != std::string::npos);
    }
  }
  CHECK(threw);
  return watch.elapsed();
}

template <class T>
void append(std::string& s, T v) {
  s.append(reinterpret_cast<const char*>(&v), sizeof v);
}

}  // namespace

// ---- memory safety: voxel counts in 64 bits, checked against the file before allocating ----

TEST_CASE("NRRD sizes whose voxel count wraps 32 bits are rejected before reading (ascii, gzip)") {
  // 65536 x 65537 x 1 = 2^32 + 2^16 voxels: the old int product wrapped to 65536, the buffer was
  // allocated that small and the reads ran past it (SIGSEGV in Release).
  expect_error(
      [] { read_volume(bad_input("nrrd_sizes_wrap_ascii.nrrd")); },
      {"nrrd_sizes_wrap_ascii.nrrd",
       "sizes 65536 x 65537 x 1 = 4 295 032 832 voxels need at least 8.0 GiB, more than the 8 B the file holds"});
  if (nrrd_gzip_supported())
    expect_error([] { read_volume(bad_input("nrrd_sizes_wrap_gzip.nrrd")); },
                 {"nrrd_sizes_wrap_gzip.nrrd", "sizes 65536 x 65537 x 1 = 4 295 032 832 voxels need 4.0 GiB",
                  "of gzip data can hold (deflate expands at most 1032 times)"});
  // A caller-built Volume with a mismatching buffer is an error, not an out-of-bounds read.
  Volume v;
  v.size = Eigen::Vector3i(65536, 65537, 1);
  v.values.assign(65536, 1);
  CHECK_THROWS_WITH_AS(threshold_volume(v, 0.5, 1.0),
                       doctest::Contains("65 536 values do not match its sizes 65536 x 65537 x 1"), InputError);
  CHECK_THROWS_WITH_AS(write_volume(tmp_path("mismatch.vol"), v),
                       doctest::Contains("does not match its sizes 65536 x 65537 x 1"), IoError);
  // Raw dimensions from the command line whose product does not even fit in 64 bits.
  VolumeReadOptions huge;
  const int m = std::numeric_limits<int>::max();
  huge.raw_dimensions = Eigen::Vector3i(m, m, m);
  const std::string raw = tmp_path("eight_bytes.raw");
  write_text(raw, "12345678");
  expect_error([&] { read_volume(raw, huge); }, {"overflow 64 bits, more than the 16.0 GiB a volume may hold"});
}

TEST_CASE("NRRD gzip: announced sizes bounded by what the compressed bytes can hold, inflating stops at the sizes") {
  if (!nrrd_gzip_supported()) {
    MESSAGE("built without zlib: gzip bounds not tested");
    return;
  }
  // 1 GiB announced with 24 bytes of gzip data (at most 24 * 1032 + 1024 bytes): the old reader
  // allocated the whole gigabyte before inflating.
  const double s = expect_error([] { read_volume(bad_input("nrrd_gzip_1gib.nrrd")); },
                                {"sizes 1024 x 1024 x 1024 = 1 073 741 824 voxels need 1.0 GiB, more than the 25.2 KiB "
                                 "that 24 B of gzip data can hold"});
  CHECK(s < 1.0);
  // 4 MiB of zeros announced as 2 x 2 x 2: rejected as soon as the 9th byte comes out.
  expect_error([] { read_volume(bad_input("nrrd_gzip_bomb.nrrd")); },
               {"gzip data holds more bytes than the sizes announce (8)"});
}

TEST_CASE("Matrix Market: banner fields parsed exactly, every index checked, entries counted") {
  const std::string p = tmp_path("mm_bounds.mtx");
  auto bad = [&](const std::string& content, const std::string& fragment) {
    write_text(p, content);
    CAPTURE(content);
    expect_error([&] { read_matrix_market(p); }, {p, fragment});
  };
  // "symmetric" with a non-square size used to be mirrored into out-of-range triplets (heap
  // overflow in setFromTriplets).
  bad("%%MatrixMarket matrix coordinate real symmetric\n2 5 1\n1 4 1\n",
      "a symmetric matrix must be square, the size line declares 2 x 5");
  // The word anywhere in the line was taken as the symmetry field.
  bad("%%MatrixMarket matrix coordinate real nonsymmetric\n2 2 1\n1 1 1\n", "unsupported symmetry 'nonsymmetric'");
  bad("%%MatrixMarket matrix coordinate real general % symmetric\n2 2 1\n1 1 1\n", "malformed header");
  bad("%%MatrixMarket matrix coordinate real skew-symmetric\n2 2 1\n2 1 1\n", "unsupported symmetry 'skew-symmetric'");
  bad("%%MatrixMarket matrix coordinate real symmetric\n3 3 1\n1 3 1\n",
      "line 3, entry 1: (1, 3) is above the diagonal");
  bad("%%MatrixMarket matrix coordinate real general\n2 2 1\n1 3 1\n",
      "entry 1: index (1, 3) out of range for a 2 x 2 matrix");
  bad("%%MatrixMarket matrix coordinate real general\n2 2 1\n0 1 1\n", "index (0, 1) out of range");
  bad("%%MatrixMarket matrix coordinate real general\n2 2 1\n1 1 1\n2 2 2\n",
      "line 4: more entries than the 1 declared");
  bad("%%MatrixMarket matrix coordinate pattern general\n2 2 1\n1 1 1\n",
      "malformed entry '1 1 1' (expected 'row column')");
  // 70 bytes declaring 2^27 columns: Eigen's outer index alone would take 512 MiB (2 GB with the
  // temporaries of setFromTriplets).
  const double t = expect_error(
      [&] {
        write_text(p, "%%MatrixMarket matrix coordinate real general\n1 134217728 1\n1 1 1\n");
        read_matrix_market(p);
      },
      {"absurd size line: 1 x 134 217 728 for 1 entries (each dimension is limited to max(1 048 576, 4 x entries)"});
  CHECK(t < 0.5);
  bad("%%MatrixMarket matrix coordinate real general\n100000 100000 1000000\n1 1 1\n",
      "1 000 000 entries need at least 5.7 MiB, more than the");

  // Valid files: symmetric lower triangle expanded, pattern entries are ones, integer values.
  write_text(p, "%%MatrixMarket matrix coordinate real symmetric\n% comment\n3 3 3\n1 1 2\n3 1 -1.5\n3 3 4\n");
  Eigen::SparseMatrix<double> A = read_matrix_market(p);
  CHECK(A.nonZeros() == 4);
  CHECK(A.coeff(0, 2) == -1.5);
  CHECK(A.coeff(2, 0) == -1.5);
  CHECK(A.coeff(2, 2) == 4.0);
  write_text(p, "%%MATRIXMARKET Matrix Coordinate Pattern General\n2 3 2\n1 3\n2 1\n");
  A = read_matrix_market(p);
  CHECK(A.rows() == 2);
  CHECK(A.cols() == 3);
  CHECK(A.coeff(0, 2) == 1.0);
  CHECK(A.coeff(1, 0) == 1.0);
  write_text(p, "%%MatrixMarket matrix coordinate integer general\n1 1 1\n1 1 -7\n\n");
  CHECK(read_matrix_market(p).coeff(0, 0) == -7.0);
}

// ---- undefined behaviour: values read from a file reach integers only through checks ----

TEST_CASE("PLY: huge, NaN and infinite counts and indices are named errors, not undefined conversions") {
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n";
  const std::string p = tmp_path("ply_checked.ply");
  auto bad = [&](const std::string& content, const std::string& fragment) {
    write_text(p, content);
    CAPTURE(fragment);
    expect_error([&] { read_ply(p); }, {p, fragment});
  };
  bad(head + "1e300 0 1 2\n", "element 'face' #0, property 'vertex_indices' (line 13): invalid list length 1e+300");
  bad(head + "inf 0 1 2\n", "non-integer value 'inf' for an integer property");
  bad(head + "nan 0 1 2\n", "non-integer value 'nan'");
  bad(head + "3 0 1 1e300\n", "face 0, property 'vertex_indices': vertex index 1e+300 out of range (3 vertices)");
  bad(head + "3 0 1 -1\n", "vertex index -1 out of range");
  // Binary float indices: NaN and 3e9 (beyond int) are out of range, never cast.
  std::string bin =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double "
      "z\n"
      "element face 1\nproperty list uint float vertex_indices\nend_header\n";
  for (double d : {0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0}) append(bin, d);
  std::string nan_id = bin, big_id = bin, big_len = bin;
  append(nan_id, std::uint32_t(3));
  for (float f : {0.0f, 1.0f, std::numeric_limits<float>::quiet_NaN()}) append(nan_id, f);
  bad(nan_id, "vertex index nan out of range (3 vertices)");
  append(big_id, std::uint32_t(3));
  for (float f : {0.0f, 1.0f, 3e9f}) append(big_id, f);
  bad(big_id, "vertex index 3e+09 out of range");
  append(big_len, std::uint32_t(4000000000u));
  bad(big_len, "invalid list length 4e+09");
}

// ---- unbounded work: header lines and element counts bounded by the bytes of the file ----

TEST_CASE("PLY: elements without properties cost nothing, counts are bounded by the file, headers by lines") {
  // 2000 elements of 2^31 entries without properties (the old reader looped over every entry,
  // about a second each) in front of a valid triangle.
  std::string junk;
  for (int i = 0; i < 2000; ++i) junk += "element empty" + std::to_string(i) + " 2147483648\n";
  const std::string p = tmp_path("ply_empty_elements.ply");
  write_text(p,
             "ply\nformat ascii 1.0\n" + junk +
                 "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                 "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  const Stopwatch watch;
  const PolygonMesh mesh = read_ply(p);
  CHECK(watch.elapsed() < 1.0);
  CHECK(mesh.positions.rows() == 3);
  CHECK(mesh.faces.size() == 1);
  // An element with one property needs at least one byte (binary) or two characters per entry.
  write_text(p,
             "ply\nformat binary_little_endian 1.0\nelement junk 2147483648\nproperty uchar a\n"
             "element vertex 1\nproperty double x\nproperty double y\nproperty double z\nelement face 1\n"
             "property list uchar int vertex_indices\nend_header\n0123456789");
  expect_error([&] { read_ply(p); },
               {"element 'junk' announces 2 147 483 648 entries", "need at least 2.0 GiB, more than the 10 B"});
  std::string comments;
  for (int i = 0; i < 10001; ++i) comments += "comment x\n";
  write_text(p, "ply\nformat ascii 1.0\n" + comments + "end_header\n");
  expect_error([&] { read_ply(p); }, {"header longer than 10000 lines"});
}

TEST_CASE("OFF: counts bounded by the file size before reserving") {
  const std::string p = tmp_path("off_counts.off");
  write_text(p, "OFF\n2147483648 2147483648 0\n0 0 0\n");
  expect_error([&] { read_off(p); },
               {"counts announce 2 147 483 648 vertices and 2 147 483 648 faces, which need at least 28.0 GiB",
                "more than the 34 B the file holds"});
  write_text(p, "OFF\n2147483649 1 0\n");
  expect_error([&] { read_off(p); }, {"absurd counts 2147483649 1 (limit 2 147 483 648)"});
}
