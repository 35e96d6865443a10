// The automatic attachment weight (docs/math.md §9.4, regularization/attachment_bias.hpp): the bias
// measure, the search rule, and regularize_surface with it on a smooth shape (alpha0 kept) and on
// a shape with sharp edges (alpha0 raised, the edges kept).
#include <doctest/doctest.h>

#include <cmath>
#include <corrlap/corrlap.hpp>
#include <corrlap/pipeline/load_surface.hpp>
#include <corrlap/pipeline/surface_defaults.hpp>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "regularization/sphere_fixture.hpp"

using namespace corrlap;

namespace {

Eigen::VectorXd vertex_mass(const SurfelMesh& mesh, const NormalFields& normals) {
  const Operators ops = make_discretization("fem")->assemble(mesh, normals, Config());
  return ops.M * Eigen::VectorXd::Ones(ops.M.cols());
}

// An axis-aligned cube of `side` voxels in a grid of `n`^3: its staircase is the cube itself.
std::vector<double> cube_volume(int n, int side) {
  std::vector<double> v(std::size_t(n) * n * n, 0.0);
  const int lo = (n - side) / 2, hi = lo + side;
  for (int x = lo; x < hi; ++x)
    for (int y = lo; y < hi; ++y)
      for (int z = lo; z < hi; ++z) v[std::size_t((x * n + y) * n + z)] = 1.0;
  return v;
}

// Mean distance of the points to the surface of the box [lo, hi].
double mean_distance_to_box(const Eigen::MatrixX3d& p, const Eigen::RowVector3d& lo, const Eigen::RowVector3d& hi) {
  double sum = 0.0;
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    const Eigen::RowVector3d x = p.row(i);
    const Eigen::RowVector3d outside = (lo - x).cwiseMax(x - hi).cwiseMax(0.0);
    if (outside.squaredNorm() > 0.0) {
      sum += outside.norm();
    } else {
      sum += std::min((x - lo).minCoeff(), (hi - x).minCoeff());
    }
  }
  return sum / double(p.rows());
}

}  // namespace

TEST_CASE("attachment_bias: a uniform offset along the normals is its size in steps, zero-mean noise averages out") {
  const test::RegularizationSphere& s = test::regularization_sphere();
  const Eigen::VectorXd mass = vertex_mass(s.mesh, s.normals);
  const double step = s.mesh.grid_step();
  const Eigen::MatrixX3d& n = s.normals.vertex;
  // Smoothing a constant leaves it: 0.3 steps inwards is 0.3 whatever the rounds.
  const Eigen::MatrixX3d inwards = s.mesh.positions - 0.3 * step * n;
  CHECK(attachment_bias(s.mesh.faces, s.mesh.positions, inwards, n, mass, step) == doctest::Approx(0.3).epsilon(1e-12));
  CHECK(attachment_bias(s.mesh.faces, s.mesh.positions, inwards, n, mass, step, 0) ==
        doctest::Approx(0.3).epsilon(1e-12));
  // Independent +-0.3-step offsets (the staircase's kind of error): unsmoothed the mean |s| is
  // 0.3; 16 rounds average each vertex over a few hundred neighbours, so the mean falls by about
  // their square root. Asserted: below a quarter.
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> coin(0, 1);
  Eigen::MatrixX3d noisy = s.mesh.positions;
  for (Eigen::Index v = 0; v < noisy.rows(); ++v) noisy.row(v) += (coin(rng) ? 0.3 : -0.3) * step * n.row(v);
  const double raw = attachment_bias(s.mesh.faces, s.mesh.positions, noisy, n, mass, step, 0);
  const double smoothed = attachment_bias(s.mesh.faces, s.mesh.positions, noisy, n, mass, step);
  CHECK(raw == doctest::Approx(0.3).epsilon(1e-12));
  CHECK(smoothed < 0.25 * raw);
  // Bad inputs are named.
  CHECK_THROWS_AS(attachment_bias(s.mesh.faces, s.mesh.positions, noisy.topRows(3), n, mass, step), InputError);
  CHECK_THROWS_AS(attachment_bias(s.mesh.faces, s.mesh.positions, noisy, n, mass, 0.0), InputError);
  CHECK_THROWS_AS(attachment_bias(s.mesh.faces, s.mesh.positions, noisy, n, mass, step, -1), InputError);
}

TEST_CASE("next_alpha0: the log-log line to 0.8 limit, stops within the limit, on a shallow slope, at the cap") {
  const double limit = kAttachmentBiasLimit;
  // First raise: slope 0.4 assumed.
  const double first = next_alpha0({{10.0, 0.1}}, limit, 1e9);
  CHECK(first == doctest::Approx(10.0 * std::pow(0.1 / (0.8 * limit), 1.0 / 0.4)));
  // Within the limit: no raise; the last trial is kept.
  CHECK(next_alpha0({{10.0, 0.5 * limit}}, limit, 1e9) == 0.0);
  CHECK(chosen_alpha0_trial({{10.0, 0.5 * limit}}) == 0);
  // A raise that bought the bias back (slope 0.4): go on along the measured slope; keep the last.
  const std::vector<Alpha0Trial> steep = {{10.0, 0.1}, {100.0, 0.1 * std::pow(10.0, -0.4)}};
  CHECK(bias_slope(steep[0], steep[1]) == doctest::Approx(0.4));
  CHECK(next_alpha0(steep, limit, 1e9) == doctest::Approx(100.0 * std::pow(steep[1].bias / (0.8 * limit), 1.0 / 0.4)));
  CHECK(chosen_alpha0_trial(steep) == 1);
  // A raise that hardly moved the bias (a smooth shape near the limit): stop, keep the one before.
  const std::vector<Alpha0Trial> shallow = {{10.0, 0.0236}, {26.0, 0.0218}};
  CHECK(bias_slope(shallow[0], shallow[1]) < kAutoAlpha0MinSlope);
  CHECK(next_alpha0(shallow, limit, 1e9) == 0.0);
  CHECK(chosen_alpha0_trial(shallow) == 0);
  // The cap and the number of solves.
  CHECK(next_alpha0({{10.0, 1.0}}, limit, 50.0) == 50.0);
  CHECK(next_alpha0({{50.0, 1.0}}, limit, 50.0) == 0.0);
  CHECK(next_alpha0({{10.0, 1.0}, {20.0, 0.5}, {40.0, 0.25}, {80.0, 0.125}}, limit, 1e9, 4) == 0.0);
  // The factor is clamped to [1.5, 1e4]: a steep slope (2) would ask for 1.25.
  CHECK(next_alpha0({{10.0, 0.1}, {20.0, 0.025}}, limit, 1e9) == doctest::Approx(30.0));
  CHECK(next_alpha0({{10.0, 100.0}}, limit, 1e9) == doctest::Approx(1e5));
  // The wavelength's alpha0: (2 pi / l)^4 s^2; a wave twice as long needs 16 times less.
  CHECK(alpha0_for_wavelength(2.0 * std::numbers::pi, 3.0) == doctest::Approx(9.0));
  CHECK(alpha0_for_wavelength(2.0, 64.0) == doctest::Approx(16.0 * alpha0_for_wavelength(4.0, 64.0)));
  CHECK_THROWS_AS(alpha0_for_wavelength(0.0, 64.0), InputError);
}

TEST_CASE("regularize_surface, automatic alpha0: kept on a smooth sphere, raised on a cube whose edges it then keeps") {
  // The sphere: smooth at the voxel scale, its result is alpha0 = 10's.
  const test::RegularizationSphere& s = test::regularization_sphere();
  RegularizationOptions fixed;
  fixed.alpha0_auto = false;
  const RegularizedSurface sphere_auto = regularize_surface(s.mesh, s.normals, RegularizationOptions{});
  const RegularizedSurface sphere_fixed = regularize_surface(s.mesh, s.normals, fixed);
  CHECK(sphere_auto.alpha0 == 10.0);
  REQUIRE(!sphere_auto.alpha0_trials.empty());
  CHECK(sphere_auto.alpha0_trials.front().alpha0 == 10.0);
  CHECK((sphere_auto.mesh.positions - sphere_fixed.mesh.positions).cwiseAbs().maxCoeff() == 0.0);
  CHECK(sphere_fixed.alpha0_trials.empty());

  // A cube of 16 voxels: alpha0 = 10 rounds its edges and corners (the curvature ball averages
  // them away); the automatic choice raises alpha0 until the bias is within the limit, and the
  // result stays closer to the cube (a third closer when written: alpha0 about 40 after 2 solves).
  const std::vector<double> values = cube_volume(24, 16);
  const LoadedSurface cube = load_surface(VolumeArrayInput::c_order(values, Eigen::Vector3i(24, 24, 24)));
  const NormalFields n = resolve_normals(cube, NormalKind::Vertex, NormalRequest{});
  const RegularizedSurface cube_auto = regularize_surface(cube, n, RegularizationOptions{});
  const RegularizedSurface cube_fixed = regularize_surface(cube, n, fixed);
  const Eigen::RowVector3d lo = cube.mesh.positions.colwise().minCoeff(), hi = cube.mesh.positions.colwise().maxCoeff();
  const double d_auto = mean_distance_to_box(cube_auto.mesh.positions, lo, hi) / cube.h;
  const double d_fixed = mean_distance_to_box(cube_fixed.mesh.positions, lo, hi) / cube.h;
  MESSAGE("cube: alpha0 " << cube_auto.alpha0 << " after " << cube_auto.alpha0_trials.size() << " solves, bias "
                          << cube_auto.alpha0_trials.back().bias << "; mean distance " << d_auto << " voxels against "
                          << d_fixed << " at alpha0 = 10");
  CHECK(cube_auto.alpha0 > 10.0);
  CHECK(cube_auto.alpha0_trials.size() >= 2);
  CHECK(cube_auto.alpha0_trials.front().bias > kAttachmentBiasLimit);
  CHECK(d_auto < 0.8 * d_fixed);
}

TEST_CASE("regularize_surface reports its stages: the curvature, then one line per solve of the automatic alpha0") {
  const RegularizationOptions defaults;
  const std::vector<double> values = cube_volume(24, 16);
  const LoadedSurface cube = load_surface(VolumeArrayInput::c_order(values, Eigen::Vector3i(24, 24, 24)));
  const NormalFields n = resolve_normals(cube, NormalKind::Vertex, NormalRequest{});
  std::vector<std::string> lines;
  RegularizationOptions o;
  o.report_stage = [&](const std::string& line) { lines.push_back(line); };
  const RegularizedSurface r = regularize_surface(cube, n, o);
  REQUIRE(r.alpha0_trials.size() >= 2);  // the cube raises alpha0 (the test above)
  REQUIRE(lines.size() == 1 + r.alpha0_trials.size());
  CHECK(lines[0].find("mean curvature in balls of radius") == 0);
  CHECK(lines[1] == "solving with alpha0 = 10");
  // Each raise names the last trial's bias and the next alpha0, as the trials record them.
  for (std::size_t t = 1; t < r.alpha0_trials.size(); ++t) {
    std::ostringstream bias, next;
    bias << r.alpha0_trials[t - 1].bias;
    next << r.alpha0_trials[t].alpha0;
    CHECK(lines[1 + t].find("keeps " + bias.str() + " voxels") != std::string::npos);
    CHECK(lines[1 + t].find("solving with alpha0 = " + next.str()) != std::string::npos);
  }
  // The same result as without a report, and a fixed alpha0 solves once.
  CHECK((regularize_surface(cube, n, defaults).mesh.positions - r.mesh.positions).cwiseAbs().maxCoeff() == 0.0);
  lines.clear();
  o.alpha0_auto = false;
  regularize_surface(cube, n, o);
  CHECK(lines.size() == 2);
}
