// The regularization study (studies/regularization_study.hpp, `corrlap study regularization`; paper
// Fig. 15): rows per (shape, h, method), the surfaces get closer with h, the CSV round trip, and
// bad options named.
#include <doctest/doctest.h>

#include <corrlap/core/error.hpp>
#include <corrlap/studies/regularization_study.hpp>
#include <filesystem>

#include "test_support.hpp"

using namespace corrlap;

TEST_CASE("regularization study on sphere1: distances fall with h, corrected beats the staircase, CSV round trip") {
  RegularizationStudyOptions o;
  o.shapes = {"sphere1"};
  o.h = {0.2, 0.1};
  o.methods = {"fem", "polydec", "alignment"};
  o.min_aabb = -1.5;
  o.max_aabb = 1.5;
  std::vector<RegularizationStudyRow> rows;
  int progress_calls = 0;
  run_regularization_study(
      o, [&](const RegularizationStudyRow& r) { rows.push_back(r); },
      [&](const RegularizationStudyProgress& p) {
        ++progress_calls;
        CHECK(p.total == 6);
      });
  REQUIRE(rows.size() == 6);
  CHECK(progress_calls == 6);
  for (const auto& r : rows) {
    CAPTURE(r.method);
    CAPTURE(r.h);
    MESSAGE(r.method << " h = " << r.h << ": distance " << r.distance_before << " -> " << r.distance_after << ", |dH| "
                     << r.curvature_error_before << " -> " << r.curvature_error_after << ", area " << r.area_after);
    CHECK(r.shape == "sphere1");
    CHECK(r.normals == "ii");
    CHECK(r.resolution == 0);
    // Every method moves the staircase towards the sphere (docs/regularization.md: 3-25x for the
    // Laplacian ones; the baseline less).
    CHECK(r.distance_after < r.distance_before);
    CHECK(r.area_after < r.area_before);  // the staircase's area is ~1.5 times the sphere's
  }
  // fem at h = 0.2 then 0.1: closer as h decreases, and closer than the staircase by > 3x.
  CHECK(rows[3].distance_after < rows[0].distance_after);
  CHECK(rows[3].distance_after < rows[3].distance_before / 3);
  // Round trip through the CSV.
  const std::string path = test::tmp_path("regularization_study.csv");
  write_regularization_csv(path, rows);
  const auto back = read_regularization_csv(path);
  REQUIRE(back.size() == rows.size());
  CHECK(back[4].method == "polydec");
  CHECK(back[4].distance_after == rows[4].distance_after);
  CHECK(back[5].area_after == rows[5].area_after);

  // By resolution: h = (longest side) / N, within two coarse voxels of 2 / N for the unit sphere.
  o.h.clear();
  o.resolutions = {16};
  o.methods = {"fem"};
  rows.clear();
  run_regularization_study(o, [&](const RegularizationStudyRow& r) { rows.push_back(r); });
  REQUIRE(rows.size() == 1);
  CHECK(rows[0].resolution == 16);
  CHECK(rows[0].h == doctest::Approx(2.0 / 16).epsilon(0.1));
}

TEST_CASE("regularization study: bad options are named") {
  RegularizationStudyOptions o;
  o.shapes = {"blob"};
  CHECK_THROWS_AS(o.validate(), InputError);
  o.shapes = {"sphere1"};
  o.methods = {"fem", "nosuch"};
  CHECK_THROWS_WITH_AS(o.validate(), doctest::Contains("nosuch"), InputError);
  o.methods = {"fem"};
  o.resolutions = {4};
  CHECK_THROWS_WITH_AS(o.validate(), doctest::Contains("outside [8, 2048]"), InputError);
  o.resolutions = {16};
  o.normals = "mesh";
  CHECK_THROWS_WITH_AS(o.validate(), doctest::Contains("expected ii or true"), InputError);
  o.normals = "ii";
  o.min_aabb = 20;
  o.max_aabb = 30;  // the sphere is not in the box
  CHECK_THROWS_WITH_AS(run_regularization_study(o, {}), doctest::Contains("no voxel inside the box"), InputError);
  // A method on faces (the heat kernel) fails its unit, naming shape, h and method.
  RegularizationStudyOptions f;
  f.shapes = {"sphere1"};
  f.h = {0.2};
  f.methods = {"heat-kernel"};
  f.min_aabb = -1.5;
  f.max_aabb = 1.5;
  CHECK_THROWS_WITH_AS(run_regularization_study(f, {}), doctest::Contains("sphere1 at h = 0.2, heat-kernel"),
                       InputError);
}

TEST_CASE("corrlap study regularization: the table, the figures' data, errors") {
  const std::string dir = test::tmp_path("study_regularization_cli");
  std::filesystem::remove_all(dir);
  std::string out, err;
  const std::string args =
      "study regularization --shapes sphere1 --h 0.2 --methods fem,alignment --bbox -1.5 1.5 --no-plots --out " + dir;
  REQUIRE(test::run_cli(args, &out, &err) == 0);
  const auto rows = read_regularization_csv(dir + "/regularization.csv");
  CHECK(rows.size() == 2);
  CHECK(out.find("sphere1 h=0.2 fem: distance") != std::string::npos);
  CHECK(test::run_cli(args, &out, &err) == 1);  // the folder holds a study
  CHECK(err.find("--overwrite") != std::string::npos);
  CHECK(test::run_cli(args + " --overwrite --resolutions 16", &out, &err) == 1);
  CHECK(err.find("--h or --resolutions, not both") != std::string::npos);
  CHECK(test::run_cli("study regularization --shapes nosuch --out " + dir + "_bad", &out, &err) == 1);
}
