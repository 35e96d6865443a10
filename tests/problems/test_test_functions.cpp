// Test functions of docs/math.md §10.2 and the Poisson / forward evaluations of docs/math.md §10.3-§10.4 built on them.
#include <doctest/doctest.h>

#include <cmath>
#include <corrlap/corrlap.hpp>
#include <random>

using namespace corrlap;

namespace {
// Laplacian on S^2 by finite differences: for the degree-0 extension F(x) = f(x/|x|), the radial
// derivatives vanish and Delta_{S^2} f = Delta_{R^3} F on |x| = 1. Central differences of step eps:
// truncation eps^2/12 sum |d^4 F| and rounding ~ 4 ulp |F| / eps^2.
double fd_laplacian(const TestFunction& t, const Eigen::Vector3d& q, double eps) {
  auto F = [&](const Eigen::Vector3d& x) { return t.value(x.normalized()); };
  double sum = 0.0;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d e = eps * Eigen::Vector3d::Unit(i);
    sum += (F(q + e) - 2.0 * F(q) + F(q - e)) / (eps * eps);
  }
  return sum;
}
}  // namespace

TEST_CASE("test functions: names, exact values at points, errors listing the names") {
  std::vector<std::string> names;
  for (const auto& t : test_functions()) names.push_back(t.name);
  CHECK(names == std::vector<std::string>{"x2", "expx", "p6"});
  const Eigen::Vector3d ex(1, 0, 0), ez(0, 0, 1);
  const Eigen::Vector3d d = Eigen::Vector3d(1, 2, 2) / 3.0;
  // Delta(x^2) = 2 - 6x^2 exactly (docs/math.md §10.2).
  CHECK(test_function("x2").laplacian(ex) == -4.0);
  CHECK(test_function("x2").laplacian(ez) == 2.0);
  CHECK(test_function("x2").laplacian(d) == doctest::Approx(2.0 - 6.0 / 9.0).epsilon(1e-15));
  CHECK(test_function("expx").laplacian(ex) == doctest::Approx(-2.0 * M_E).epsilon(1e-15));
  CHECK(test_function("expx").laplacian(ez) == 1.0);
  // P6(1) = 1, P6(0) = -5/16; degree 6: Delta = -6*7 = -42.
  CHECK(test_function("p6").value(ez) == 1.0);
  CHECK(test_function("p6").value(ex) == -5.0 / 16.0);
  CHECK(test_function("p6").laplacian(ez) == -42.0);
  CHECK(has_test_function("p6"));
  CHECK(!has_test_function("x3"));
  CHECK_THROWS_WITH_AS(test_function("x3"), doctest::Contains("unknown test function 'x3'; available: x2 expx p6"),
                       InputError);
}

TEST_CASE("test functions: the Laplacians agree with finite differences on the sphere") {
  std::mt19937 rng(7);
  std::normal_distribution<double> g;
  const double eps = 1e-4;
  for (const auto& t : test_functions()) {
    CAPTURE(t.name);
    double worst = 0.0;
    for (int k = 0; k < 200; ++k) {
      const Eigen::Vector3d q = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
      worst = std::max(worst, std::abs(fd_laplacian(t, q, eps) - t.laplacian(q)));
    }
    // eps = 1e-4: truncation ~1e-6 for P6 (4th derivatives O(1e3)), rounding of F (normalization
    // included) a few 1e-16 / eps^2 ~ 1e-7. Measured worst: 2e-7 (x2), 3e-7 (expx), 1.3e-6 (p6).
    // A wrong formula is off by O(1).
    CHECK(worst < 1e-5);
  }
}

TEST_CASE("sample_on_unit_sphere projects radially from the centre") {
  Eigen::MatrixX3d x(2, 3);
  x << 3.0, 0.0, 0.0, 1.0, 1.0, 2.0;
  const Eigen::Vector3d c(1.0, 1.0, 0.0);
  const TestFunctionSamples s = sample_on_unit_sphere(test_function("x2"), x, c);
  // (2, -1, 0)/sqrt(5) and (0, 0, 1)
  CHECK(s.f[0] == doctest::Approx(0.8).epsilon(1e-15));
  CHECK(s.laplacian[0] == doctest::Approx(2.0 - 4.8).epsilon(1e-15));
  CHECK(s.f[1] == 0.0);
  CHECK(s.laplacian[1] == 2.0);
  x.row(1) = c.transpose();
  CHECK_THROWS_WITH_AS(sample_on_unit_sphere(test_function("x2"), x, c), doctest::Contains("vertex 1"), InputError);
}

namespace {
struct Case {
  SurfelMesh mesh;
  NormalFields radial;  // docs/math.md §12.3/§12.5: u_v = x_v/|x_v|, u_f = b_f/|b_f|
};
Case sphere(double h) {
  const ImplicitShape shape = make_implicit_shape("sphere1");
  Case c;
  c.mesh = extract_surface(digitize(shape, {.h = h, .min_aabb = -2, .max_aabb = 2}));
  c.radial.face = true_face_normals(shape, c.mesh);
  c.radial.vertex = exact_vertex_normals(shape, c.mesh);
  return c;
}
}  // namespace

TEST_CASE("solve_poisson and forward_error reproduce the evaluation table of docs/math.md §12.5") {
  const Case c2 = sphere(0.2), c1 = sphere(0.1);
  auto solver = make_linear_solver();
  // The table prints 3 significant digits: compare at half a unit of the third digit (0.5 %).
  const double tol = 0.005;
  const Operators fem2 = corrected_fem(c2.mesh, c2.radial.face), fem1 = corrected_fem(c1.mesh, c1.radial.face);
  const Operators cc2 = interpolated(c2.mesh, c2.radial.vertex), cc1 = interpolated(c1.mesh, c1.radial.vertex);
  const TestFunction &x2 = test_function("x2"), &expx = test_function("expx"), &p6 = test_function("p6");
  // Backward L2 (docs/math.md §10.4).
  const PoissonResult r = solve_poisson(fem2, c2.mesh.positions, x2, *solver);
  CHECK(r.errors.l2 == doctest::Approx(0.0204).epsilon(tol));
  CHECK(r.residual < 1e-12);
  CHECK(r.g[0] == r.f[0]);  // the pinned vertex
  CHECK(solve_poisson(fem1, c1.mesh.positions, x2, *solver).errors.l2 == doctest::Approx(0.00483).epsilon(tol));
  CHECK(solve_poisson(cc2, c2.mesh.positions, x2, *solver).errors.l2 == doctest::Approx(0.0185).epsilon(tol));
  CHECK(solve_poisson(cc2, c2.mesh.positions, expx, *solver).errors.l2 == doctest::Approx(0.0317).epsilon(tol));
  CHECK(solve_poisson(cc2, c2.mesh.positions, p6, *solver).errors.l2 == doctest::Approx(0.0762).epsilon(tol));
  // Forward L_inf (docs/math.md §10.3): naive (dt = 0) and diffused (dt = 0.035 h).
  CHECK(forward_error(fem2, c2.mesh.positions, x2, *solver).linf == doctest::Approx(2.93).epsilon(tol));
  CHECK(forward_error(cc2, c2.mesh.positions, x2, *solver, 0.035 * 0.2).linf == doctest::Approx(0.371).epsilon(tol));
  CHECK(forward_error(cc2, c2.mesh.positions, expx, *solver, 0.035 * 0.2).linf == doctest::Approx(0.409).epsilon(tol));
  CHECK(forward_error(cc2, c2.mesh.positions, p6, *solver, 0.035 * 0.2).linf == doctest::Approx(6.53).epsilon(tol));
  CHECK(forward_error(cc1, c1.mesh.positions, x2, *solver, 0.035 * 0.1).linf == doctest::Approx(0.173).epsilon(tol));
  CHECK(forward_error(fem2, c2.mesh.positions, expx, *solver, 0.035 * 0.2).linf == doctest::Approx(0.584).epsilon(tol));
  // Bad input: dt < 0, operators on faces.
  CHECK_THROWS_AS(forward_error(fem2, c2.mesh.positions, x2, *solver, -1.0), InputError);
  const Operators hk = heat_kernel(c2.mesh, c2.radial.face);
  CHECK_THROWS_WITH_AS(solve_poisson(hk, c2.mesh.positions, x2, *solver), doctest::Contains("on faces"), InputError);
}
