// Nothing wrong leaves the regularization: its options are checked before any computation (an
// alpha0 beyond what double precision holds, a method on faces), and every result is checked
// against its input (finite, not collapsed, the solve's residual) with the numbers in the error.
#include <doctest/doctest.h>

#include <chrono>
#include <cmath>
#include <corrlap/corrlap.hpp>
#include <filesystem>
#include <limits>

#include "regularization/sphere_fixture.hpp"
#include "test_support.hpp"

using namespace corrlap;

namespace {

// The InputError's parameter and message of f(), or "" when it does not throw one.
template <class F>
std::pair<std::string, std::string> input_error(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return {e.parameter(), e.what()};
  }
  return {};
}

}  // namespace

TEST_CASE("alpha0: the paper's range 0.01..1000 passes the solution check with every vertex method on sphere1") {
  const test::RegularizationSphere& s = test::regularization_sphere();
  RegularizationOptions o;
  const RegularizationCurvature curvature = regularization_curvature(s.mesh, s.normals, o);
  for (const char* method : {"fem", "interpolated", "polydec", "projected-polydec", "vrm", "corrected-vrm", "cotan"})
    for (const double alpha0 : {0.01, 1000.0}) {
      o.method = method;
      o.alpha0 = alpha0;
      const RegularizedSurface r = regularize_surface(s.mesh, s.normals, o, &curvature);
      INFO(method << ", alpha0 = " << alpha0 << ": " << r.check.describe());
      CHECK(r.check.area_ratio > kMinAreaRatio);
      CHECK(r.check.area_ratio < kMaxAreaRatio);
      CHECK(r.check.extent_ratio > kMinExtentRatio);
      if (r.solve_scheme == "preconditioned-cg") {
        // Stopped at a proven accuracy: the bound replaces the residual test.
        CHECK(!r.check.residual);
        CHECK(r.solve_error_bound > 0.0);
        CHECK(r.solve_error_bound <= o.solve_accuracy);
      } else {
        REQUIRE(r.check.residual);
        CHECK(*r.check.residual < kMaxResidual);
      }
    }
  // Solved to rounding, the residual is checked.
  o.method = "fem";
  o.alpha0 = 10.0;
  o.solve_accuracy = 0.0;
  const RegularizedSurface r = regularize_surface(s.mesh, s.normals, o, &curvature);
  CHECK(r.solve_scheme == "preconditioned-cg");
  REQUIRE(r.check.residual);
  CHECK(*r.check.residual < 1e-9);
}

TEST_CASE("alpha0 too large to be represented (1e300, 1e160) is refused before solving, naming the range") {
  const test::RegularizationSphere& s = test::regularization_sphere();
  for (const double alpha0 : {1e300, 1e160}) {
    RegularizationOptions o;
    o.alpha0 = alpha0;
    // Refused by the check alone (no curvature, no operators), and by regularize_surface the same way.
    const auto [parameter, message] = input_error([&] { check_regularization_options(s.mesh, o); });
    CHECK(parameter == "alpha0");
    CHECK(message.find("beyond what the solve represents in double precision") != std::string::npos);
    CHECK(message.find("the paper uses 0.01 to 1000") != std::string::npos);
    CHECK(input_error([&] { (void)regularize_surface(s.mesh, s.normals, o); }).second == message);
  }
  // The largest alpha0 the message names is solvable: the bound is not beyond the check's range.
  RegularizationOptions o;
  o.alpha0 = 1e300;
  const std::string message = input_error([&] { check_regularization_options(s.mesh, o); }).second;
  const std::size_t at = message.find("alpha0 up to ");
  REQUIRE(at != std::string::npos);
  o.alpha0 = std::stod(message.substr(at + 13));
  CHECK(input_error([&] { check_regularization_options(s.mesh, o); }).first.empty());
  o.alpha0 *= 1.01;
  CHECK(input_error([&] { check_regularization_options(s.mesh, o); }).first == "alpha0");
}

TEST_CASE("every real option is validated in the library, naming its parameter") {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  const auto parameter = [](const RegularizationOptions& o) {
    return input_error([&] { check_regularization_options(o); }).first;
  };
  for (const double bad : {0.0, -1.0, nan, inf}) {
    CAPTURE(bad);
    RegularizationOptions o;
    o.alpha0 = bad;
    CHECK(parameter(o) == (bad == 0.0 ? "" : "alpha0"));  // 0: no attachment (docs/math.md §9.3)
    o = {};
    o.size = bad;
    CHECK(parameter(o) == "size");
    o = {};
    o.curvature_radius = bad;
    CHECK(parameter(o) == "curvature_radius");
    o = {};
    o.alpha_step = bad;
    CHECK(parameter(o) == "alpha_step");
    o = {};
    o.normal_attachment = bad;
    CHECK(parameter(o) == "normal_attachment");
  }
  for (const double bad : {-1.0, nan, inf}) {
    RegularizationOptions o;
    o.h_clamp = bad;
    CHECK(parameter(o) == "h_clamp");
  }
  RegularizationOptions o;
  o.h_scale = nan;
  CHECK(parameter(o) == "h_scale");
  o = {};
  o.k2_edit = {PrincipalCurvatureEdit::Kind::Scale, inf};
  CHECK(parameter(o) == "k2");
  o = {};
  o.method = "polydec";
  o.method_params.set("lambda", -1.0);
  CHECK(parameter(o) == "lambda");
  o = {};
  o.h_scale = -2.0;  // a sign flip is an edit, not an error
  o.h_clamp = 0.0;
  CHECK(parameter(o).empty());
}

TEST_CASE("a method whose operators live on faces is refused up front, naming those that can") {
  RegularizationOptions o;
  o.method = "heat-kernel";
  const auto [parameter, message] = input_error([&] { check_regularization_options(o); });
  CHECK(parameter == "method");
  CHECK(message.find("'heat-kernel' defines its operators on faces") != std::string::npos);
  for (const char* able : {"fem", "interpolated", "polydec", "cotan"}) CHECK(message.find(able) != std::string::npos);
  CHECK(message.find("or heat-kernel with variant=primal") != std::string::npos);
  o.method_params.set("variant", "primal");
  CHECK(input_error([&] { check_regularization_options(o); }).first.empty());
}

TEST_CASE("check_solution: a collapsed, blown-up, non-finite or inexact result fails with its numbers") {
  const SurfelMesh& mesh = test::regularization_sphere().mesh;
  const SolutionCheck same = check_solution(mesh, mesh.positions, 1e-12, "test");
  CHECK(same.area_ratio == doctest::Approx(1.0));
  CHECK(same.extent_ratio == doctest::Approx(1.0));
  // Every vertex at the origin (what alpha0 = 1e300 used to give), a shrunk copy, a flattened one.
  const auto message = [&](const Eigen::MatrixX3d& q, std::optional<double> residual) -> std::string {
    try {
      (void)check_solution(mesh, q, residual, "test");
    } catch (const NumericalError& e) {
      return e.what();
    }
    return "no error";
  };
  CHECK(message(Eigen::MatrixX3d::Zero(mesh.num_vertices(), 3), 0.0)
            .find("test: the result collapsed (area ratio 0, extent ratio 0, residual 0;") != std::string::npos);
  CHECK(message(0.3 * mesh.positions, std::nullopt).find("collapsed (area ratio 0.09, extent ratio 0.3;") !=
        std::string::npos);
  Eigen::MatrixX3d flat = mesh.positions;
  flat.col(2) *= 0.1;
  CHECK(message(flat, std::nullopt).find("collapsed") != std::string::npos);
  CHECK(message(3.0 * mesh.positions, std::nullopt).find("blew up (area ratio 9,") != std::string::npos);
  Eigen::MatrixX3d nan = mesh.positions;
  nan(5, 1) = std::nan("");
  CHECK(message(nan, 0.0).find("the position of vertex 5 is not finite") != std::string::npos);
  CHECK(message(mesh.positions, 1e-2)
            .find("is not the solution of its system (area ratio 1, extent ratio 1, residual "
                  "0.01;") != std::string::npos);
  CHECK(message(mesh.positions, std::nan("")).find("is not the solution") != std::string::npos);
}

#ifdef CORRLAP_CLI
namespace {
// ico3: the icosahedron subdivided three times on the unit sphere (642 vertices), the input.
std::string ico3() {
  const std::string obj = test::tmp_path("solution_check_ico3.obj");
  if (!std::filesystem::exists(obj)) write_mesh(obj, test::icosphere(3));
  return obj;
}
}  // namespace

TEST_CASE("corrlap reconstruct / regularize --alpha0 1e300: exit 1 naming --alpha0, before writing anything") {
  const std::string dir = test::tmp_path("solution_check_alpha_reconstruct");
  std::filesystem::remove_all(dir);
  std::string err;
  CHECK(test::run_cli("reconstruct --mesh-file " + ico3() + " --resolution 8 --subdivide 1 --alpha0 1e300 --out " + dir,
                      nullptr, &err) == 1);
  CHECK(err.find("corrlap: error: regularization: alpha0 = 1e+300 gives alpha") != std::string::npos);
  CHECK(err.find("(--alpha0)") != std::string::npos);
  CHECK_FALSE(std::filesystem::exists(dir));

  const std::string out = test::tmp_path("solution_check_alpha_regularize");
  std::filesystem::remove_all(out);
  CHECK(test::run_cli("regularize --shape sphere1 --h 0.2 --bbox -1.5 1.5 --alpha0 1e300 --out " + out, nullptr,
                      &err) == 1);
  CHECK(err.find("regularization: alpha0 = 1e+300") != std::string::npos);
  CHECK(err.find("(--alpha0)") != std::string::npos);
  CHECK_FALSE(std::filesystem::exists(out));
}

TEST_CASE("corrlap reconstruct --methods heat-kernel: refused before any computation") {
  const std::string dir = test::tmp_path("solution_check_heat_kernel");
  std::filesystem::remove_all(dir);
  std::string err;
  const auto start = std::chrono::steady_clock::now();
  CHECK(test::run_cli("reconstruct --mesh-file " + ico3() +
                          " --resolution 8 --subdivide 1 --methods fem,heat-kernel "
                          "--out " +
                          dir,
                      nullptr, &err) == 1);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  MESSAGE("refused in " << seconds << " s");
  CHECK(err.find("method 'heat-kernel' defines its operators on faces") != std::string::npos);
  CHECK(err.find("or heat-kernel with variant=primal") != std::string::npos);
  // Before the voxelization: its report line never came, and nothing was written.
  CHECK(err.find("voxelized at") == std::string::npos);
  CHECK_FALSE(std::filesystem::exists(dir));
}
TEST_CASE("a one-voxel volume: the II ball covers the object, named as such, not as flipped normals") {
  const std::string vol = test::tmp_path("solution_check_one_voxel.vol");
  test::write_text(vol, std::string("X: 1\nY: 1\nZ: 1\nVoxel-Size: 1\nAlpha-Color: 0\nVersion: 2\n.\n") + '\xff');
  const std::string dir = test::tmp_path("solution_check_one_voxel");
  std::string err;
  // By default the II balls shrink below the object's size (docs/math.md §7.2), and what stops the
  // run is the speck's own curvature: a voxel is a ball of about half a voxel.
  CHECK(test::run_cli("regularize --volume " + vol + " --threshold 0 --no-render --out " + dir, nullptr, &err) == 1);
  CHECK(err.find("voxels across (its bounding box's diagonal), too small for a surface to be regularized") !=
        std::string::npos);
  CHECK(err.find("(--h-clamp)") != std::string::npos);
  // With the radius kept, 4 voxels is wider than the whole box (the voxel and its padding).
  CHECK(test::run_cli("regularize --volume " + vol + " --threshold 0 --ii-thin-parts keep --no-render --out " + dir,
                      nullptr, &err) == 1);
  CHECK(err.find("II normals: digital radius r/h = 4.000000 is larger than the volume (3 voxels)") !=
        std::string::npos);
  CHECK(err.find("give a smaller ii_radius (while r/h stays at least 1) (--ii-radius)") != std::string::npos);
  // 1.9 voxels fits in the box and still holds the voxel from every surfel.
  CHECK(test::run_cli("regularize --volume " + vol +
                          " --threshold 0 --ii-radius 1.9 --ii-thin-parts keep --no-render --out " + dir,
                      nullptr, &err) == 1);
  CHECK(err.find("II normals: the object is 1.73205 voxels across") != std::string::npos);
  CHECK(err.find("use a smaller ii_radius (while r/h stays at least 1) or a finer resolution (--ii-radius)") !=
        std::string::npos);
  // A radius between one voxel and the diagonal passes that check; the normals still lie in the
  // surfels' planes, and the operators say what that means for estimated normals.
  CHECK(test::run_cli("operators --volume " + vol +
                          " --threshold 0 --method fem --ii-radius 1.5 --ii-thin-parts keep --out " + dir,
                      nullptr, &err) == 1);
  CHECK(err.find("point inward or lie in the surfels' planes") != std::string::npos);
  CHECK(err.find("estimated ones did not see the surface") != std::string::npos);
}
#endif
