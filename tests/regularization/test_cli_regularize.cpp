// `corrlap regularize`: outputs with the input's vertex and face order, metrics that show the
// surface moving towards the true one, and clear errors for surfaces it cannot take.
#include <doctest/doctest.h>

#include <cmath>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/io/volume_io.hpp>
#include <corrlap/render/image.hpp>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "test_support.hpp"

using corrlap::test::run_cli;

TEST_CASE("regularize sphere1 (h = 0.1, fem, II normals): files, order kept, distance reduced") {
  const std::string dir = corrlap::test::tmp_path("regularize_sphere");
  std::string err;
  const int rc = run_cli("regularize --shape sphere1 --h 0.1 --bbox -1.5 1.5 --out " + dir, nullptr, &err);
  INFO(err);
  REQUIRE(rc == 0);
  const corrlap::PolygonMesh in = corrlap::read_mesh(dir + "/input.ply");
  corrlap::MeshAttributes attr;
  const corrlap::PolygonMesh out = corrlap::read_ply(dir + "/regularized.ply", &attr);
  REQUIRE(out.positions.rows() == in.positions.rows());
  REQUIRE(out.faces == in.faces);  // same faces, same vertex ids
  CHECK(attr.vertex_scalars.count("H") == 1);
  CHECK(attr.vertex_normals.rows() == out.positions.rows());
  CHECK(corrlap::read_mesh(dir + "/regularized.obj").positions.rows() == in.positions.rows());
  // The pictures, one view and one colour range: the staircase and the smooth surface differ.
  const corrlap::Image picture_before = corrlap::read_png(dir + "/before.png"),
                       picture_after = corrlap::read_png(dir + "/after.png");
  CHECK(picture_before.width == 800);
  CHECK(picture_after.height == 800);
  CHECK(picture_before.rgb != picture_after.rgb);
  const auto m = nlohmann::json::parse(corrlap::test::read_text(dir + "/metrics.json"));
  for (const char* key :
       {"vertices", "faces", "h", "method", "solver", "time_s", "area_before", "area_after", "energy_initial",
        "energy_final", "distance_l1_before", "distance_l1_after", "normal_angle_deg_before", "normal_angle_deg_after",
        "mean_curvature_error_before", "mean_curvature_error_after"})
    CHECK_MESSAGE(m.contains(key), key);
  for (const char* stage : {"surface_s", "normals_s", "curvature_s", "operators_s", "solve_s", "write_s", "render_s"})
    CHECK_MESSAGE(m["time_s"].contains(stage), stage);
  CHECK(m["method"] == "fem");
  CHECK(m["normals"] == "ii");
  const double before = m["distance_l1_before"], after = m["distance_l1_after"];
  MESSAGE("distance " << before << " -> " << after << ", normal angle " << m["normal_angle_deg_before"] << " -> "
                      << m["normal_angle_deg_after"] << " deg, |H - 1| " << m["mean_curvature_error_before"] << " -> "
                      << m["mean_curvature_error_after"]);
  // The staircase's pointels are ~h/4 off the sphere on average; the II normals and H are good to
  // a few percent at h = 0.1, so the result must be several times closer.
  CHECK(after < 0.3 * before);
  CHECK(m["normal_angle_deg_after"].get<double>() < 0.5 * m["normal_angle_deg_before"].get<double>());
  // The staircase's area is about 1.5 times the sphere's (docs/math.md §1.4); the regularized
  // surface's is within a few percent of 4 pi.
  CHECK(m["area_before"].get<double>() > 1.4 * 4 * M_PI);
  CHECK(std::abs(m["area_after"].get<double>() / (4 * M_PI) - 1.0) < 0.05);
  CHECK(m["energy_final"].get<double>() < m["energy_initial"].get<double>());
}

TEST_CASE("regularize --k1/--k2: principal-curvature edits reach the metrics, the shape follows") {
  // The torus (R = 6, r = 2) has k2 = 1/r on its tube everywhere; k1 = cos / (R + r cos) changes sign.
  const std::string plain = corrlap::test::tmp_path("regularize_k_plain"),
                    edited = corrlap::test::tmp_path("regularize_k_edited");
  std::string err;
  const std::string base = "regularize --shape torus --h 0.25 --normals true --no-render --out ";
  REQUIRE(run_cli(base + plain, nullptr, &err) == 0);
  REQUIRE(run_cli(base + edited + " --k1 set:0 --k2 scale:1", nullptr, &err) == 0);
  const auto a = nlohmann::json::parse(corrlap::test::read_text(plain + "/metrics.json"));
  const auto b = nlohmann::json::parse(corrlap::test::read_text(edited + "/metrics.json"));
  CHECK(a["k1_edit"] == "none");
  CHECK(b["k1_edit"] == "set:0");
  CHECK(b["k2_edit"] == "scale:1");
  CHECK(b.contains("normal_angle_change_deg"));
  CHECK(b["normal_attachment"] == 1.0);
  corrlap::MeshAttributes pa, pb;
  (void)corrlap::read_ply(plain + "/regularized.ply", &pa);
  (void)corrlap::read_ply(edited + "/regularized.ply", &pb);
  // H' = (0 + k2) / 2 = 1 / (2 r) = 0.25 all over the tube, where the plain H = (k1 + k2) / 2 runs
  // from 0.125 (inside, k1 = -1/4) to 0.3125 (outside, k1 = 1/8): the edit removes that spread.
  const Eigen::VectorXd &Ha = pa.vertex_scalars.at("H"), &Hb = pb.vertex_scalars.at("H");
  const auto spread = [](const Eigen::VectorXd& v) { return std::sqrt((v.array() - v.mean()).square().mean()); };
  MESSAGE("H: plain mean " << Ha.mean() << " spread " << spread(Ha) << "; k1 set to 0: mean " << Hb.mean() << " spread "
                           << spread(Hb));
  CHECK(Hb.mean() == doctest::Approx(0.25).epsilon(0.1));
  CHECK(spread(Hb) < 0.5 * spread(Ha));
  CHECK(run_cli(base + edited + " --k1 double:2", nullptr, &err) == 1);
  CHECK(err.find("expected scale:S, set:V or clamp:V") != std::string::npos);
  CHECK(run_cli(base + edited + " --k2 clamp:1 --baseline alignment", nullptr, &err) == 1);
  CHECK(err.find("--k2 applies to the paper's regularization") != std::string::npos);
}

TEST_CASE("regularize: bad options and surfaces are named") {
  std::string err;
  const std::string dir = corrlap::test::tmp_path("regularize_bad");
  CHECK(run_cli("regularize --shape sphere1 --h 0.2 --bbox -1.5 1.5 --method nosuch --out " + dir, nullptr, &err) == 1);
  CHECK(err.find("fem") != std::string::npos);
  CHECK(run_cli("regularize --shape sphere1 --h 0.2 --bbox -1.5 1.5 --method heat-kernel --out " + dir, nullptr,
                &err) == 1);
  CHECK(err.find("on faces") != std::string::npos);
  CHECK(run_cli("regularize --shape sphere1 --h 0.2 --bbox -1.5 1.5 --alpha0 -1 --out " + dir, nullptr, &err) != 0);
  CHECK(err.find("--alpha0: must be a number >= 0 (got -1)") != std::string::npos);
  // alpha0 = 0 is the unattached solve (paper Fig. 11), not an error.
  const std::string unattached = corrlap::test::tmp_path("regularize_alpha0_zero");
  std::filesystem::remove_all(unattached);
  REQUIRE(run_cli("regularize --shape sphere1 --h 0.2 --bbox -1.5 1.5 --alpha0 0 --no-render --out " + unattached,
                  nullptr, &err) == 0);
  CHECK(nlohmann::json::parse(corrlap::test::read_text(unattached + "/metrics.json"))["solve_scheme"] == "unattached");
  // An open surface: a flat 2 x 2 patch of quads.
  const std::string patch = corrlap::test::tmp_path("regularize_patch.obj");
  std::string obj;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) obj += "v " + std::to_string(i) + " " + std::to_string(j) + " 0\n";
  obj += "f 1 2 5 4\nf 2 3 6 5\nf 4 5 8 7\nf 5 6 9 8\n";
  corrlap::test::write_text(patch, obj);
  CHECK(run_cli("regularize --mesh " + patch + " --normals trivial --out " + dir, nullptr, &err) == 1);
  CHECK(err.find("open (8 boundary edges)") != std::string::npos);
  CHECK(run_cli("regularize --shape sphere1 --h 0.2 --bbox -1.5 1.5 --solver nosuch --out " + dir, nullptr, &err) == 1);
  CHECK(err.find("cholmod") != std::string::npos);
  // Options the chosen regularization would ignore.
  CHECK(run_cli("regularize --shape sphere1 --h 0.2 --bbox -1.5 1.5 --baseline alignment --method interpolated --out " +
                    dir,
                nullptr, &err) == 1);
  CHECK(err.find("--method and its parameters apply to the paper's regularization") != std::string::npos);
  CHECK(run_cli("regularize --shape sphere1 --h 0.2 --bbox -1.5 1.5 --clamp --out " + dir, nullptr, &err) == 1);
  CHECK(err.find("--clamp applies to --baseline alignment") != std::string::npos);
  // The empty volume.
  CHECK(run_cli("regularize --polynomial \"x^2+y^2+z^2+1\" --h 0.2 --bbox -1.5 1.5 --out " + dir, nullptr, &err) == 1);
  CHECK(err.find("empty") != std::string::npos);
}

TEST_CASE("regularize: a volume whose features are thinner than the II radius is refused, not silently wrong") {
  // A torus of tube radius 5 voxels in 48^3: in world units (h = 2/48) the paper's II radius
  // 3 h^(1/3) is about 25 voxels, so the II normals and H are meaningless on the tube.
  corrlap::Volume v;
  v.size = {48, 48, 48};
  v.values.assign(48 * 48 * 48, 0);
  for (int z = 0; z < 48; ++z)
    for (int y = 0; y < 48; ++y)
      for (int x = 0; x < 48; ++x) {
        const double rho = std::hypot(x - 23.5, y - 23.5);
        if ((rho - 14) * (rho - 14) + (z - 23.5) * (z - 23.5) < 25) v.values[std::size_t((z * 48 + y) * 48 + x)] = 255;
      }
  const std::string vol = corrlap::test::tmp_path("thin_torus.vol");
  corrlap::write_volume(vol, v);
  const std::string dir = corrlap::test::tmp_path("regularize_thin_torus");
  std::string err;
  CHECK(run_cli("regularize --volume " + vol + " --ii-radius 3 --ii-alpha 0.33 --ii-thin-parts keep --out " + dir,
                nullptr, &err) == 1);
  CHECK(err.find("exceeds 1/h") != std::string::npos);
  CHECK(err.find("ii_radius") != std::string::npos);  // the library's name (the CLI may add its flag)
  // With the default --ii-thin-parts shrink the surfels whose ball reaches across the tube get
  // smaller balls (docs/math.md §7.2): the same radius runs, and moves the surface by about a voxel.
  std::filesystem::remove_all(dir);
  REQUIRE(run_cli("regularize --volume " + vol + " --ii-radius 3 --ii-alpha 0.33 --no-render --out " + dir, nullptr,
                  &err) == 0);
  {
    const auto m = nlohmann::json::parse(corrlap::test::read_text(dir + "/metrics.json"));
    CHECK(m["displacement_max"].get<double>() < 1.5);
  }
  // The default radius for volumes, 4 voxels, is below the tube's: the surface moves by less than a voxel.
  std::filesystem::remove_all(dir);
  REQUIRE(run_cli("regularize --volume " + vol + " --no-render --out " + dir, nullptr, &err) == 0);
  CHECK(!std::filesystem::exists(dir + "/before.png"));  // --no-render
  CHECK(!std::filesystem::exists(dir + "/after.png"));
  const auto m = nlohmann::json::parse(corrlap::test::read_text(dir + "/metrics.json"));
  CHECK(!m["time_s"].contains("render_s"));
  CHECK(m["displacement_max"].get<double>() < 1.0);  // in the .vol's physical units: its voxels
}

TEST_CASE("regularize: voxels touching along an edge give two manifold sheets and the run succeeds") {
  // Two 2^3 blocks that touch along one edge only.
  corrlap::Volume v;
  v.size = {6, 6, 4};
  v.values.assign(6 * 6 * 4, 0);
  for (int z = 1; z < 3; ++z)
    for (int y = 0; y < 2; ++y)
      for (int x = 0; x < 2; ++x) {
        v.values[std::size_t((z * 6 + y) * 6 + x)] = 255;
        v.values[std::size_t((z * 6 + y + 2) * 6 + x + 2)] = 255;
      }
  const std::string vol = corrlap::test::tmp_path("edge_touching.vol");
  corrlap::write_volume(vol, v);
  std::string err;
  const std::string dir = corrlap::test::tmp_path("reg_nm");
  CHECK(run_cli("regularize --volume " + vol + " --normals trivial --no-render --out " + dir, nullptr, &err) == 0);
  const corrlap::PolygonMesh input = corrlap::read_mesh(dir + "/input.ply");
  const corrlap::PolygonMesh result = corrlap::read_mesh(dir + "/regularized.ply");
  // Two cubes of 2^3 voxels: 2 x 24 faces, and 2 x 26 vertices (the shared edge's 3 pointels split).
  CHECK(input.faces.size() == 48);
  CHECK(input.positions.rows() == 52);
  CHECK(result.positions.allFinite());
  // The flag that let such surfaces through is still accepted.
  CHECK(run_cli("regularize --volume " + vol + " --normals trivial --no-render --allow-nonmanifold --out " + dir,
                nullptr, &err) == 0);
}

namespace {
// Two balls of radius 7 voxels, 20 voxels apart, in a 40 x 20 x 20 volume.
std::string two_balls_volume() {
  corrlap::Volume v;
  v.size = {40, 20, 20};
  v.values.assign(40 * 20 * 20, 0);
  for (int z = 0; z < 20; ++z)
    for (int y = 0; y < 20; ++y)
      for (int x = 0; x < 40; ++x)
        for (const double cx : {9.5, 29.5})
          if ((x - cx) * (x - cx) + (y - 9.5) * (y - 9.5) + (z - 9.5) * (z - 9.5) <= 49.0)
            v.values[std::size_t((z * 20 + y) * 40 + x)] = 255;
  const std::string vol = corrlap::test::tmp_path("two_balls.vol");
  corrlap::write_volume(vol, v);
  return vol;
}
}  // namespace

TEST_CASE("regularize: small balls in a volume work with the default II radius, a too large one is named") {
  const std::string vol = two_balls_volume();
  const std::string dir = corrlap::test::tmp_path("reg_two_balls");
  std::string err;
  CHECK(run_cli("regularize --volume " + vol + " --threshold 127 --no-render --out " + dir, nullptr, &err) == 0);
  const corrlap::PolygonMesh out = corrlap::read_mesh(dir + "/regularized.obj");
  CHECK(out.positions.allFinite());
  // The paper's radius at this h (3 h^0.33 with the longest side spanning 2, h = 0.05) is 22.3
  // voxels, wider than a ball: the faces' II normals around some vertices cancel out. The error
  // names both sizes.
  CHECK(run_cli("regularize --volume " + vol +
                    " --threshold 127 --ii-radius 3 --ii-alpha 0.33 --ii-thin-parts keep --no-render --out " + dir,
                nullptr, &err) == 1);
  INFO(err);
  CHECK(err.find("is the zero vector") != std::string::npos);
  CHECK(err.find("the II radius, 22.") != std::string::npos);
  CHECK(err.find("voxels, exceeds the part it lies on (14 x 14 x 14 voxels") != std::string::npos);
  CHECK(err.find("--ii-radius") != std::string::npos);
  // Shrinking the balls where they reach across a ball (the default) runs with that radius too.
  std::filesystem::remove_all(dir);
  CHECK(
      run_cli("regularize --volume " + vol + " --threshold 127 --ii-radius 3 --ii-alpha 0.33 --no-render --out " + dir,
              nullptr, &err) == 0);
}

TEST_CASE("regularize: a mesh file gives the same surface in any unit (scaled by 0.1, 1 and 10)") {
  // Two unit icospheres 3 apart: the II radius is in voxels and every other default is relative to
  // the object's size, so the outputs must agree up to the scale.
  corrlap::PolygonMesh a = corrlap::test::icosphere(3), b = corrlap::test::icosphere(3, 1.0, Eigen::Vector3d(3, 0, 0));
  const Eigen::Index na = a.positions.rows();
  a.positions.conservativeResize(na + b.positions.rows(), 3);
  a.positions.bottomRows(b.positions.rows()) = b.positions;
  for (const auto f : b.faces) a.faces.push_back({f[0] + int(na), f[1] + int(na), f[2] + int(na)});
  std::vector<Eigen::MatrixX3d> results;
  for (const double scale : {0.1, 1.0, 10.0}) {
    corrlap::PolygonMesh m = a;
    m.positions *= scale;
    const std::string obj = corrlap::test::tmp_path("two_icospheres_" + std::to_string(int(scale * 10)) + ".obj");
    corrlap::write_obj(obj, m);
    const std::string dir = corrlap::test::tmp_path("reg_scaled_" + std::to_string(int(scale * 10)));
    std::string err;
    const int rc =
        run_cli("regularize --mesh-file " + obj + " --resolution 32 --no-render --out " + dir, nullptr, &err);
    INFO(err);
    REQUIRE(rc == 0);
    results.push_back(corrlap::read_mesh(dir + "/regularized.ply").positions / scale);
  }
  // Scaling by 0.1 is not exact in binary, so the solve sees inputs that differ by rounding and the
  // results need not agree bitwise (measured: 4e-15). 1e-8 (2e-9 of the 5-unit object, 7 orders below
  // its 0.16-unit voxels) leaves room for a CG solve that stops one iteration earlier or later, and
  // catches any default that depends on the units (the paper's II radius moved vertices by 0.01 to
  // whole voxels, or failed).
  REQUIRE(results[0].rows() == results[1].rows());
  REQUIRE(results[2].rows() == results[1].rows());
  const double diff01 = (results[0] - results[1]).cwiseAbs().maxCoeff(),
               diff21 = (results[2] - results[1]).cwiseAbs().maxCoeff();
  MESSAGE("largest difference to scale 1: " << diff01 << " (scale 0.1), " << diff21 << " (scale 10)");
  CHECK(diff01 < 1e-8);
  CHECK(diff21 < 1e-8);
}

TEST_CASE("regularize: a checkerboard of blocks and a checkerboard corner run with no other flag") {
  // Blocks of 4^3 voxels on the even cells of a 2x2x2 checkerboard touch along edges and at the
  // centre only: four cubes (docs/math.md §1.4). A solid block with a 2x2x2 checkerboard carved into
  // it pinches the inner surface the same way.
  corrlap::Volume board;
  board.size = {10, 10, 10};
  board.values.assign(1000, 0);
  corrlap::Volume corner;
  corner.size = {14, 14, 14};
  corner.values.assign(14 * 14 * 14, 0);
  for (int z = 0; z < 14; ++z)
    for (int y = 0; y < 14; ++y)
      for (int x = 0; x < 14; ++x) {
        if (x >= 1 && x < 9 && y >= 1 && y < 9 && z >= 1 && z < 9 && ((x - 1) / 4 + (y - 1) / 4 + (z - 1) / 4) % 2 == 0)
          board.values[std::size_t((z * 10 + y) * 10 + x)] = 255;
        const bool block = x >= 1 && x < 13 && y >= 1 && y < 13 && z >= 1 && z < 13;
        const bool carved = x >= 6 && x < 8 && y >= 6 && y < 8 && z >= 6 && z < 8 && (x + y + z) % 2 == 1;
        if (block && !carved) corner.values[std::size_t((z * 14 + y) * 14 + x)] = 255;
      }
  struct Case {
    const char* name;
    const corrlap::Volume* volume;
    int components, euler;
  };
  // The corner: the block's outer surface and the cavity's (two of the carved voxels' faces pinch).
  for (const Case& c : {Case{"checkerboard", &board, 4, 8}, Case{"checkerboard_corner", &corner, 2, 4}}) {
    CAPTURE(c.name);
    const std::string vol = corrlap::test::tmp_path(std::string(c.name) + ".vol");
    corrlap::write_volume(vol, *c.volume);
    const std::string dir = corrlap::test::tmp_path(std::string("reg_") + c.name);
    std::string err, out;
    const int rc = run_cli("regularize --volume " + vol + " --no-render --out " + dir, nullptr, &err);
    INFO(err);
    CHECK(rc == 0);
    if (rc != 0) continue;
    CHECK(corrlap::read_mesh(dir + "/regularized.ply").positions.allFinite());
    REQUIRE(run_cli("info " + dir + "/input.ply --json", &out) == 0);
    const auto info = nlohmann::json::parse(out);
    CHECK(info["boundary_edges"] == 0);
    CHECK(info["nonmanifold_edges"] == 0);
    CHECK(info["nonmanifold_vertices"] == 0);
    CHECK(info["components"] == c.components);
    CHECK(info["euler"] == c.euler);
  }
}
