// Write-then-read round trips of every format, bit-exact, and parsing of hand-written files.
#include <doctest/doctest.h>

#include <cmath>
#include <corrlap/core/config.hpp>
#include <corrlap/core/error.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/io/text_io.hpp>
#include <corrlap/io/volume_io.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <limits>
#include <random>

#include "test_support.hpp"

using namespace corrlap;
using corrlap::test::tmp_path;
using corrlap::test::write_text;

namespace {
// A mesh with mixed face degrees and coordinates that need all 17 digits.
PolygonMesh odd_mesh() {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-3, 3);
  PolygonMesh m;
  m.positions.resize(7, 3);
  for (Eigen::Index i = 0; i < m.positions.size(); ++i) m.positions.data()[i] = u(rng) / 3.0;
  m.positions(0, 0) = 1e-300;
  m.positions(1, 1) = -123456789.123456789;
  m.faces = {{0, 1, 2}, {1, 2, 3, 4}, {2, 3, 4, 5, 6}, {6, 5, 0}};
  return m;
}

void check_same(const PolygonMesh& a, const PolygonMesh& b) {
  REQUIRE(a.positions.rows() == b.positions.rows());
  CHECK((a.positions.array() == b.positions.array()).all());
  CHECK(a.faces == b.faces);
}

Volume random_volume(Eigen::Vector3i size, unsigned seed) {
  std::mt19937 rng(seed);
  Volume v;
  v.size = size;
  v.values.resize(std::size_t(size.prod()));
  for (auto& x : v.values) x = std::uint8_t(rng() & 0xff);
  v.values[0] = 0;
  v.values[1] = 255;
  v.values[2] = '\n';  // a newline byte in the payload must not confuse header parsing
  return v;
}
}  // namespace

TEST_CASE("OBJ round trip is exact (17 significant digits)") {
  const PolygonMesh m = odd_mesh();
  const std::string p = tmp_path("rt.obj");
  write_mesh(p, m);
  check_same(read_mesh(p), m);
}

TEST_CASE("binary PLY round trip is exact, attributes included") {
  const PolygonMesh m = odd_mesh();
  MeshAttributes a;
  a.vertex_normals = Eigen::MatrixX3d::Random(7, 3);
  a.face_normals = Eigen::MatrixX3d::Random(4, 3);
  a.vertex_scalars["u"] = Eigen::VectorXd::LinSpaced(7, -1, 1) / 3.0;
  a.vertex_scalars["curvature.mean"] = Eigen::VectorXd::Random(7);
  a.face_scalars["area"] = Eigen::VectorXd::Random(4);
  const std::string p = tmp_path("rt.ply");
  write_mesh(p, m, a);
  MeshAttributes b;
  check_same(read_ply(p, &b), m);
  CHECK(b.vertex_normals == a.vertex_normals);
  CHECK(b.face_normals == a.face_normals);
  CHECK(b.vertex_scalars.size() == 2);
  CHECK(b.vertex_scalars.at("u") == a.vertex_scalars.at("u"));
  CHECK(b.vertex_scalars.at("curvature.mean") == a.vertex_scalars.at("curvature.mean"));
  CHECK(b.face_scalars.at("area") == a.face_scalars.at("area"));
  CHECK(b.face_scalars.size() == 1);
  // read_mesh dispatches .ply
  check_same(read_mesh(p), m);
}

TEST_CASE("PLY writer rejects attributes of the wrong size or with invalid names") {
  const PolygonMesh m = odd_mesh();
  const std::string p = tmp_path("bad_attr.ply");
  MeshAttributes a;
  a.vertex_scalars["u"] = Eigen::VectorXd::Zero(6);
  CHECK_THROWS_WITH_AS(write_ply(p, m, a), doctest::Contains("vertex scalar 'u' has 6 rows, expected 7"), IoError);
  MeshAttributes b;
  b.face_scalars["two words"] = Eigen::VectorXd::Zero(4);
  CHECK_THROWS_WITH_AS(write_ply(p, m, b), doctest::Contains("not a valid"), IoError);
  MeshAttributes c;
  c.face_normals = Eigen::MatrixX3d::Zero(3, 3);
  CHECK_THROWS_WITH_AS(write_ply(p, m, c), doctest::Contains("face normals has 3 rows, expected 4"), IoError);
}

TEST_CASE("PLY faces of more than 255 corners use a wide count type") {
  PolygonMesh m;
  const int n = 300;
  m.positions.resize(n, 3);
  for (int i = 0; i < n; ++i) m.positions.row(i) << std::cos(2 * M_PI * i / n), std::sin(2 * M_PI * i / n), 0;
  std::vector<int> face(n);
  for (int i = 0; i < n; ++i) face[std::size_t(i)] = i;
  m.faces.push_back(face);
  const std::string p = tmp_path("wide.ply");
  write_ply(p, m);
  check_same(read_ply(p), m);
}

TEST_CASE("ASCII PLY with other types, extra elements and vertex_index is read") {
  const std::string p = tmp_path("ascii.ply");
  write_text(p,
             "ply\r\nformat ascii 1.0\ncomment hi\nelement vertex 4\nproperty float x\nproperty float y\n"
             "property float z\nproperty uchar red\nelement face 2\nproperty list uchar uint vertex_index\n"
             "property int flags\nelement edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n"
             "0 0 0 255\n1 0 0 0\n0 1 0 1\n0.5 0.5 1 2\n3 0 1 2 7\n4 0 1 3 2 8\n0 1\n");
  MeshAttributes a;
  const PolygonMesh m = read_ply(p, &a);
  REQUIRE(m.positions.rows() == 4);
  CHECK(m.positions(3, 0) == 0.5);
  CHECK(m.positions(3, 2) == 1.0);
  CHECK(m.faces == FaceList{{0, 1, 2}, {0, 1, 3, 2}});
  CHECK(a.vertex_scalars.at("red") == Eigen::Vector4d(255, 0, 1, 2));
  CHECK(a.face_scalars.at("flags") == Eigen::Vector2d(7, 8));
}

TEST_CASE("smallest ASCII PLY without a final newline is read") {
  const std::string p = tmp_path("ascii_min.ply");
  write_text(p,
             "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
             "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2");
  CHECK(read_ply(p).faces == FaceList{{0, 1, 2}});
}

TEST_CASE("OFF files are read (comments, counts on the header line, colours ignored)") {
  const std::string p = tmp_path("tet.off");
  write_text(p,
             "OFF # a tetrahedron\n# comment\n4 4 6\n0 0 0\n1 0 0\n0 1 0\n0 0 1 0.5 0.5 0.5 1\n"
             "3 0 2 1\n3 0 1 3\n3 1 2 3 255 0 0\n3 0 3 2\n");
  const PolygonMesh m = read_mesh(p);
  CHECK(m.positions.rows() == 4);
  CHECK(m.positions(3, 2) == 1.0);
  CHECK(m.faces == FaceList{{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}});
  const std::string q = tmp_path("tet2.off");
  write_text(q, "COFF 4 1 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n");
  CHECK(read_off(q).faces.size() == 1);
}

TEST_CASE("volume round trips are exact for .vol, .longvol, .raw and .nrrd") {
  const Volume v = random_volume({5, 3, 4}, 3);
  for (const char* ext : {"vol", "longvol", "raw", "nrrd"}) {
    CAPTURE(ext);
    const std::string p = tmp_path(std::string("rt.") + ext);
    write_volume(p, v);
    VolumeReadOptions o;
    o.raw_dimensions = v.size;
    const Volume w = read_volume(p, o);
    CHECK(w.size == v.size);
    CHECK(w.values == v.values);
  }
}

TEST_CASE(".vol Version 3 (zlib): DGtal's compressed files are read, written and read back exactly") {
  const std::string dgtal = corrlap::test::reference_dir() + "/volumes/pattern_6x5x4_v3.vol";
  if (!nrrd_gzip_supported()) {
    CHECK_THROWS_WITH_AS(read_volume(dgtal), doctest::Contains("zlib"), IoError);
    return;
  }
  const Volume d = read_volume(dgtal);
  REQUIRE(d.size == Eigen::Vector3i(6, 5, 4));
  for (std::size_t i = 0; i < d.values.size(); ++i) CHECK(d.values[i] == std::uint8_t((37 * i) % 256));
  // Our writer: a Version 3 header, smaller than the raw bytes for a volume with structure, exact.
  Volume ball;
  ball.size = {40, 30, 20};
  ball.values.resize(40 * 30 * 20);
  for (int z = 0; z < 20; ++z)
    for (int y = 0; y < 30; ++y)
      for (int x = 0; x < 40; ++x)
        ball.values[std::size_t((z * 30 + y) * 40 + x)] =
            (x - 20) * (x - 20) + (y - 15) * (y - 15) + (z - 10) * (z - 10) < 81 ? 255 : 0;
  const std::string p = tmp_path("ball_v3.vol");
  VolumeWriteOptions compressed;
  compressed.compressed = true;
  write_volume(p, ball, compressed);
  const std::string text = corrlap::test::read_text(p);
  CHECK(text.find("Version: 3\n.\n") != std::string::npos);
  CHECK(text.size() < ball.values.size() / 4);
  CHECK(read_volume(p).values == ball.values);
  // Version 2 stays the default; other versions and other compressed formats are refused by name.
  write_volume(p, ball);
  CHECK(corrlap::test::read_text(p).find("Version: 2\n") != std::string::npos);
  CHECK_THROWS_WITH_AS(write_volume(tmp_path("ball.nrrd"), ball, compressed), doctest::Contains("Version 3"), IoError);
  write_text(p, "X: 2\nY: 2\nZ: 2\nVersion: 4\n.\n12345678");
  CHECK_THROWS_WITH_AS(read_volume(p), doctest::Contains("unsupported Version '4'"), IoError);
  // Corrupt or short zlib data, and more voxels than the stream holds, are named.
  const std::string header = text.substr(0, text.find("Version: 3\n.\n") + 13);
  const std::string data = text.substr(header.size());
  write_text(p, header + data.substr(0, data.size() / 2));
  CHECK_THROWS_WITH_AS(read_volume(p), doctest::Contains("truncated zlib data"), IoError);
  write_text(p, header + std::string(data.size(), 'x'));
  CHECK_THROWS_WITH_AS(read_volume(p), doctest::Contains("corrupt zlib data"), IoError);
  // 2^27 voxels announced in a 60-byte stream: refused before inflating (deflate expands <= 1032x).
  write_text(p, "X: 512\nY: 512\nZ: 512\nVersion: 3\n.\n" + data.substr(0, 60));
  CHECK_THROWS_WITH_AS(read_volume(p), doctest::Contains("deflate expands at most"), IoError);
}

TEST_CASE(".longvol: 64-bit little-endian voxels (DGtal's LongvolWriter layout), thresholded as they are") {
  // Written by hand as DGtal's LongvolWriter lays it out: header, then one 8-byte word per voxel,
  // least significant byte first. Values up to 2^40: labels beyond uint8.
  const Eigen::Vector3i size(3, 2, 2);
  std::string payload;
  std::vector<std::uint64_t> values;
  for (int i = 0; i < 12; ++i) {
    const std::uint64_t value = i % 3 == 0 ? (std::uint64_t{1} << 40) + std::uint64_t(i) : std::uint64_t(i * 20);
    values.push_back(value);
    for (int b = 0; b < 8; ++b) payload.push_back(char((value >> (8 * b)) & 0xFF));
  }
  const std::string header =
      "Center-X: 1\nCenter-Y: 1\nCenter-Z: 1\nX: 3\nY: 2\nZ: 2\nLvoxel-Size: 4\nAlpha-Color: 0\n"
      "Lvoxel-Endian: 0\nInt-Endian: 0123\nVersion: 2\n.\n";
  const std::string p = tmp_path("labels.longvol");
  write_text(p, header + payload);
  VolumeReadOptions o;
  o.h = 1.0;
  for (const double threshold : {100.0, 1000.0, 1e12}) {
    CAPTURE(threshold);
    o.inside = InsideRule::above(threshold);
    const VoxelGrid g = read_volume_as_voxels(p, o);
    int differ = 0;
    for (int i = 0; i < 12; ++i)
      differ += g.get(i % 3, (i / 3) % 2, i / 6) != (double(values[std::size_t(i)]) > threshold);
    CHECK(differ == 0);
  }
  // As uint8 bytes, values above 255 are named, not wrapped.
  CHECK_THROWS_WITH_AS(read_volume(p), doctest::Contains("uint64 value 1099511627776"), IoError);
  // A word short: truncated, named.
  write_text(p, header + payload.substr(0, payload.size() - 3));
  CHECK_THROWS_WITH_AS(read_volume_as_voxels(p, o), doctest::Contains("truncated data"), IoError);
  // Our writer: DGtal's field names, 8 bytes per voxel, Version 3 when compressed.
  const Volume v = random_volume({4, 3, 2}, 5);
  write_volume(p, v);
  const std::string text = corrlap::test::read_text(p);
  CHECK(text.find("Lvoxel-Size: 4\n") != std::string::npos);
  CHECK(text.size() - (text.find("Version: 2\n.\n") + 13) == 8 * v.values.size());
  if (nrrd_gzip_supported()) {
    VolumeWriteOptions compressed;
    compressed.compressed = true;
    write_volume(p, v, compressed);
    CHECK(corrlap::test::read_text(p).find("Version: 3\n.\n") != std::string::npos);
    CHECK(read_volume(p).values == v.values);
  }
}

TEST_CASE("NRRD: ascii encoding, aliases of uint8, comments and key/value pairs") {
  const std::string p = tmp_path("ascii.nrrd");
  write_text(p,
             "NRRD0005\n# comment\ntype: unsigned char\ndimension: 3\nsizes: 2 2 1\nspacings: 1 1 1\n"
             "endian: big\nkey:=value: with colon\nencoding: ascii\n\n0 10\n200 255\n");
  const Volume v = read_volume(p);
  CHECK(v.size == Eigen::Vector3i(2, 2, 1));
  CHECK(v.values == std::vector<std::uint8_t>{0, 10, 200, 255});
}

TEST_CASE("NRRD gzip encoding is read when built with zlib, else a clear error") {
  const Volume v = random_volume({6, 5, 4}, 11);
  const std::string raw = tmp_path("payload.bin");
  {
    std::ofstream out(raw, std::ios::binary);
    out.write(reinterpret_cast<const char*>(v.values.data()), std::streamsize(v.values.size()));
  }
  const std::string gz = tmp_path("payload.bin.gz");
  if (std::system(("gzip -c " + raw + " > " + gz).c_str()) != 0) {
    MESSAGE("gzip command not available: gzip NRRD test skipped");
    return;
  }
  const std::string p = tmp_path("gz.nrrd");
  write_text(p, "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 6 5 4\nencoding: gzip\n\n" + corrlap::test::read_text(gz));
  if (nrrd_gzip_supported()) {
    const Volume w = read_volume(p);
    CHECK(w.values == v.values);
    // Announcing more voxels than the stream holds is a truncation error.
    write_text(p,
               "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 6 5 5\nencoding: gzip\n\n" + corrlap::test::read_text(gz));
    CHECK_THROWS_WITH_AS(read_volume(p), doctest::Contains("truncated gzip data"), IoError);
    write_text(p,
               "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 6 5 3\nencoding: gzip\n\n" + corrlap::test::read_text(gz));
    CHECK_THROWS_WITH_AS(read_volume(p), doctest::Contains("more bytes than the sizes"), IoError);
  } else {
    CHECK_THROWS_WITH_AS(read_volume(p), doctest::Contains("gzip"), IoError);
  }
}

TEST_CASE("threshold turns grey levels into voxels (strictly above)") {
  Volume v;
  v.size = {3, 2, 2};
  v.values = {0, 50, 100, 150, 200, 250, 10, 20, 30, 40, 100, 101};
  const VoxelGrid g = threshold_volume(v, 100, 0.5);
  CHECK(g.count() == 4);  // 150 200 250 101; the two values equal to 100 are outside
  CHECK(g.get(0, 1, 0));  // 150
  CHECK(g.get(2, 1, 1));
  CHECK_FALSE(g.get(2, 0, 0));
  CHECK(g.h() == 0.5);
  CHECK_THROWS_AS(threshold_volume(v, 100, 0.0), InputError);
  const Volume back = voxels_to_volume(g);
  CHECK(back.size == Eigen::Vector3i(5, 4, 4));  // padded by one voxel on every side
}

TEST_CASE("normals, scalars and Matrix Market round trips are exact") {
  const Eigen::MatrixX3d n = Eigen::MatrixX3d::Random(9, 3) / 7.0;
  const std::string pn = tmp_path("rt_normals.txt");
  write_normals(pn, n);
  CHECK(read_normals(pn) == n);
  const Eigen::VectorXd s = Eigen::VectorXd::Random(5) * 1e-20;
  const std::string ps = tmp_path("rt_scalars.txt");
  write_scalars(ps, s);
  CHECK(read_scalars(ps) == s);
  Eigen::SparseMatrix<double> A(4, 6);
  A.insert(0, 0) = 1.0 / 3.0;
  A.insert(3, 5) = -2e-300;
  A.insert(2, 1) = M_PI;
  A.makeCompressed();
  const std::string pm = tmp_path("rt.mtx");
  write_matrix_market(pm, A);
  const Eigen::SparseMatrix<double> B = read_matrix_market(pm);
  CHECK(B.rows() == 4);
  CHECK(B.cols() == 6);
  CHECK(Eigen::MatrixXd(B) == Eigen::MatrixXd(A));
}

TEST_CASE("CLI digitizes every volume format with --threshold") {
  // A 6x6x6 grey ball: values decrease with the distance to the centre.
  Volume v;
  v.size = {7, 7, 7};
  v.values.resize(343);
  for (int z = 0; z < 7; ++z)
    for (int y = 0; y < 7; ++y)
      for (int x = 0; x < 7; ++x) {
        const double d = std::sqrt(double((x - 3) * (x - 3) + (y - 3) * (y - 3) + (z - 3) * (z - 3)));
        v.values[std::size_t((z * 7 + y) * 7 + x)] = std::uint8_t(std::max(0.0, 250.0 - 80.0 * d));
      }
  // threshold 100: d < 1.875 -> the centre, its 6 + 12 + 8 neighbours at d = 1, 1.41, 1.73: 27 voxels = a 3^3 cube
  int expected_vertices = -1;
  for (const char* ext : {"vol", "raw", "nrrd"}) {
    CAPTURE(ext);
    const std::string p = tmp_path(std::string("ball.") + ext), out = tmp_path(std::string("ball_") + ext + ".obj");
    write_volume(p, v);
    std::string err;
    const std::string extra = std::string(ext) == "raw" ? " --raw-dimensions 7 7 7" : "";
    REQUIRE(corrlap::test::run_cli("digitize --volume " + p + " --threshold 100" + extra + " --out " + out, nullptr,
                                   &err) == 0);
    const PolygonMesh m = read_mesh(out);
    CHECK(m.faces.size() == 54);      // 6 sides of a 3x3x3 cube, 9 surfels each
    CHECK(m.positions.rows() == 56);  // 6*16 - 12*4 + 8 pointels of the cube surface
    if (expected_vertices < 0) expected_vertices = int(m.positions.rows());
    CHECK(int(m.positions.rows()) == expected_vertices);
  }
}

TEST_CASE("writers refuse NaN and infinity and never leave a half-written file") {
  const std::string dir = corrlap::test::tmp_path("atomic_writes");
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string normals = dir + "/n.txt", scalars = dir + "/s.txt", mtx = dir + "/A.mtx", obj = dir + "/m.obj";
  // A valid file first: a failed write later must leave it exactly as it was.
  Eigen::MatrixX3d n(2, 3);
  n << 0, 0, 1, 1, 0, 0;
  corrlap::write_normals(normals, n);
  const std::string before = corrlap::test::read_text(normals);
  n(1, 2) = std::numeric_limits<double>::quiet_NaN();
  try {
    corrlap::write_normals(normals, n);
    FAIL("a NaN normal was written");
  } catch (const corrlap::IoError& e) {
    CHECK(std::string(e.what()).find("row 2 is not finite (nan)") != std::string::npos);
  }
  CHECK(corrlap::test::read_text(normals) == before);

  Eigen::VectorXd s(3);
  s << 1, std::numeric_limits<double>::infinity(), 2;
  CHECK_THROWS_WITH_AS(corrlap::write_scalars(scalars, s), doctest::Contains("row 2 is not finite (inf)"),
                       corrlap::IoError);
  CHECK_FALSE(std::filesystem::exists(scalars));

  Eigen::SparseMatrix<double> A(2, 2);
  A.insert(0, 0) = 1.0;
  A.insert(1, 1) = -std::numeric_limits<double>::infinity();
  A.makeCompressed();
  CHECK_THROWS_WITH_AS(corrlap::write_matrix_market(mtx, A), doctest::Contains("stored entry 2 is not finite (-inf)"),
                       corrlap::IoError);
  CHECK_FALSE(std::filesystem::exists(mtx));

  corrlap::PolygonMesh mesh;
  mesh.positions = Eigen::MatrixX3d::Zero(3, 3);
  mesh.positions(1, 0) = 1.0;
  mesh.positions(2, 1) = std::numeric_limits<double>::quiet_NaN();
  mesh.faces = {{0, 1, 2}};
  CHECK_THROWS_WITH_AS(corrlap::write_mesh(obj, mesh), doctest::Contains("vertex 3 is not finite"), corrlap::IoError);
  CHECK_THROWS_WITH_AS(corrlap::write_mesh(dir + "/m.ply", mesh), doctest::Contains("vertex 2 is not finite"),
                       corrlap::IoError);
  // No temporary file is left behind by any of the failures.
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    CHECK(entry.path().filename().string().find(".tmp-") == std::string::npos);

  // An unwritable destination: a named error, nothing created.
  CHECK_THROWS_WITH_AS(corrlap::write_scalars(dir + "/no/such/folder/s.txt", Eigen::VectorXd::Ones(2)),
                       doctest::Contains("cannot open for writing"), corrlap::IoError);
}

TEST_CASE("volume writers go through a temporary file: replaced whole, or untouched on failure") {
  const std::string dir = corrlap::test::tmp_path("atomic_volumes");
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  Volume small;
  small.size = Eigen::Vector3i(2, 2, 2);
  small.values.assign(8, 7);
  Volume large;
  large.size = Eigen::Vector3i(4, 3, 2);
  large.values.assign(24, 200);
  for (const std::string ext : {"vol", "raw", "nrrd"}) {
    CAPTURE(ext);
    const std::string path = dir + "/v." + ext;
    VolumeReadOptions opt;
    if (ext == "raw") opt.raw_dimensions = small.size;
    write_volume(path, small);
    const std::string before = corrlap::test::read_text(path);
    CHECK(read_volume(path, opt).values == small.values);
    // A volume whose data does not match its sizes is refused; the existing file stays as it was.
    Volume broken = large;
    broken.values.pop_back();
    CHECK_THROWS_AS(write_volume(path, broken), corrlap::IoError);
    CHECK(corrlap::test::read_text(path) == before);
    // A valid rewrite replaces it whole.
    write_volume(path, large);
    if (ext == "raw") opt.raw_dimensions = large.size;
    CHECK(read_volume(path, opt).values == large.values);
    CHECK_THROWS_WITH_AS(write_volume(dir + "/no/such/folder/v." + ext, small),
                         doctest::Contains("cannot open for writing"), corrlap::IoError);
  }
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    CHECK(entry.path().filename().string().find(".tmp-") == std::string::npos);
}

TEST_CASE("volumes are in world units by default: the longest side spans 2 (h = 2 / N), --h overrides") {
  CHECK(unit_size_grid_step(Eigen::Vector3i(6, 5, 4)) == doctest::Approx(1.0 / 3.0));
  const std::string vol = corrlap::test::reference_dir() + "/volumes/pattern_6x5x4_v3.vol";
  if (!nrrd_gzip_supported()) return;
  VolumeReadOptions o;
  o.inside = InsideRule::above(100);
  o.h = 0.0;
  const SurfelMesh unit = extract_surface(read_volume_as_voxels(vol, o));
  o.h = 1.0;
  const SurfelMesh voxels = extract_surface(read_volume_as_voxels(vol, o));
  REQUIRE(unit.num_vertices() == voxels.num_vertices());
  CHECK((unit.positions - voxels.positions / 3.0).cwiseAbs().maxCoeff() < 1e-12);
  // The CLI: no --h gives the same h = 1/3, the volume's centre at the origin (docs/io.md); its
  // output is in physical coordinates unless --output-units world.
  o.h = 0.0;
  o.centered = true;
  const SurfelMesh centered = extract_surface(read_volume_as_voxels(vol, o));
  const std::string out = corrlap::test::tmp_path("unit_volume.obj");
  REQUIRE(corrlap::test::run_cli("digitize --volume " + vol + " --threshold 100 --output-units world --out " + out) ==
          0);
  CHECK((read_mesh(out).positions - centered.positions).cwiseAbs().maxCoeff() < 1e-12);
  o.h = -1.0;
  CHECK_THROWS_AS(read_volume_as_voxels(vol, o), InputError);
}

TEST_CASE("read_volume_as_voxels streams every format into the same voxels as threshold_volume(read_volume)") {
  // 70 x 3 x 4: rows longer than one 64-bit word, values on both sides of the threshold.
  const Volume v = random_volume({70, 3, 4}, 11);
  for (const char* ext : {"vol", "longvol", "raw", "nrrd"})
    for (bool compressed : {false, true}) {
      if (compressed && ((std::string(ext) != "vol" && std::string(ext) != "longvol") || !nrrd_gzip_supported()))
        continue;
      CAPTURE(ext);
      CAPTURE(compressed);
      const std::string p = tmp_path(std::string("stream.") + ext);
      VolumeWriteOptions w;
      w.compressed = compressed;
      write_volume(p, v, w);
      VolumeReadOptions o;
      o.raw_dimensions = v.size;
      o.inside = InsideRule::above(127.5);
      o.h = 0.5;
      const VoxelGrid expected = threshold_volume(read_volume(p, o), o.inside.value, o.h);
      const VoxelGrid streamed = read_volume_as_voxels(p, o);
      REQUIRE(streamed.lower() == expected.lower());
      REQUIRE(streamed.upper() == expected.upper());
      CHECK(streamed.h() == 0.5);
      CHECK(streamed.count() == expected.count());
      int differ = 0;
      for (int z = -1; z <= v.size.z(); ++z)
        for (int y = -1; y <= v.size.y(); ++y)
          for (int x = -1; x <= v.size.x(); ++x) {
            // The readable rule: inside iff the file's value is strictly above the threshold.
            const bool in_file = x >= 0 && y >= 0 && z >= 0 && x < v.size.x() && y < v.size.y() && z < v.size.z();
            const bool inside = in_file && double(v.at(x, y, z)) > o.inside.value;
            differ += streamed.get(x, y, z) != expected.get(x, y, z);
            differ += streamed.get(x, y, z) != inside;
          }
      CHECK(differ == 0);
      // Centred: file voxel (x, y, z) is the digital point (x, y, z) - (size - 1) / 2.
      o.centered = true;
      const VoxelGrid centred = read_volume_as_voxels(p, o);
      const Eigen::Vector3i shift = volume_centering_shift(v.size);
      CHECK(shift == Eigen::Vector3i(34, 1, 1));
      CHECK(centred.lower() == expected.lower() - shift);
      CHECK(centred.count() == expected.count());
      differ = 0;
      for (int z = 0; z < v.size.z(); ++z)
        for (int y = 0; y < v.size.y(); ++y)
          for (int x = 0; x < v.size.x(); ++x)
            differ += centred.get(x - shift.x(), y - shift.y(), z - shift.z()) != expected.get(x, y, z);
      CHECK(differ == 0);
    }
  // An NRRD in ascii encoding goes through the same sink.
  const std::string ascii = tmp_path("stream_ascii.nrrd");
  write_text(ascii, "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 2 1 2\nencoding: ascii\n\n0 200\n255 3\n");
  VolumeReadOptions o;
  o.inside = InsideRule::above(100);
  const VoxelGrid g = read_volume_as_voxels(ascii, o);
  CHECK(g.count() == 2);
  CHECK(g.get(1, 0, 0));
  CHECK(g.get(0, 0, 1));
  CHECK(g.h() == 1.0);
  // Nothing above the threshold: named.
  o.inside = InsideRule::above(255);
  CHECK_THROWS_WITH_AS(read_volume_as_voxels(ascii, o), doctest::Contains("empty volume"), InputError);
}
