// The regularization study (studies/regularization_study.hpp, `corrlap study regularization`; paper
// Fig. 15): rows per (shape, h, method), the surfaces get closer with h, the CSV round trip, and
// bad options named.
#include <doctest/doctest.h>

#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/studies/regularization_study.hpp>
#include <filesystem>
#include <map>
#include <numbers>

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
    // The staircase encloses its voxels, within 10% of the ball at h = 0.2.
    CHECK(r.volume_before == doctest::Approx(4.0 / 3.0 * std::numbers::pi).epsilon(0.1));
    if (r.method != "alignment") CHECK(r.alpha0 == 10.0);
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
  CHECK(back[5].volume_after == rows[5].volume_after);
  CHECK(back[0].alpha0 == 10.0);
  CHECK(std::isnan(back[5].alpha0));  // the baseline has no attachment weight

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

TEST_CASE("regularization study: the alpha0 sweep shows the uncorrected operator's inflation (paper Fig. 13)") {
  // sphere1 at h = 0.1. The uncorrected PolyDEC inflates the sphere as alpha0 falls (the paper: "the
  // non-corrected operator inflates the shape at low alpha"); fem keeps its area within 2% of 4 pi.
  RegularizationStudyOptions o;
  o.shapes = {"sphere1"};
  o.h = {0.1};
  o.methods = {"fem", "polydec", "alignment"};
  o.alpha0 = {10.0, 0.1, 0.01};
  o.min_aabb = -1.5;
  o.max_aabb = 1.5;
  std::vector<RegularizationStudyRow> rows;
  int total = 0;
  run_regularization_study(
      o, [&](const RegularizationStudyRow& r) { rows.push_back(r); },
      [&](const RegularizationStudyProgress& p) { total = p.total; });
  REQUIRE(rows.size() == 7);  // 2 methods x 3 weights + the baseline once
  CHECK(total == 7);
  std::map<std::string, std::vector<double>> area;
  const double sphere = 4.0 * std::numbers::pi;
  for (const auto& r : rows) {
    MESSAGE(r.method << " alpha0 = " << r.alpha0 << ": area " << r.area_after << ", volume " << r.volume_after
                     << ", distance " << r.distance_after);
    if (r.method == "alignment") {
      CHECK(std::isnan(r.alpha0));
      continue;
    }
    area[r.method].push_back(r.area_after);
  }
  REQUIRE(area["polydec"].size() == 3);
  REQUIRE(area["fem"].size() == 3);
  // alpha0 10, 0.1, 0.01 in that order: polydec's area grows as alpha0 falls, and at 0.01 it is
  // more than 20% above the sphere's (measured 20.3 against 12.57).
  CHECK(area["polydec"][1] > area["polydec"][0]);
  CHECK(area["polydec"][2] > area["polydec"][1]);
  CHECK(area["polydec"][2] > 1.2 * sphere);
  for (const double a : area["fem"]) CHECK(a == doctest::Approx(sphere).epsilon(0.02));
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
  o.alpha0 = {1.0, -1.0};
  CHECK_THROWS_WITH_AS(o.validate(),
                       doctest::Contains("alpha0 must be a finite number >= 0 (0: no attachment), got -1"), InputError);
  o.alpha0 = {1.0, 1.0};
  CHECK_THROWS_WITH_AS(o.validate(), doctest::Contains("alpha0 = 1 is given twice"), InputError);
  o.alpha0 = {};
  CHECK_THROWS_WITH_AS(o.validate(), doctest::Contains("no alpha0"), InputError);
  o.alpha0 = {10.0};
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
  CHECK(out.find("sphere1 h=0.2 fem alpha0=10: distance") != std::string::npos);
  CHECK(out.find("sphere1 h=0.2 alignment: distance") != std::string::npos);
  CHECK(test::run_cli(args, &out, &err) == 1);  // the folder holds a study
  CHECK(err.find("--overwrite") != std::string::npos);
  CHECK(test::run_cli(args + " --overwrite --resolutions 16", &out, &err) == 1);
  CHECK(err.find("--h or --resolutions, not both") != std::string::npos);
  CHECK(test::run_cli("study regularization --shapes nosuch --out " + dir + "_bad", &out, &err) == 1);
  CHECK(test::run_cli("study regularization --alpha0 1,x --out " + dir + "_bad", &out, &err) == 1);
  CHECK(err.find("--alpha0: 'x' is not a number") != std::string::npos);
  CHECK(test::run_cli("study regularization --alpha0 1,-2 --out " + dir + "_bad", &out, &err) == 1);
  CHECK(err.find("alpha0 must be a finite number >= 0 (0: no attachment), got -2") != std::string::npos);
  // A sweep: one row per alpha0 for fem, one for the baseline.
  REQUIRE(test::run_cli(args + " --overwrite --alpha0 0.1,10", &out, &err) == 0);
  const auto swept = read_regularization_csv(dir + "/regularization.csv");
  REQUIRE(swept.size() == 3);
  CHECK(swept[0].alpha0 == 0.1);
  CHECK(swept[1].alpha0 == 10.0);
  CHECK(std::isnan(swept[2].alpha0));
}
