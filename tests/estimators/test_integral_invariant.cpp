// Integral-invariant normals (docs/math.md §7, numbers of §12.4, reference data of sphere1 h = 0.2).
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/estimators/integral_invariant.hpp>
#include <corrlap/estimators/normal_resolution.hpp>
#include <corrlap/io/text_io.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <corrlap/surface/implicit_shape.hpp>
#include <functional>
#include <map>
#include <random>
#include <tuple>

#include "test_support.hpp"

using namespace corrlap;

namespace {
struct Digital {
  VoxelGrid grid;
  SurfelMesh mesh;
};
Digital digital(const std::string& shape, double h, double lo, double hi) {
  DigitizationParams p;
  p.h = h;
  p.min_aabb = lo;
  p.max_aabb = hi;
  Digital d;
  d.grid = digitize(make_implicit_shape(shape), p);
  d.mesh = extract_surface(d.grid);
  return d;
}
// Angle (radians) between each face normal and the radial direction at the surfel centre.
std::vector<double> radial_angles(const SurfelMesh& m, const Eigen::MatrixX3d& n) {
  const Eigen::MatrixX3d c = m.face_centroids();
  std::vector<double> a(std::size_t(c.rows()));
  for (Eigen::Index f = 0; f < c.rows(); ++f) {
    const double d = std::clamp(n.row(f).dot(c.row(f).normalized()), -1.0, 1.0);
    a[std::size_t(f)] = std::acos(d);
  }
  return a;
}
double mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return s / double(v.size());
}
double maxv(const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); }
constexpr double deg = 180.0 / M_PI;
}  // namespace

TEST_CASE("ii fast moments equal brute-force moments exactly, also near the box boundary") {
  // Torus at h = 0.5 crossing the box (open surface, balls clipped by the box) and goursat.
  for (const auto& [shape, h, lo, hi] :
       {std::tuple<std::string, double, double, double>{"torus", 0.5, -8, 4}, {"goursat", 0.6, -10, 10}}) {
    const Digital d = digital(shape, h, lo, hi);
    std::vector<Eigen::Vector3i> centres;
    for (std::size_t f = 0; f < d.mesh.surfels.size(); f += 7) {
      centres.push_back(d.mesh.surfels[f].inner_voxel());
      centres.push_back(d.mesh.surfels[f].outer_voxel());
    }
    const double rd = ii_digital_radius(h, {});
    const auto fast = ii_moments(d.grid, rd, h, centres);
    const auto slow = ii_moments_brute_force(d.grid, rd, h, centres);
    REQUIRE(fast.size() == slow.size());
    int mismatches = 0;
    for (std::size_t i = 0; i < fast.size(); ++i) mismatches += !(fast[i] == slow[i]);
    const auto shape_copy = shape;  // clang 14: no structured binding inside CAPTURE/INFO
    CHECK_MESSAGE(mismatches == 0, shape_copy);
    CHECK(slow[0].m0 > 0);
  }
}

TEST_CASE("ii fast and brute-force normals agree to 1e-9") {
  // Brute force: ii_component_moments_brute_force (docs/math.md §7.1).
  const Digital d = digital("goursat", 0.7, -10, 10);
  const Eigen::MatrixX3d a = ii_face_normals(d.grid, d.mesh, {}, IIMethod::Fast);
  const Eigen::MatrixX3d b = ii_face_normals(d.grid, d.mesh, {}, IIMethod::BruteForce);
  CHECK((a - b).cwiseAbs().maxCoeff() <= 1e-9);
  CHECK((a.rowwise().norm().array() - 1.0).abs().maxCoeff() < 1e-12);
}

TEST_CASE("ii normals match the reference on sphere1 h=0.2 (alpha = 1/3)") {
  const Digital d = digital("sphere1", 0.2, -1.5, 1.5);
  IIParams p;
  p.alpha = 1.0 / 3.0;
  CHECK(ii_digital_radius(0.2, p) * 0.2 == doctest::Approx(1.7544106429277198).epsilon(1e-14));
  const Eigen::MatrixX3d n = ii_face_normals(d.grid, d.mesh, p);
  const Eigen::MatrixX3d ref = read_normals(test::reference_dir() + "/sphere1_h0.2/face_normals_ii.txt");
  REQUIRE(ref.rows() == n.rows());
  double mean_angle = 0, max_angle = 0;
  for (Eigen::Index f = 0; f < n.rows(); ++f) {
    const double a = std::atan2(n.row(f).cross(ref.row(f)).norm(), n.row(f).dot(ref.row(f)));
    mean_angle += a / double(n.rows());
    max_angle = std::max(max_angle, a);
  }
  MESSAGE("II vs reference: mean angle " << mean_angle << " rad, max " << max_angle);
  CHECK(mean_angle <= 1e-6);
  CHECK(max_angle <= 1e-6);
}

TEST_CASE("ii angle statistics on sphere1 reproduce docs/math.md §12.4") {
  // Default box of the reference (-10..10) gives the same surface; -2..2 is faster (docs/math.md §1.2).
  const Digital d25 = digital("sphere1", 0.25, -2, 2);
  const auto a25 = radial_angles(d25.mesh, ii_face_normals(d25.grid, d25.mesh));
  CHECK(mean(a25) * deg == doctest::Approx(5.227).epsilon(5e-4));
  CHECK(maxv(a25) * deg == doctest::Approx(11.663).epsilon(5e-4));
  const Digital d10 = digital("sphere1", 0.1, -2, 2);
  const auto a10 = radial_angles(d10.mesh, ii_face_normals(d10.grid, d10.mesh));
  CHECK(mean(a10) * deg == doctest::Approx(0.336).epsilon(2e-3));
  CHECK(maxv(a10) * deg == doctest::Approx(0.637).epsilon(2e-3));
}

TEST_CASE("ii mean angle error on sphere1 decreases from h=0.1 to h=0.025") {
  double previous = 1e9;
  for (double h : {0.1, 0.05, 0.025}) {
    const Digital d = digital("sphere1", h, -1.5, 1.5);
    const double m = mean(radial_angles(d.mesh, ii_face_normals(d.grid, d.mesh)));
    CHECK_MESSAGE(m < previous, "h = " << h);
    previous = m;
  }
  CHECK(previous * deg < 0.2);
}

TEST_CASE("ii normals reject a radius below one voxel, above the volume, and meshes without voxels") {
  const Digital d = digital("sphere1", 0.25, -1.5, 1.5);
  IIParams tiny;
  tiny.k = 0.1;
  CHECK_THROWS_WITH_AS(ii_face_normals(d.grid, d.mesh, tiny), doctest::Contains("smaller than one voxel"), InputError);
  IIParams huge;
  huge.k = 100;
  CHECK_THROWS_WITH_AS(ii_face_normals(d.grid, d.mesh, huge), doctest::Contains("larger than the volume"), InputError);
  SurfelMesh no_voxels = d.mesh;
  no_voxels.surfels.clear();
  CHECK_THROWS_AS(ii_face_normals(d.grid, no_voxels), InputError);
  // The errors speak library terms and name the parameter at fault (front ends add their flag).
  const auto parameter_of = [](const auto& f) -> std::string {
    try {
      f();
    } catch (const InputError& e) {
      CHECK(std::string(e.what()).find("--") == std::string::npos);
      return e.parameter();
    }
    return "(no error)";
  };
  CHECK(parameter_of([&] { ii_face_normals(d.grid, d.mesh, tiny); }) == "ii_radius");
  CHECK(parameter_of([&] { ii_face_normals(d.grid, no_voxels); }) == "normals");
}

// docs/math.md §7.1: each surfel's balls keep the 6-component of X that holds its inner voxel.
namespace {
VoxelGrid voxels(const Eigen::Vector3i& size, const std::function<bool(int, int, int)>& inside) {
  VoxelGrid g(Eigen::Vector3i::Zero(), size - Eigen::Vector3i::Ones(), 1.0);
  for (int z = 0; z < size.z(); ++z)
    for (int y = 0; y < size.y(); ++y)
      for (int x = 0; x < size.x(); ++x)
        if (inside(x, y, z)) g.set(x, y, z, true);
  return g;
}
// Blocks of 10 voxels from 4 to 24 on each axis, the even ones inside: four blocks meeting along edges.
bool checkerboard(int x, int y, int z) {
  if (std::min({x, y, z}) < 4 || std::max({x, y, z}) >= 24) return false;
  return ((x - 4) / 10 + (y - 4) / 10 + (z - 4) / 10) % 2 == 0;
}
// The two balls of each surfel, as ii_face_normals builds them.
std::vector<IIBall> surfel_balls(const SurfelMesh& mesh) {
  std::vector<IIBall> balls;
  for (const Surfel& s : mesh.surfels) {
    balls.push_back({s.inner_voxel(), s.inner_voxel()});
    balls.push_back({s.outer_voxel(), s.inner_voxel()});
  }
  return balls;
}
}  // namespace

TEST_CASE("ii component moments: the fast form equals the brute force on several components") {
  std::mt19937 rng(7);
  std::bernoulli_distribution coin(0.45);
  std::vector<std::pair<std::string, VoxelGrid>> cases;
  cases.emplace_back("checkerboard", voxels({28, 28, 28}, checkerboard));
  for (int i = 0; i < 3; ++i)
    cases.emplace_back("random " + std::to_string(i), voxels({12, 11, 10}, [&](int, int, int) { return coin(rng); }));
  // Two balls of radius 5 two voxels apart, closer than the ball's diameter.
  cases.emplace_back("two close balls", voxels({28, 16, 16}, [](int x, int y, int z) {
                       const auto d2 = [&](double cx) {
                         return (x - cx) * (x - cx) + (y - 7.5) * (y - 7.5) + (z - 7.5) * (z - 7.5);
                       };
                       return d2(7.5) <= 25.0 || d2(19.5) <= 25.0;
                     }));
  cases.emplace_back("sphere1 h=0.25", digital("sphere1", 0.25, -2, 2).grid);
  for (const auto& [name, grid] : cases) {
    const SurfelMesh mesh = extract_surface(grid);
    std::vector<IIBall> balls = surfel_balls(mesh);
    // A seed outside X has no component: zero moments.
    balls.push_back({mesh.surfels[0].outer_voxel(), mesh.surfels[0].outer_voxel()});
    for (const double rd : {1.5, 4.0}) {
      const ComponentMoments fast = ii_component_moments(grid, rd, grid.h(), balls);
      const std::vector<BallMoments> slow = ii_component_moments_brute_force(grid, rd, grid.h(), balls);
      REQUIRE(fast.index.size() == slow.size());
      int mismatches = 0;
      for (std::size_t i = 0; i < slow.size(); ++i) mismatches += !(fast[i] == slow[i]);
      const std::string what = name;  // clang 14: no structured binding inside CAPTURE/INFO
      CHECK_MESSAGE(mismatches == 0, what << ", r_d = " << rd);
      CHECK(slow.back().m0 == 0);
      CHECK(slow[0].m0 > 0);
    }
  }
}

TEST_CASE("ii component moments on one component are the whole ball's (the normals do not change)") {
  // A single 6-component: B(c, R) ∩ K = B(c, R) ∩ X, so every ball has the moments of ii_moments,
  // bit for bit, and the normals stay those verified against the reference.
  for (const auto& [shape, h, lo, hi] : {std::tuple<std::string, double, double, double>{"sphere1", 0.1, -2, 2},
                                         {"torus", 0.25, -10, 10},
                                         {"torus", 0.1, -10, 10},
                                         {"goursat", 0.25, -10, 10}}) {
    const Digital d = digital(shape, h, lo, hi);
    const std::vector<IIBall> balls = surfel_balls(d.mesh);
    std::vector<Eigen::Vector3i> centres;
    for (const IIBall& b : balls) centres.push_back(b.centre);
    const double rd = ii_digital_radius(h, {});
    const ComponentMoments restricted = ii_component_moments(d.grid, rd, h, balls);
    const std::vector<BallMoments> whole = ii_moments(d.grid, rd, h, centres);
    int mismatches = 0;
    for (std::size_t i = 0; i < whole.size(); ++i) mismatches += !(restricted[i] == whole[i]);
    const std::string what = shape + " h=" + std::to_string(h);
    CHECK_MESSAGE(mismatches == 0, what);
  }
}

TEST_CASE("ii normals on a checkerboard are those of each block alone") {
  const VoxelGrid board = voxels({28, 28, 28}, checkerboard);
  const SurfelMesh mesh = extract_surface(board);
  IIParams p = default_ii_params(false);
  const Eigen::MatrixX3d n = ii_face_normals(board, mesh, p);
  // The block of voxels [4, 14)^3 alone in the same box: its surfels' normals must be the same.
  const VoxelGrid block = voxels({28, 28, 28}, [](int x, int y, int z) {
    return std::min({x, y, z}) >= 4 && std::max({x, y, z}) < 14;
  });
  const SurfelMesh block_mesh = extract_surface(block);
  const Eigen::MatrixX3d nb = ii_face_normals(block, block_mesh, p);
  std::map<std::tuple<int, int, int, int>, Eigen::Index> face_of;
  for (std::size_t f = 0; f < block_mesh.surfels.size(); ++f) {
    const Surfel& s = block_mesh.surfels[f];
    face_of[{s.lower_voxel.x(), s.lower_voxel.y(), s.lower_voxel.z(), s.axis}] = Eigen::Index(f);
  }
  int matched = 0;
  double max_difference = 0.0, max_angle = 0.0;
  int over_30 = 0;
  for (std::size_t f = 0; f < mesh.surfels.size(); ++f) {
    const Surfel& s = mesh.surfels[f];
    const double a = std::acos(std::clamp(n.row(Eigen::Index(f)).dot(s.trivial_normal().transpose()), -1.0, 1.0));
    max_angle = std::max(max_angle, a);
    over_30 += a > 30.0 / deg;
    const auto it = face_of.find({s.lower_voxel.x(), s.lower_voxel.y(), s.lower_voxel.z(), s.axis});
    if (it == face_of.end()) continue;
    ++matched;
    max_difference = std::max(max_difference, (n.row(Eigen::Index(f)) - nb.row(it->second)).cwiseAbs().maxCoeff());
  }
  MESSAGE("checkerboard: " << over_30 << " of " << mesh.surfels.size()
                           << " II normals more than 30 degrees from the trivial normal, max " << max_angle * deg
                           << " degrees");
  CHECK(matched == 600);  // the block's 6 x 10 x 10 surfels
  CHECK(max_difference == 0.0);
}

TEST_CASE("a zero II vertex normal: the radius is named when it reaches across the part, not otherwise") {
  // A box of 10 x 6 x 20 voxels: 6 across at its thinnest, so radii from 3 voxels reach across it.
  const VoxelGrid grid =
      voxels({14, 10, 24}, [](int x, int y, int z) { return x >= 2 && x < 12 && y >= 2 && y < 8 && z >= 2 && z < 22; });
  const SurfelMesh mesh = extract_surface(grid);
  Eigen::MatrixX3d normals = Eigen::MatrixX3d::Zero(mesh.num_vertices(), 3);
  normals.col(0).setOnes();
  IIParams small;  // alpha = 1: k is the radius in voxels
  small.alpha = 1.0;
  small.k = 2.0;
  IIParams wide = small;
  wide.k = 3.0;
  CHECK_NOTHROW(detail::check_ii_vertex_normals(mesh, normals, small));
  normals.row(5).setZero();
  normals.row(9).setZero();
  const auto error_of = [&](const IIParams& ii) -> std::pair<std::string, std::string> {
    try {
      detail::check_ii_vertex_normals(mesh, normals, ii);
    } catch (const InputError& e) {
      return {e.parameter(), e.what()};
    }
    return {"(no error)", ""};
  };
  const auto below = error_of(small);
  CHECK(below.first == "normals");
  CHECK(below.second.find("normal of vertex 5 (and of 1 other vertices) is the zero vector") != std::string::npos);
  CHECK(below.second.find("less than half the part it lies on (10 x 6 x 20 voxels)") != std::string::npos);
  CHECK(below.second.find("the radius is not what makes them cancel") != std::string::npos);
  const auto across = error_of(wide);
  CHECK(across.first == "ii_radius");
  CHECK(across.second.find("exceeds the part it lies on (10 x 6 x 20 voxels, 6 across at its thinnest)") !=
        std::string::npos);
  CHECK(across.second.find("a radius below 3 voxels") != std::string::npos);
}

// docs/math.md §7.2: where the ball reaches across a part thinner than itself, the surfel is
// estimated again with smaller balls.
namespace {
// A rod of radius 1.6 voxels around the segment a-b, tilted off the axes, in a 48^3 box (h = 1).
const Eigen::Vector3d kRodA(8, 10, 7), kRodB(40, 34, 39);
double rod_distance(const Eigen::Vector3d& p) {
  const Eigen::Vector3d d = (kRodB - kRodA).normalized();
  const double t = std::clamp((p - kRodA).dot(d), 0.0, (kRodB - kRodA).norm());
  return (p - kRodA - t * d).norm();
}
// Mean angle (degrees) between the normals of the faces away from the rod's ends and the radial
// direction from the axis at their centroids.
double rod_angle_error(const SurfelMesh& mesh, const Eigen::MatrixX3d& n) {
  const Eigen::Vector3d d = (kRodB - kRodA).normalized();
  const Eigen::MatrixX3d c = mesh.face_centroids();
  double sum = 0.0;
  int count = 0;
  for (Eigen::Index f = 0; f < c.rows(); ++f) {
    const Eigen::Vector3d p = c.row(f).transpose();
    const double t = (p - kRodA).dot(d);
    if (t < 4.0 || t > (kRodB - kRodA).norm() - 4.0) continue;
    const Eigen::Vector3d radial = (p - kRodA - t * d).normalized();
    sum += std::acos(std::clamp(n.row(f).dot(radial), -1.0, 1.0)) * deg;
    ++count;
  }
  return sum / count;
}
}  // namespace

TEST_CASE("ii normals on a rod thinner than the ball: the shrunk balls see the rod's own side") {
  const VoxelGrid grid = voxels(Eigen::Vector3i(48, 48, 48),
                                [](int x, int y, int z) { return rod_distance(Eigen::Vector3d(x, y, z)) <= 1.6; });
  const SurfelMesh mesh = extract_surface(grid);
  IIParams fixed{.k = 4.0, .alpha = 1.0};
  IIParams shrink = fixed;
  shrink.shrink_on_thin_parts = true;
  const double before = rod_angle_error(mesh, ii_face_normals(grid, mesh, fixed));
  const Eigen::MatrixX3d n = ii_face_normals(grid, mesh, shrink);
  const double after = rod_angle_error(mesh, n);
  // The radius a user would have to pick for this rod by hand: one that fits inside it.
  IIParams fits{.k = 1.5, .alpha = 1.0};
  const double by_hand = rod_angle_error(mesh, ii_face_normals(grid, mesh, fits));
  MESSAGE("rod: mean angle to the radial direction " << before << " deg with a 4-voxel ball, " << after
                                                     << " deg shrunk, " << by_hand << " deg with 1.5 voxels");
  CHECK(after < 0.6 * before);
  // The readable form of the moments gives the same normals (the shrinking is shared).
  const Eigen::MatrixX3d brute = ii_face_normals(grid, mesh, shrink, IIMethod::BruteForce);
  CHECK((brute - n).cwiseAbs().maxCoeff() < 1e-9);
  for (Eigen::Index f = 0; f < n.rows(); ++f) {
    REQUIRE(std::abs(n.row(f).norm() - 1.0) < 1e-12);
    REQUIRE(n.row(f).dot(mesh.surfels[std::size_t(f)].trivial_normal()) > 0.0);
  }
}

TEST_CASE("ii normals of a thick object do not change when shrinking is on") {
  const VoxelGrid grid = voxels(Eigen::Vector3i(40, 40, 40), [](int x, int y, int z) {
    return (Eigen::Vector3d(x, y, z) - Eigen::Vector3d(19.3, 20.1, 19.6)).norm() <= 13.0;
  });
  const SurfelMesh mesh = extract_surface(grid);
  IIParams fixed{.k = 4.0, .alpha = 1.0};
  IIParams shrink = fixed;
  shrink.shrink_on_thin_parts = true;
  CHECK(ii_face_normals(grid, mesh, shrink) == ii_face_normals(grid, mesh, fixed));
}

TEST_CASE("ii normals of an object smaller than the ball: refused at a fixed radius, shrunk otherwise") {
  const VoxelGrid grid = voxels(Eigen::Vector3i(8, 8, 8), [](int x, int y, int z) {
    return x >= 3 && x <= 4 && y == 3 && z == 3;  // two voxels
  });
  const SurfelMesh mesh = extract_surface(grid);
  IIParams fixed{.k = 4.0, .alpha = 1.0};
  CHECK_THROWS_WITH_AS(ii_face_normals(grid, mesh, fixed), doctest::Contains("covers all of it"), InputError);
  IIParams shrink = fixed;
  shrink.shrink_on_thin_parts = true;
  const Eigen::MatrixX3d n = ii_face_normals(grid, mesh, shrink);
  REQUIRE(n.rows() == mesh.num_faces());
  for (Eigen::Index f = 0; f < n.rows(); ++f) {
    CHECK(std::abs(n.row(f).norm() - 1.0) < 1e-12);
    CHECK(n.row(f).dot(mesh.surfels[std::size_t(f)].trivial_normal()) > 0.0);
  }
}

TEST_CASE("ii_start_radius: an object smaller than the ball starts below its size, only when shrinking") {
  const double across = 2.0 * std::sqrt(3.0);  // a 2-voxel cube's diagonal
  const IIStartRadius speck = ii_start_radius(4.0, across, true);
  CHECK(speck.smaller_than_ball);
  CHECK(speck.radius == doctest::Approx(kIIShrinkFactor * across).epsilon(1e-15));
  const IIStartRadius kept = ii_start_radius(4.0, across, false);
  CHECK_FALSE(kept.smaller_than_ball);
  CHECK(kept.radius == 4.0);
  CHECK_FALSE(ii_start_radius(4.0, 10.0, true).smaller_than_ball);
  CHECK(ii_start_radius(4.0, 10.0, true).radius == 4.0);
  // One voxel or less across: nothing smaller to start from.
  CHECK_FALSE(ii_start_radius(4.0, 1.0, true).smaller_than_ball);
  // A ball of 1.2 voxels on a 1.5-voxel object starts at one voxel, not below.
  CHECK(ii_start_radius(1.2, 1.2, true).radius == 1.0);
}
