// The readers that stream their files in blocks (PLY, OFF, Matrix Market): whatever the block size,
// down to one byte (every value, record and line then straddles a block boundary), they read the
// same values and give the same errors as with the default 4 MiB block; every PLY property type
// reads back exactly; corners are reserved from the face degrees, not assumed triangles.
#include <doctest/doctest.h>

#include <Eigen/Sparse>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/io/detail/block_readers.hpp>
#include <corrlap/io/detail/corner_reserve.hpp>
#include <corrlap/io/detail/line_reader.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/io/text_io.hpp>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "../test_support.hpp"

using namespace corrlap;
using corrlap::test::tmp_path;
using corrlap::test::write_text;

namespace {

// Block sizes from one byte to larger than the files, and the default.
const std::size_t kBlocks[] = {1, 2, 3, 5, 8, 13, 64, 1000, io_detail::LineReader::kDefaultBlock};

template <class T>
void put(std::string& s, T v) {
  s.append(reinterpret_cast<const char*>(&v), sizeof v);
}

bool same_bits(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * std::size_t(a.size())) == 0;
}

// The message of the IoError a read throws ("" when it does not throw).
template <class F>
std::string error_of(F&& read) {
  try {
    read();
  } catch (const IoError& e) {
    return e.what();
  }
  return "";
}

// 5 vertices (float x y z, uchar red, double nx ny nz, short label), 3 faces (a triangle, a quad,
// a pentagon: the corner reserve grows) with a uchar count and int ids and an int flag, then an
// element that is read and dropped (a list and a uint).
struct Sample {
  std::vector<float> xyz = {0.1f, -2.5f, 3e-38f, 1, 0, 0, 0, 1, 0, -1e30f, 0.5f, 7, 2, 2, 2};
  std::vector<double> n = {0.1, 0.2, 0.3, -1, 0, 0, 0, 1, 0, 1e-310, 1e300, -0.0, 1, 1, 1};
  std::vector<int> red = {255, 0, 1, 2, 3}, label = {-32768, 32767, 0, -1, 5};
  FaceList faces{{0, 1, 2}, {1, 2, 3, 4}, {4, 3, 2, 1, 0}};
  std::vector<int> flags = {7, -8, 2147483647};

  std::string header(const char* format) const {
    return std::string("ply\nformat ") + format +
           " 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\n"
           "property double nx\nproperty double ny\nproperty double nz\nproperty short label\n"
           "element face 3\nproperty list uchar int vertex_indices\nproperty int flags\n"
           "element extra 2\nproperty list ushort uint ids\nproperty uint tag\nend_header\n";
  }
  std::string binary() const {
    std::string s = header("binary_little_endian");
    for (int v = 0; v < 5; ++v) {
      for (int c = 0; c < 3; ++c) put(s, xyz[std::size_t(3 * v + c)]);
      put(s, std::uint8_t(red[std::size_t(v)]));
      for (int c = 0; c < 3; ++c) put(s, n[std::size_t(3 * v + c)]);
      put(s, std::int16_t(label[std::size_t(v)]));
    }
    for (std::size_t f = 0; f < faces.size(); ++f) {
      put(s, std::uint8_t(faces[f].size()));
      for (int id : faces[f]) put(s, std::int32_t(id));
      put(s, std::int32_t(flags[f]));
    }
    for (std::uint32_t k = 0; k < 2; ++k) {
      put(s, std::uint16_t(k + 1));
      for (std::uint32_t j = 0; j <= k; ++j) put(s, j);
      put(s, 4000000000u);
    }
    return s;
  }
  std::string ascii() const {
    char buf[64];
    std::string s = header("ascii");
    for (int v = 0; v < 5; ++v) {
      for (int c = 0; c < 3; ++c) {
        std::snprintf(buf, sizeof buf, "%.17g ", double(xyz[std::size_t(3 * v + c)]));  // the float's value
        s += buf;
      }
      (s += std::to_string(red[std::size_t(v)])) += "  ";
      for (int c = 0; c < 3; ++c) {
        std::snprintf(buf, sizeof buf, "%.17g\t", n[std::size_t(3 * v + c)]);
        s += buf;
      }
      s += std::to_string(label[std::size_t(v)]);
      s += v == 2 ? "\r\n" : "\n";  // CRLF once
    }
    for (std::size_t f = 0; f < faces.size(); ++f) {
      s += std::to_string(faces[f].size());
      for (int id : faces[f]) (s += ' ') += std::to_string(id);  // not " " + ...: GCC 12's false -Wrestrict
      (s += ' ') += std::to_string(flags[f]) + "\n";
    }
    return s + "1 0 4000000000\n2 0 1\n4000000000\n\n";  // an entry over two lines, a blank line at the end
  }
  void check(const PolygonMesh& m, const MeshAttributes& a) const {
    REQUIRE(m.positions.rows() == 5);
    for (int v = 0; v < 5; ++v)
      for (int c = 0; c < 3; ++c) CHECK(m.positions(v, c) == double(xyz[std::size_t(3 * v + c)]));
    CHECK(m.faces == faces);
    REQUIRE(a.vertex_normals.rows() == 5);
    for (int v = 0; v < 5; ++v)
      for (int c = 0; c < 3; ++c)
        CHECK(std::memcmp(&a.vertex_normals(v, c), &n[std::size_t(3 * v + c)], sizeof(double)) == 0);  // -0.0 too
    REQUIRE(a.vertex_scalars.size() == 2);
    REQUIRE(a.face_scalars.size() == 1);
    for (int v = 0; v < 5; ++v) {
      CHECK(a.vertex_scalars.at("red")[v] == red[std::size_t(v)]);
      CHECK(a.vertex_scalars.at("label")[v] == label[std::size_t(v)]);
    }
    for (int f = 0; f < 3; ++f) CHECK(a.face_scalars.at("flags")[f] == flags[std::size_t(f)]);
    CHECK(a.face_normals.rows() == 0);
  }
};

}  // namespace

TEST_CASE("PLY binary and ASCII read the same at every block size: every type, attributes, dropped elements") {
  const Sample sample;
  for (const bool binary : {true, false}) {
    const std::string p = tmp_path(binary ? "blocks_bin.ply" : "blocks_ascii.ply");
    write_text(p, binary ? sample.binary() : sample.ascii());
    for (std::size_t block : kBlocks) {
      CAPTURE(binary);
      CAPTURE(block);
      MeshAttributes a;
      sample.check(io_detail::read_ply(p, &a, block), a);
      // Without attributes the mesh is the same (the columns are not kept).
      CHECK(io_detail::read_ply(p, nullptr, block).faces == sample.faces);
    }
  }
}

TEST_CASE("PLY: every index type in binary and ASCII, float indices, wide counts, at every block size") {
  const char* types[] = {"char", "uchar", "short", "ushort", "int", "uint", "float", "double"};
  const int bytes[] = {1, 1, 2, 2, 4, 4, 4, 8};
  const FaceList faces{{0, 1, 2, 3}, {3, 2, 1}, {0, 2, 1, 3}};
  for (int t = 0; t < 8; ++t) {
    for (const char* count : {"uchar", "uint"}) {
      std::string head = std::string("ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty double x\n") +
                         "property double y\nproperty double z\nelement face 3\nproperty list " + count + " " +
                         types[t] + " vertex_index\nend_header\n";
      std::string bin = head;
      for (int k = 0; k < 12; ++k) put(bin, double(k) / 3.0);
      for (const auto f : faces) {
        if (std::string(count) == "uchar")
          put(bin, std::uint8_t(f.size()));
        else
          put(bin, std::uint32_t(f.size()));
        for (int id : f) {
          std::uint64_t raw = 0;  // the id as the type's bytes
          if (t == 6) {
            const float x = float(id);
            std::memcpy(&raw, &x, 4);
          } else if (t == 7) {
            const double x = double(id);
            std::memcpy(&raw, &x, 8);
          } else {
            raw = std::uint64_t(id);
          }
          bin.append(reinterpret_cast<const char*>(&raw), std::size_t(bytes[t]));
        }
      }
      const std::string p = tmp_path("index_types.ply");
      write_text(p, bin);
      for (std::size_t block : {std::size_t(1), std::size_t(3), std::size_t(7), io_detail::LineReader::kDefaultBlock}) {
        CAPTURE(types[t]);
        CAPTURE(block);
        const PolygonMesh m = io_detail::read_ply(p, nullptr, block);
        CHECK(m.faces == faces);
        CHECK(m.positions(3, 2) == 11.0 / 3.0);
      }
    }
  }
}

TEST_CASE("PLY: errors are the same whatever the block size") {
  const Sample sample;
  const std::string bin = sample.binary(), ascii = sample.ascii();
  const std::size_t body = sample.header("binary_little_endian").size();
  std::string bad_id = bin, bad_z = bin, cut = bin.substr(0, bin.size() - 2);
  bad_id[body + 5 * 39 + 1 + 4] = char(9);  // second id of the first face: 9 (5 vertices)
  const float inf = std::numeric_limits<float>::infinity();
  std::memcpy(&bad_z[body + 39 * 3 + 8], &inf, 4);         // z of vertex 3
  const std::size_t quad = ascii.find("\n4 1 2 3 4") + 9;  // the quad's last id
  const std::string ascii_bad = ascii.substr(0, quad) + "x" + ascii.substr(quad + 1);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {bad_id, "face 0, property 'vertex_indices': vertex index 9 out of range (5 vertices)"},
      {bad_z, "vertex 3: non-finite value of 'z'"},
      {cut, "truncated binary data: end of file while reading extra"},
      {bin + "x", "trailing data after the last element (1 bytes)"},
      {bin.substr(0, body + 39 * 2 + 20), "truncated data: element 'vertex' announces 5 entries"},
      {ascii_bad, "line 25: malformed number 'x' in face"},
      {ascii.substr(0, ascii.size() - 14), "truncated data: end of file while reading extra"},
      {ascii + "9\n", "trailing data after the last element (line 31)"},
  };
  const std::string p = tmp_path("blocks_errors.ply");
  for (const auto& c : cases) {  // no structured binding: CAPTURE's lambda cannot take one in clang 14
    const std::string& fragment = c.second;
    write_text(p, c.first);
    const std::string expected = error_of([&] { read_ply(p); });
    CAPTURE(fragment);
    CAPTURE(expected);
    CHECK(expected.find(fragment) != std::string::npos);
    for (std::size_t block : kBlocks) {
      CAPTURE(block);
      CHECK(error_of([&] { io_detail::read_ply(p, nullptr, block); }) == expected);
    }
  }
}

TEST_CASE("PLY round trip of extreme doubles is exact through small blocks, binary and ASCII") {
  std::mt19937_64 rng(3);
  PolygonMesh m;
  m.positions.resize(300, 3);
  for (Eigen::Index i = 0; i < m.positions.size(); ++i) {
    double d = 0;
    do {
      const std::uint64_t bits = rng();
      std::memcpy(&d, &bits, 8);
    } while (!std::isfinite(d));
    m.positions.data()[i] = d;
  }
  m.positions(0, 0) = std::numeric_limits<double>::denorm_min();
  m.positions(1, 0) = -0.0;
  for (int f = 0; f + 3 < 300; f += 2) m.faces.push_back({f, f + 1, f + 2, f + 3});
  MeshAttributes a;
  a.vertex_scalars["s"] = m.positions.col(1);
  a.face_normals = Eigen::MatrixX3d::Random(Eigen::Index(m.faces.size()), 3);
  const std::string p = tmp_path("extreme_blocks.ply");
  write_ply(p, m, a);
  // The same values as ASCII with 17 digits.
  std::string text =
      "ply\nformat ascii 1.0\nelement vertex 300\nproperty double x\nproperty double y\n"
      "property double z\nelement face " +
      std::to_string(m.faces.size()) + "\nproperty list uchar uint vertex_indices\nend_header\n";
  char buf[32];
  for (Eigen::Index v = 0; v < 300; ++v)
    for (int c = 0; c < 3; ++c) {
      std::snprintf(buf, sizeof buf, c == 2 ? "%.17g\n" : "%.17g ", m.positions(v, c));
      text += buf;
    }
  for (const auto f : m.faces)
    text += "4 " + std::to_string(f[0]) + " " + std::to_string(f[1]) + " " + std::to_string(f[2]) + " " +
            std::to_string(f[3]) + "\n";
  const std::string q = tmp_path("extreme_blocks_ascii.ply");
  write_text(q, text);
  for (std::size_t block : kBlocks) {
    CAPTURE(block);
    MeshAttributes b;
    const PolygonMesh back = io_detail::read_ply(p, &b, block);
    CHECK(same_bits(back.positions, m.positions));
    CHECK(back.faces == m.faces);
    CHECK(back.faces.corners().capacity() == back.faces.num_corners());  // quads: reserved exactly
    CHECK(same_bits(b.vertex_scalars.at("s"), a.vertex_scalars.at("s")));
    CHECK(same_bits(b.face_normals, a.face_normals));
    const PolygonMesh text_back = io_detail::read_ply(q, nullptr, block);
    CHECK(same_bits(text_back.positions, m.positions));
    CHECK(text_back.faces == m.faces);
    CHECK(text_back.faces.corners().capacity() == text_back.faces.num_corners());
  }
}

TEST_CASE("corner reserve: exact for one face degree, grows by the mean degree, bounded by the file") {
  FaceList quads;
  {
    io_detail::CornerReserve reserve(quads, 1000);
    for (int f = 0; f < 1000; ++f) {
      reserve.before_face(4, 1 << 20);
      quads.start_face();
      for (int k = 0; k < 4; ++k) quads.add_corner(k);
    }
  }
  CHECK(quads.corners().capacity() == 4000);  // triangles assumed would have reallocated to 6000
  FaceList mixed;
  io_detail::CornerReserve reserve(mixed, 1000);
  std::size_t reallocations = 0, capacity = 0;
  for (int f = 0; f < 1000; ++f) {
    const std::size_t n = f % 10 == 9 ? 6 : 3;  // mostly triangles, every tenth a hexagon
    reserve.before_face(n, 1 << 20);
    mixed.start_face();
    for (std::size_t k = 0; k < n; ++k) mixed.add_corner(0);
    if (mixed.corners().capacity() != capacity) ++reallocations, capacity = mixed.corners().capacity();
  }
  CHECK(mixed.num_corners() == 3300);
  CHECK(reallocations <= 3);
  CHECK(capacity <= 3300 * 17 / 16 + 8);
  // A corrupt count cannot make it reserve more than the file can hold.
  FaceList few;
  io_detail::CornerReserve bounded(few, std::size_t(1) << 31);
  bounded.before_face(200, 1000);
  CHECK(few.corners().capacity() == 1000);
}

TEST_CASE("OFF reads the same at every block size, quads and mixed faces") {
  const std::string p = tmp_path("blocks.off");
  write_text(p,
             "OFF\n# quads and a triangle\n6 4 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 1e-300\n"
             "-1.2345678901234567 2 3\n4 0 1 2 3\n4 3 2 1 0  # reversed\n3 0 1 4\n5 0 1 2 3 5 0.5 0.5 0.5\n");
  for (std::size_t block : kBlocks) {
    CAPTURE(block);
    const PolygonMesh m = io_detail::read_off(p, block);
    CHECK(m.faces == FaceList{{0, 1, 2, 3}, {3, 2, 1, 0}, {0, 1, 4}, {0, 1, 2, 3, 5}});
    CHECK(m.positions(4, 2) == 1e-300);
    CHECK(m.positions(5, 0) == -1.2345678901234567);
  }
  write_text(p, "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n4 3 2 1 0\n");
  const PolygonMesh quads = read_off(p);
  CHECK(quads.faces.num_corners() == 8);
  CHECK(quads.faces.corners().capacity() == 8);  // not 2 x 3 triangles' worth, grown to 12
  write_text(p, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n");
  const std::string expected = error_of([&] { read_off(p); });
  CHECK(expected.find("line 6: face 0: vertex index 3 out of range (3 vertices)") != std::string::npos);
  for (std::size_t block : kBlocks) CHECK(error_of([&] { io_detail::read_off(p, block); }) == expected);
}

TEST_CASE("Matrix Market: sorted, unsorted, repeated and symmetric entries at every block size") {
  const std::string p = tmp_path("blocks.mtx");
  auto expect = [&](const std::string& text, int rows, int cols, const std::vector<Eigen::Triplet<double>>& entries) {
    write_text(p, text);
    Eigen::SparseMatrix<double> want(rows, cols);
    want.setFromTriplets(entries.begin(), entries.end());  // sums repeats in file order
    for (std::size_t block : kBlocks) {
      CAPTURE(text);
      CAPTURE(block);
      const Eigen::SparseMatrix<double> got = io_detail::read_matrix_market(p, block);
      REQUIRE(got.nonZeros() == want.nonZeros());
      CHECK(got.isCompressed());
      CHECK(std::memcmp(got.outerIndexPtr(), want.outerIndexPtr(), sizeof(int) * std::size_t(cols + 1)) == 0);
      CHECK(std::memcmp(got.innerIndexPtr(), want.innerIndexPtr(), sizeof(int) * std::size_t(want.nonZeros())) == 0);
      CHECK(std::memcmp(got.valuePtr(), want.valuePtr(), sizeof(double) * std::size_t(want.nonZeros())) == 0);
    }
  };
  const std::string general = "%%MatrixMarket matrix coordinate real general\n";
  // Sorted by column then row, empty columns first, between and last.
  expect(general + "3 6 4\n1 2 0.1\n3 2 -0.2\n2 4 1e-310\n1 5 3\n", 3, 6,
         {{0, 1, 0.1}, {2, 1, -0.2}, {1, 3, 1e-310}, {0, 4, 3}});
  // Out of order from the third entry on, with a repeat summed in file order (0.1 + 0.2 + 0.3).
  expect(general + "% comment\n3 3 6\n1 1 0.1\n2 1 5\n1 1 0.2\n3 3 1\n1 3 2\n1 1 0.3\n", 3, 3,
         {{0, 0, 0.1}, {1, 0, 5}, {0, 0, 0.2}, {2, 2, 1}, {0, 2, 2}, {0, 0, 0.3}});
  // Unsorted at once (row before the previous in the same column).
  expect(general + "2 2 2\n2 1 1\n1 1 2\n", 2, 2, {{1, 0, 1}, {0, 0, 2}});
  // Symmetric: the lower triangle mirrored, the diagonal once.
  expect("%%MatrixMarket matrix coordinate real symmetric\n3 3 4\n1 1 4\n3 1 -1.5\n2 2 1\n3 2 0.25\n", 3, 3,
         {{0, 0, 4}, {2, 0, -1.5}, {0, 2, -1.5}, {1, 1, 1}, {2, 1, 0.25}, {1, 2, 0.25}});
}
