// `corrlap digitize` and `corrlap info` end to end.
#include <doctest/doctest.h>

#include <corrlap/io/mesh_io.hpp>
#include <nlohmann/json.hpp>

#include "test_support.hpp"

using corrlap::test::run_cli;
using corrlap::test::tmp_path;

TEST_CASE("digitize torus then info --json reports the genus-1 counts") {
  const std::string obj = tmp_path("cli_torus.obj");
  std::string out, err;
  REQUIRE(run_cli("digitize --shape torus --h 0.5 --out " + obj, &out, &err) == 0);
  REQUIRE(run_cli("info --json " + obj, &out, &err) == 0);
  const auto j = nlohmann::json::parse(out);
  CHECK(j["vertices"] == 2584);  // docs/math.md §12.1
  CHECK(j["faces"] == 2584);
  CHECK(j["edges"] == 5168);
  CHECK(j["euler"] == 0);
  CHECK(j["components"] == 1);
  CHECK(j["boundary_edges"] == 0);
  CHECK(j["nonmanifold_edges"] == 0);
  CHECK(j["nonmanifold_vertices"] == 0);
  CHECK(j["area"].get<double>() == doctest::Approx(2584 * 0.25).epsilon(1e-12));
  REQUIRE(run_cli("info " + obj, &out, &err) == 0);
  CHECK(out.find("genus                 1") != std::string::npos);
}

TEST_CASE("digitize writes true normals to text files and into PLY") {
  const std::string ply = tmp_path("cli_sphere.ply"), fn = tmp_path("cli_fn.txt");
  std::string out, err;
  REQUIRE(run_cli("digitize --shape sphere1 --h 0.25 --out " + ply + " --face-normals " + fn, &out, &err) == 0);
  corrlap::MeshAttributes attributes;
  const corrlap::PolygonMesh mesh = corrlap::read_ply(ply, &attributes);
  REQUIRE(mesh.faces.size() == 294);
  REQUIRE(attributes.face_normals.rows() == 294);
  REQUIRE(attributes.vertex_normals.rows() == 296);
  // True normals of the unit sphere are radial at the face centroids (docs/math.md §1.5).
  double worst = 0;
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int v : mesh.faces[f]) c += mesh.positions.row(v).transpose();
    worst = std::max(worst, (c.normalized() - attributes.face_normals.row(Eigen::Index(f)).transpose()).norm());
  }
  CHECK(worst < 1e-12);
}

TEST_CASE("digitize and info reject bad input with a message and exit code 1") {
  std::string err;
  CHECK(run_cli("digitize --shape nosuchshape --out " + tmp_path("x.obj"), nullptr, &err) == 1);
  CHECK(err.find("known shapes") != std::string::npos);
  CHECK(run_cli("digitize --polynomial \"x^2+\" --out " + tmp_path("x.obj"), nullptr, &err) == 1);
  CHECK(err.find("position") != std::string::npos);
  CHECK(run_cli("digitize --shape sphere1 --h 0.5 --bbox 3 4 --offset 0 --out " + tmp_path("x.obj"), nullptr, &err) ==
        1);
  CHECK(err.find("no surfel") != std::string::npos);
  CHECK(run_cli("info /nonexistent/mesh.obj", nullptr, &err) == 1);
  CHECK(err.find("/nonexistent/mesh.obj") != std::string::npos);
  CHECK(run_cli("digitize --volume /nonexistent.vol --out " + tmp_path("x.obj"), nullptr, &err) == 1);
  CHECK(err.find("cannot open") != std::string::npos);
}
