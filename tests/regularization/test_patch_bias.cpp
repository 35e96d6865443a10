// The first trial of the automatic alpha0 estimated from patches (docs/math.md §9.5,
// regularization/patch_bias.hpp): exact when one patch holds the whole surface, close to the whole
// solve's bias when it samples it, and regularize_surface's use of it.
#include <doctest/doctest.h>

#include <cmath>
#include <corrlap/corrlap.hpp>
#include <corrlap/pipeline/load_surface.hpp>
#include <corrlap/pipeline/surface_defaults.hpp>
#include <corrlap/regularization/patch_bias.hpp>
#include <string>
#include <vector>

#include "regularization/sphere_fixture.hpp"

using namespace corrlap;

namespace {

// A cube of voxels, `side` wide in a grid of n^3: sharp edges and corners whose curvature the ball
// spreads. With `ridges`, its top and bottom faces carry ridges 2 voxels wide and high, 6 apart:
// detail narrower than a ball of several voxels, which alpha0 = 10 smooths away.
LoadedSurface box(int n, int side, bool ridges) {
  std::vector<double> v(std::size_t(n) * n * n, 0.0);
  const auto set = [&](int x, int y, int z) { v[std::size_t((x * n + y) * n + z)] = 1.0; };
  const int lo = (n - side) / 2, hi = lo + side;
  for (int x = lo; x < hi; ++x)
    for (int y = lo; y < hi; ++y) {
      for (int z = lo; z < hi; ++z) set(x, y, z);
      if (ridges && x % 6 < 2)
        for (int dz = 0; dz < 2; ++dz) {
          set(x, y, hi + dz);
          set(x, y, lo - 1 - dz);
        }
    }
  return load_surface(VolumeArrayInput::c_order(v, Eigen::Vector3i(n, n, n)));
}

struct Problem {
  LoadedSurface surface;
  NormalFields normals;
  RegularizationOptions options;
  RegularizationCurvature curvature;
  Operators ops;
  double alpha = 0.0, step = 0.0;
};

// `radius_voxels` > 0: the curvature ball in voxels, else the default.
Problem problem(int n, int side, bool ridges = false, double radius_voxels = 0.0) {
  Problem p{box(n, side, ridges), {}, {}, {}, {}, 0.0, 0.0};
  p.normals = resolve_normals(p.surface, NormalKind::Vertex, NormalRequest{});
  p.step = p.surface.mesh.grid_step();
  if (radius_voxels > 0.0) p.options.curvature_radius = radius_voxels * p.step;
  p.curvature = regularization_curvature(p.surface, p.normals, p.options);
  p.ops = make_discretization("fem")->assemble(p.surface.mesh, p.normals, Config());
  p.alpha = regularization_alpha(p.step * p.curvature.size, 10.0);
  return p;
}

double whole_bias(const Problem& p) {
  auto solver = make_linear_solver("cholmod");
  const Eigen::MatrixX3d q = regularize_positions_preconditioned(
      p.ops.L, p.ops.M, p.surface.mesh.positions, p.curvature.normals, p.curvature.H, p.alpha, *solver, nullptr, 0.0);
  const Eigen::VectorXd mass = p.ops.M * Eigen::VectorXd::Ones(p.ops.M.cols());
  return attachment_bias(p.surface.mesh.faces, p.surface.mesh.positions, q, p.curvature.normals, mass, p.step);
}

PatchBias estimate(const Problem& p, const PatchBiasOptions& o) {
  return patch_attachment_bias(p.surface.mesh.faces, p.ops.L, p.ops.M, p.surface.mesh.positions, p.curvature.normals,
                               p.curvature.H, p.alpha, p.step, o);
}

}  // namespace

TEST_CASE("patch_attachment_bias: one patch over the whole surface is attachment_bias of the whole solve") {
  const Problem p = problem(28, 20);
  PatchBiasOptions whole;
  whole.patches = 1;
  whole.core_rings = 1000000;  // every vertex of the (single) component
  whole.accuracy = 0.0;        // both solves to rounding
  const PatchBias e = estimate(p, whole);
  const double reference = whole_bias(p);
  MESSAGE("box of 20 voxels: whole-solve bias " << reference << ", one patch " << e.bias);
  CHECK(e.patches == 1);
  CHECK(e.vertices == p.surface.mesh.num_vertices());
  CHECK(e.core_vertices == p.surface.mesh.num_vertices());
  // The same system (L M^-1 L + alpha M) q = alpha M p - 2 L (H n), its right-hand side formed
  // through the displacement: the two solutions agree to the solves' rounding.
  CHECK(e.bias == doctest::Approx(reference).epsilon(1e-6));
}

TEST_CASE("patch_attachment_bias: sampled patches estimate the whole solve's bias") {
  // The plain box (bias 0.034, edges and corners) and the ridged one with an 8-voxel ball (0.153,
  // detail everywhere on two faces). The cores, 8 rings around seeds spread over the vertex order,
  // sample faces of different bias; written: within 4% at 16 and 64 patches. Asserted: 15%, the
  // margin that the skip rule's factor 4 over the limit leaves (kPatchBiasSkipFactor).
  for (const bool ridges : {false, true}) {
    const Problem p = problem(48, 36, ridges, ridges ? 8.0 : 0.0);
    const double reference = whole_bias(p);
    for (const int patches : {16, 64}) {
      PatchBiasOptions o;
      o.patches = patches;
      const PatchBias e = estimate(p, o);
      MESSAGE("box of 36 voxels, ridges " << ridges << ", " << p.surface.mesh.num_vertices()
                                          << " vertices: whole-solve bias " << reference << ", " << patches
                                          << " patches " << e.bias << " (" << e.vertices << " vertices solved)");
      CHECK(e.patches == patches);
      CHECK(e.core_vertices < e.vertices);
      CHECK(std::abs(e.bias - reference) <= 0.15 * reference);
    }
  }
  // stop_below: after the first round (every 4th patch, spread over the surface) an estimate below
  // it stops; the rounds that run give the same estimate as patches that many.
  const Problem p = problem(28, 20);
  PatchBiasOptions all, early;
  all.patches = early.patches = 16;
  early.stop_below = 1.0;  // far above this box's 0.03
  const PatchBias e_all = estimate(p, all), e_early = estimate(p, early);
  CHECK(e_all.patches == 16);
  CHECK(e_early.patches == 4);
  CHECK(e_early.vertices < e_all.vertices);
  CHECK(e_early.bias > 0.0);
  // Bad inputs are named.
  PatchBiasOptions none;
  none.patches = 0;
  CHECK_THROWS_AS(estimate(p, none), InputError);
  CHECK_THROWS_AS(patch_rings(0.0, p.step), InputError);
}

TEST_CASE("regularize_surface skips a first trial whose estimate is far above the limit") {
  // The ridged box with an 8-voxel ball, as above: the first trial's bias is 0.15 (7.6 times the
  // limit). With the estimate on (any surface size), alpha0 = 10 is not solved; without it, it is.
  const Problem p = problem(48, 36, true, 8.0);
  RegularizationOptions estimated = p.options, whole = p.options;
  estimated.patch_bias_min_vertices = 0;
  whole.patch_bias_min_vertices = p.surface.mesh.num_vertices() + 1;
  std::vector<std::string> lines;
  estimated.report_stage = [&](const std::string& line) { lines.push_back(line); };
  const RegularizedSurface a = regularize_surface(p.surface, p.normals, estimated);
  const RegularizedSurface b = regularize_surface(p.surface, p.normals, whole);
  MESSAGE("estimated: alpha0 " << a.alpha0 << " after trials " << a.alpha0_trials.size() << " (first bias "
                               << a.alpha0_trials.front().bias << "); whole: alpha0 " << b.alpha0 << " (first bias "
                               << b.alpha0_trials.front().bias << ")");
  REQUIRE(a.alpha0_trials.size() >= 2);
  CHECK(a.alpha0_trials.front().estimated);
  CHECK(a.alpha0_trials.front().alpha0 == 10.0);
  CHECK_FALSE(a.alpha0_trials.back().estimated);
  CHECK_FALSE(b.alpha0_trials.front().estimated);
  // The first bias within the estimate's 15%, so the next alpha0 (bias^(1/0.4)) within a factor
  // 1.15^2.5 = 1.42 of the whole path's, and the result within the limit either way.
  CHECK(std::abs(a.alpha0_trials.front().bias - b.alpha0_trials.front().bias) <= 0.15 * b.alpha0_trials.front().bias);
  CHECK(a.alpha0 == doctest::Approx(b.alpha0).epsilon(0.42));
  CHECK(a.alpha0_trials.back().bias <= kAttachmentBiasLimit);
  CHECK(b.alpha0_trials.back().bias <= kAttachmentBiasLimit);
  // The report says so.
  REQUIRE(lines.size() >= 3);
  CHECK(lines[1] == "estimating the bias at alpha0 = 10 from 128 patches");
  CHECK(lines[2].find("the estimate at alpha0 = 10 keeps ") == 0);
  // A smooth sphere's estimate is below the skip factor: its first trial is solved as without it.
  const test::RegularizationSphere& s = test::regularization_sphere();
  RegularizationOptions sphere;
  sphere.patch_bias_min_vertices = 0;
  const RegularizedSurface c = regularize_surface(s.mesh, s.normals, sphere);
  const RegularizedSurface d = regularize_surface(s.mesh, s.normals, RegularizationOptions{});
  CHECK_FALSE(c.alpha0_trials.front().estimated);
  CHECK((c.mesh.positions - d.mesh.positions).cwiseAbs().maxCoeff() == 0.0);
}
