// A gallery of volumes a user would bring (docs/io.md, docs/regularization.md): `corrlap regularize
// --volume F --out D` with no other flag must succeed on each, write finite positions, and write
// them in the volume's physical coordinates (voxel indices for a .vol file, which has no geometry).
// Also the volume flags shared by every command: --label, --labels all, --threshold.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/io/volume_io.hpp>
#include <corrlap/render/view_page.hpp>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>

#include "test_support.hpp"

#ifdef CORRLAP_CLI

namespace {

namespace fs = std::filesystem;
using corrlap::test::run_cli;
using corrlap::test::tmp_path;

using Inside = std::function<bool(int, int, int)>;

corrlap::Volume make_volume(const Eigen::Vector3i& size, const Inside& inside, std::uint8_t value = 1) {
  corrlap::Volume v;
  v.size = size;
  v.values.assign(std::size_t(size.prod()), 0);
  for (int z = 0; z < size.z(); ++z)
    for (int y = 0; y < size.y(); ++y)
      for (int x = 0; x < size.x(); ++x)
        if (inside(x, y, z))
          v.values[(std::size_t(z) * std::size_t(size.y()) + std::size_t(y)) * std::size_t(size.x()) + std::size_t(x)] =
              value;
  return v;
}

// The box of the inside voxels' pointels, in voxel indices: [min - 1/2, max + 1/2].
std::pair<Eigen::RowVector3d, Eigen::RowVector3d> labelled_box(const corrlap::Volume& v) {
  Eigen::RowVector3d lo = Eigen::RowVector3d::Constant(1e300), hi = -lo;
  for (int z = 0; z < v.size.z(); ++z)
    for (int y = 0; y < v.size.y(); ++y)
      for (int x = 0; x < v.size.x(); ++x)
        if (v.at(x, y, z)) {
          lo = lo.cwiseMin(Eigen::RowVector3d(x, y, z));
          hi = hi.cwiseMax(Eigen::RowVector3d(x, y, z));
        }
  return {lo.array() - 0.5, hi.array() + 0.5};
}

// regularize with no flag but --volume and --out: exit 0, finite positions, in voxel indices
// (the .vol file's physical coordinates) near the labelled box.
void check_gallery(const std::string& name, const corrlap::Volume& volume) {
  const std::string dir = tmp_path("gallery_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string file = dir + "/" + name + ".vol";
  corrlap::write_volume(file, volume);
  std::string out, err;
  const int rc = run_cli("regularize --volume " + file + " --out " + dir + "/out", &out, &err);
  INFO(name << ": " << err);
  REQUIRE(rc == 0);
  const corrlap::PolygonMesh m = corrlap::read_mesh(dir + "/out/regularized.obj");
  REQUIRE(m.positions.rows() > 0);
  CHECK(m.positions.allFinite());
  // Not a structured binding: INFO captures lo and hi, which clang-14 refuses for bindings.
  const auto box = labelled_box(volume);
  const Eigen::RowVector3d lo = box.first, hi = box.second;
  const Eigen::RowVector3d min = m.positions.colwise().minCoeff(), max = m.positions.colwise().maxCoeff();
  INFO("output box " << min << " .. " << max << ", labelled box " << lo << " .. " << hi);
  // Within 2 voxels: the regularization rounds sharp corners (the tip of a 2-voxel plate recedes
  // by up to 1.6 voxels), while output in another unit (world, or a missing origin) would be off by
  // far more.
  CHECK(((min - lo).cwiseAbs().maxCoeff()) <= 2.0);
  CHECK(((max - hi).cwiseAbs().maxCoeff()) <= 2.0);
  std::ifstream metrics(dir + "/out/metrics.json");
  const nlohmann::json j = nlohmann::json::parse(metrics);
  CHECK(j["output_units"] == "physical");
  MESSAGE(name << ": " << j["vertices"] << " vertices, " << j["components"] << " components, time "
               << j["time_s"].dump());
}

}  // namespace

TEST_CASE("gallery: an L-bracket with a plate two voxels thin regularizes with the defaults") {
  check_gallery("l_bracket", make_volume({48, 40, 40}, [](int x, int y, int z) {
                  const bool plate = x >= 4 && x < 44 && y >= 4 && y < 36 && z >= 4 && z < 6;
                  const bool wall = x >= 4 && x < 10 && y >= 4 && y < 36 && z >= 4 && z < 36;
                  return plate || wall;
                }));
}

TEST_CASE("gallery: a CAD-like block with a drilled hole regularizes with the defaults") {
  check_gallery("drilled_block", make_volume({40, 40, 32}, [](int x, int y, int z) {
                  const double dx = x - 19.5, dy = y - 19.5;
                  return x >= 4 && x < 36 && y >= 4 && y < 36 && z >= 4 && z < 28 && dx * dx + dy * dy > 36.0;
                }));
}

TEST_CASE("gallery: two components are both kept and reported") {
  const corrlap::Volume v = make_volume({48, 32, 32}, [](int x, int y, int z) {
    const auto ball = [&](double cx) {
      return (x - cx) * (x - cx) + (y - 15.5) * (y - 15.5) + (z - 15.5) * (z - 15.5);
    };
    return ball(12.0) <= 64.0 || ball(35.0) <= 64.0;
  });
  check_gallery("two_components", v);
  std::ifstream metrics(tmp_path("gallery_two_components") + "/out/metrics.json");
  CHECK(nlohmann::json::parse(metrics)["components"] == 2);
}

TEST_CASE("gallery: a torus (a hole through the shape) regularizes with the defaults") {
  check_gallery("torus", make_volume({44, 44, 20}, [](int x, int y, int z) {
                  const double q = std::hypot(x - 21.5, y - 21.5) - 13.0, dz = z - 9.5;
                  return q * q + dz * dz <= 25.0;
                }));
}

TEST_CASE("gallery: a checkerboard corner (non-manifold edges and vertices) regularizes with the defaults") {
  const corrlap::Volume v = make_volume({28, 28, 28}, [](int x, int y, int z) {
    if (x < 4 || y < 4 || z < 4 || x >= 24 || y >= 24 || z >= 24) return false;
    return ((x - 4) / 10 + (y - 4) / 10 + (z - 4) / 10) % 2 == 0;
  });
  check_gallery("checkerboard", v);
  // Four blocks touching along edges: four closed sheets (docs/math.md §1.4), each with the II
  // normals of a block alone (§7.1). The regularized surface stays on the staircase: every vertex
  // within 1.5 voxels of the input surface (the regularization rounds the blocks' edges and corners,
  // by less than that), and no face turns over.
  const std::string dir = tmp_path("gallery_checkerboard") + "/out";
  std::ifstream metrics(dir + "/metrics.json");
  CHECK(nlohmann::json::parse(metrics)["components"] == 4);
  const corrlap::PolygonMesh in = corrlap::read_mesh(dir + "/input.ply");
  const corrlap::PolygonMesh out = corrlap::read_mesh(dir + "/regularized.obj");
  REQUIRE(in.positions.rows() == out.positions.rows());
  REQUIRE(in.faces.size() == out.faces.size());
  // Distance to the staircase: the input is the union of axis-aligned unit squares, so the distance
  // from a point to it is the least distance to a face's square.
  double farthest = 0.0;
  for (Eigen::Index i = 0; i < out.positions.rows(); ++i) {
    const Eigen::RowVector3d p = out.positions.row(i);
    double best = 1e300;
    for (const auto& f : in.faces) {
      Eigen::RowVector3d lo = in.positions.row(f[0]), hi = lo;
      for (const int v : f) lo = lo.cwiseMin(in.positions.row(v)), hi = hi.cwiseMax(in.positions.row(v));
      best = std::min(best, (p - p.cwiseMax(lo).cwiseMin(hi)).norm());
    }
    farthest = std::max(farthest, best);
  }
  MESSAGE("checkerboard: farthest regularized vertex " << farthest << " voxels from the staircase");
  CHECK(farthest <= 1.5);
  // No face turned over: each output face's normal (Newell) agrees with its input face's.
  const auto newell = [](const corrlap::PolygonMesh& m, const auto& f) {
    Eigen::RowVector3d n = Eigen::RowVector3d::Zero();
    for (std::size_t j = 0; j < f.size(); ++j) {
      const Eigen::RowVector3d a = m.positions.row(f[j]), b = m.positions.row(f[(j + 1) % f.size()]);
      n += a.cross(b);
    }
    return n;
  };
  int flipped = 0;
  double least = 1.0;
  for (std::size_t k = 0; k < in.faces.size(); ++k) {
    const Eigen::RowVector3d a = newell(in, in.faces[k]).normalized(), b = newell(out, out.faces[k]).normalized();
    flipped += a.dot(b) <= 0.0;
    least = std::min(least, a.dot(b));
  }
  MESSAGE("checkerboard: least cosine between an input face's normal and its output face's " << least);
  CHECK(flipped == 0);
}

TEST_CASE("gallery: a scan-like ellipsoid of 1 x 1 x 2.5 mm voxels comes out in millimetres") {
  const std::string dir = tmp_path("gallery_ellipsoid");
  fs::remove_all(dir);
  fs::create_directories(dir);
  corrlap::VolumeData data;
  data.size = {40, 32, 12};
  data.type = corrlap::VoxelValueType::UInt8;
  data.geometry.spacing = {1.0, 1.0, 2.5};
  data.geometry.origin = {-19.5, -15.5, -13.75};
  data.bytes.assign(std::size_t(data.size.prod()), 0);
  for (int k = 0; k < 12; ++k)
    for (int j = 0; j < 32; ++j)
      for (int i = 0; i < 40; ++i) {
        const Eigen::Vector3d p = data.geometry.to_physical(Eigen::Vector3d(i, j, k));
        if (std::pow(p.x() / 16.0, 2) + std::pow(p.y() / 12.0, 2) + std::pow(p.z() / 10.0, 2) <= 1.0)
          data.bytes[std::size_t((k * 32 + j) * 40 + i)] = 1;
      }
  corrlap::write_volume_data(dir + "/scan.nrrd", data);
  std::string err;
  REQUIRE(run_cli("regularize --volume " + dir + "/scan.nrrd --out " + dir + "/out", nullptr, &err) == 0);
  const corrlap::PolygonMesh m = corrlap::read_mesh(dir + "/out/regularized.obj");
  CHECK(m.positions.allFinite());
  // Millimetres, centred on the ellipsoid: within a voxel of its semi-axes.
  const Eigen::RowVector3d max = m.positions.colwise().maxCoeff(), min = m.positions.colwise().minCoeff();
  CHECK(max.x() == doctest::Approx(16.0).epsilon(0.1));
  CHECK(min.z() == doctest::Approx(-10.0).epsilon(0.25));
}

TEST_CASE("volume flags: --label, --labels all writes one folder per label, --threshold excludes them") {
  const std::string dir = tmp_path("cli_volume_labels");
  fs::remove_all(dir);
  fs::create_directories(dir);
  // Two boxes labelled 3 and 7.
  corrlap::Volume v = make_volume(
      {24, 14, 14}, [](int x, int y, int z) { return x >= 2 && x < 10 && y >= 3 && y < 11 && z >= 3 && z < 11; }, 3);
  for (int z = 3; z < 11; ++z)
    for (int y = 3; y < 11; ++y)
      for (int x = 13; x < 21; ++x) v.values[std::size_t((z * 14 + y) * 24 + x)] = 7;
  const std::string file = dir + "/seg.vol";
  corrlap::write_volume(file, v);
  std::string err;
  REQUIRE(run_cli("regularize --volume " + file + " --labels all --no-render --out " + dir + "/all", nullptr, &err) ==
          0);
  CHECK(fs::exists(dir + "/all/label-3/regularized.obj"));
  CHECK(fs::exists(dir + "/all/label-7/regularized.obj"));
  CHECK(fs::exists(dir + "/all/labels.json"));
  // One page per label, and every label on one page (the build has a viewer).
  CHECK(fs::exists(dir + "/all/label-3/view.html") == corrlap::has_viewer());
  if (corrlap::has_viewer()) {
    const std::string page = corrlap::test::read_text(dir + "/all/view.html");
    CHECK(page.find("\"name\":\"label-3\"") != std::string::npos);
    CHECK(page.find("\"name\":\"label-7\"") != std::string::npos);
    CHECK(page.find("\"layout\":\"overlay\"") != std::string::npos);
  }
  // Label 7 alone: its box in voxel indices (physical for a .vol), x in [12.5, 20.5].
  const corrlap::PolygonMesh seven = corrlap::read_mesh(dir + "/all/label-7/input.ply");
  CHECK(seven.positions.col(0).minCoeff() == doctest::Approx(12.5));
  CHECK(seven.positions.col(0).maxCoeff() == doctest::Approx(20.5));
  REQUIRE(run_cli("digitize --volume " + file + " --label 3 --out " + dir + "/three.obj", nullptr, &err) == 0);
  const corrlap::PolygonMesh three = corrlap::read_mesh(dir + "/three.obj");
  CHECK(three.positions.col(0).maxCoeff() == doctest::Approx(9.5));
  // --output-units world: the computation's centred coordinates, the longest side spanning 2.
  REQUIRE(run_cli("digitize --volume " + file + " --out " + dir + "/world.obj --output-units world", nullptr, &err) ==
          0);
  const corrlap::PolygonMesh world = corrlap::read_mesh(dir + "/world.obj");
  CHECK(world.positions.col(0).maxCoeff() < 1.0);
  CHECK(world.positions.col(0).minCoeff() > -1.0);
  CHECK(run_cli("digitize --volume " + file + " --label 3 --threshold 1 --out " + dir + "/x.obj", nullptr, &err) != 0);
  CHECK(err.find("excludes") != std::string::npos);
  CHECK(run_cli("digitize --volume " + file + " --label 4 --out " + dir + "/x.obj", nullptr, &err) == 1);
  CHECK(err.find("no voxel equal to the label 4") != std::string::npos);
  CHECK(run_cli("digitize --volume " + file + " --labels all --out " + dir + "/x.obj", nullptr, &err) == 1);
  CHECK(err.find("--labels all") != std::string::npos);
  CHECK(run_cli("digitize --shape sphere1 --label 3 --out " + dir + "/x.obj", nullptr, &err) == 1);
  CHECK(err.find("--label applies to --volume only") != std::string::npos);
}

TEST_CASE("--labels all: a label that cannot be regularized is reported, the others are written") {
  const std::string dir = tmp_path("cli_volume_labels_failure");
  fs::remove_all(dir);
  fs::create_directories(dir);
  // A box labelled 3 and a single voxel labelled 5: a speck whose mean curvature exceeds 1/h.
  corrlap::Volume v = make_volume(
      {24, 14, 14}, [](int x, int y, int z) { return x >= 2 && x < 10 && y >= 3 && y < 11 && z >= 3 && z < 11; }, 3);
  v.values[std::size_t((7 * 14 + 7) * 24 + 17)] = 5;
  const std::string file = dir + "/seg.vol";
  corrlap::write_volume(file, v);
  std::string err;
  CHECK(run_cli("regularize --volume " + file + " --labels all --no-render --out " + dir + "/all", nullptr, &err) == 1);
  CHECK(err.find("label 5 not written") != std::string::npos);
  CHECK(err.find("1 of 2 labels could not be regularized (5;") != std::string::npos);
  CHECK(fs::exists(dir + "/all/label-3/regularized.obj"));
  CHECK(!fs::exists(dir + "/all/label-5"));
  const auto index = nlohmann::json::parse(corrlap::test::read_text(dir + "/all/labels.json"));
  REQUIRE(index.size() == 2);
  CHECK(index[0]["folder"] == "label-3");
  CHECK(index[1]["label"] == 5.0);
  CHECK(index[1]["error"].get<std::string>().find("too small for a surface to be regularized") != std::string::npos);
  // Every label failing writes nothing.
  CHECK(run_cli("regularize --volume " + file + " --labels all --alpha0 1e300 --no-render --out " + dir + "/none",
                nullptr, &err) == 1);
  CHECK(!fs::exists(dir + "/none"));
}

#endif
