// The internal text writer and line reader behind every text format: the writer's doubles are
// printf("%.17g")'s, byte for byte; lines split across the reader's blocks read whole; round trips
// through OBJ, normals, scalars and Matrix Market are exact for extreme values.
#include <doctest/doctest.h>

#include <Eigen/Sparse>
#include <bit>
#include <cmath>
#include <corrlap/io/detail/line_reader.hpp>
#include <corrlap/io/detail/text_writer.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/io/text_io.hpp>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "../test_support.hpp"

using namespace corrlap;
using corrlap::test::tmp_path;
using corrlap::test::write_text;

namespace {
std::string read_all(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Doubles of every kind: random bit patterns (all exponents, subnormals), integers, ±0, limits.
std::vector<double> extreme_doubles(std::size_t random_count) {
  std::vector<double> v = {0.0,
                           -0.0,
                           1.0,
                           -1.0,
                           0.1,
                           1e16,
                           1e17,
                           123456789012345678.0,
                           9007199254740993.0,
                           1e-5,
                           1e-4,
                           0.0001234,
                           std::numeric_limits<double>::max(),
                           -std::numeric_limits<double>::max(),
                           std::numeric_limits<double>::min(),
                           std::numeric_limits<double>::denorm_min(),
                           -std::numeric_limits<double>::denorm_min(),
                           std::numeric_limits<double>::epsilon(),
                           5e-324,
                           2.2250738585072009e-308};
  std::mt19937_64 rng(17);
  while (v.size() < random_count) {
    const double d = std::bit_cast<double>(rng());
    if (std::isfinite(d)) v.push_back(d);
    v.push_back(double(std::int64_t(rng()) >> (rng() % 64)));                     // integers of every size
    const double e = std::ldexp(double(rng() % 1000), int(rng() % 2100) - 1075);  // huge and tiny exponents
    if (std::isfinite(e)) v.push_back(e);
  }
  return v;
}
}  // namespace

TEST_CASE("TextWriter prints doubles exactly as printf(\"%.17g\") and integers as printf(\"%lld\")") {
  const std::vector<double> values = extreme_doubles(200000);
  const std::string path = tmp_path("writer_equivalence.txt");
  std::string expected;
  {
    io_detail::TextWriter out(path, "test", false, 100);  // tiny buffer: many flushes
    char buf[64];
    for (double d : values) {
      out.write_double(d);
      out.write('\n');
      std::snprintf(buf, sizeof buf, "%.17g\n", d);
      expected += buf;
    }
    for (long long i :
         {0LL, -1LL, 42LL, std::numeric_limits<long long>::min(), std::numeric_limits<long long>::max()}) {
      out.write_int(i);
      out.write(' ');
      std::snprintf(buf, sizeof buf, "%lld ", i);
      expected += buf;
    }
    out.write(std::string(300, 'x'));  // longer than the buffer
    expected += std::string(300, 'x');
    out.commit();
  }
  const std::string written = read_all(path);
  REQUIRE(written.size() == expected.size());
  CHECK(written == expected);
}

TEST_CASE("LineReader: lines split across blocks, CRLF, no final newline, long lines, rewind") {
  const std::string text = std::string("first line\r\n\nv 1 2 3\n") + std::string(50, 'a') + "\nlast";
  const std::string path = tmp_path("line_reader.txt");
  write_text(path, text);
  for (std::size_t block : {1, 2, 7, 13, 64, 1 << 20}) {
    io_detail::LineReader in(path, block);
    REQUIRE(in.is_open());
    CHECK(in.file_size() == text.size());
    for (int pass = 0; pass < 2; ++pass) {
      std::vector<std::string> lines;
      std::string_view line;
      while (in.next(line)) lines.emplace_back(line);
      CHECK(!in.error());
      REQUIRE(lines.size() == 5);
      CHECK(lines[0] == "first line\r");
      CHECK(io_detail::without_cr(lines[0]) == "first line");
      CHECK(lines[1].empty());
      CHECK(lines[2] == "v 1 2 3");
      CHECK(lines[3] == std::string(50, 'a'));
      CHECK(lines[4] == "last");
      CHECK(in.line_number() == 5);
      in.rewind();
    }
  }
  write_text(path, "");
  io_detail::LineReader empty(path, 7);
  std::string_view line;
  CHECK(!empty.next(line));
  CHECK(!io_detail::LineReader(tmp_path("no_such_file.txt")).is_open());
}

TEST_CASE("exact round trips of extreme values: OBJ, normals, scalars, Matrix Market") {
  const std::vector<double> values = extreme_doubles(30000);
  const Eigen::Index n = Eigen::Index(values.size() / 3);
  Eigen::MatrixX3d xyz(n, 3);
  for (Eigen::Index i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) xyz(i, c) = values[std::size_t(3 * i + c)];
  auto same_bits = [](const auto& a, const auto& b) {
    return a.rows() == b.rows() && a.cols() == b.cols() &&
           std::memcmp(a.data(), b.data(), sizeof(double) * std::size_t(a.size())) == 0;
  };

  PolygonMesh mesh;
  mesh.positions = xyz;
  for (int f = 0; f + 4 < int(n); f += 3) mesh.faces.push_back({f, f + 1, f + 2, f + 3 + f % 2});
  const std::string obj = tmp_path("extreme.obj");
  write_obj(obj, mesh);
  const PolygonMesh back = read_obj(obj);
  CHECK(same_bits(back.positions, mesh.positions));
  CHECK(back.faces == mesh.faces);

  const std::string nf = tmp_path("extreme_normals.txt");
  write_normals(nf, xyz);
  CHECK(same_bits(read_normals(nf), xyz));

  const Eigen::VectorXd s = Eigen::Map<const Eigen::VectorXd>(values.data(), Eigen::Index(values.size()));
  const std::string sf = tmp_path("extreme_scalars.txt");
  write_scalars(sf, s);
  CHECK(same_bits(read_scalars(sf), s));

  std::vector<Eigen::Triplet<double>> t;
  for (std::size_t k = 0; k < values.size(); ++k) t.emplace_back(int(k * 7919 % 997), int(k % 1009), values[k]);
  Eigen::SparseMatrix<double> A(997, 1009);
  A.setFromTriplets(t.begin(), t.end());
  A.makeCompressed();
  const std::string mf = tmp_path("extreme.mtx");
  write_matrix_market(mf, A);
  const Eigen::SparseMatrix<double> B = read_matrix_market(mf);
  REQUIRE(B.nonZeros() == A.nonZeros());
  CHECK(std::memcmp(A.outerIndexPtr(), B.outerIndexPtr(), sizeof(int) * 1010) == 0);
  CHECK(std::memcmp(A.innerIndexPtr(), B.innerIndexPtr(), sizeof(int) * std::size_t(A.nonZeros())) == 0);
  CHECK(std::memcmp(A.valuePtr(), B.valuePtr(), sizeof(double) * std::size_t(A.nonZeros())) == 0);
}

TEST_CASE("Matrix Market: unsorted entries, repeats and explicit zeros read as setFromTriplets builds them") {
  const std::string p = tmp_path("unsorted.mtx");
  write_text(p, "%%MatrixMarket matrix coordinate real general\n3 3 5\n3 3 1.5\n1 1 2\n3 3 0.5\n2 1 0\n1 3 -1\n");
  const Eigen::SparseMatrix<double> A = read_matrix_market(p);
  CHECK(A.nonZeros() == 4);  // the repeat summed, the zero kept
  CHECK(A.coeff(2, 2) == 2.0);
  CHECK(A.coeff(0, 0) == 2.0);
  CHECK(A.coeff(0, 2) == -1.0);
  write_text(p, "%%MatrixMarket matrix coordinate real general\n2 2 2\n1 1 1\n2 2 1\n");
  CHECK(read_matrix_market(p).isApprox(Eigen::MatrixXd::Identity(2, 2).sparseView()));
}
