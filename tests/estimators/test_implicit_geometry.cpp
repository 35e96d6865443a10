// Distances to an implicit surface and its mean curvature (estimators/implicit_normals.hpp), against
// closed forms on the unit sphere and the torus (R = 6, r = 2, docs/math.md §1.1).
#include <doctest/doctest.h>

#include <cmath>
#include <corrlap/estimators/implicit_normals.hpp>

using namespace corrlap;

TEST_CASE("distances_to_surface: exact on spheres, Newton projection on the torus") {
  const ImplicitShape sphere = make_implicit_shape("sphere1", Eigen::Vector3d(0.1, -0.2, 0.3));
  Eigen::MatrixX3d p(3, 3);
  p << 0.1, -0.2, 1.8, 1.6, -0.2, 0.3, 0.1, 0.3, 0.3;  // 1.5 above, 0.5 outside, 0.5 inside
  const Eigen::VectorXd d = distances_to_surface(sphere, p);
  CHECK(d[0] == doctest::Approx(0.5).epsilon(1e-14));
  CHECK(d[1] == doctest::Approx(0.5).epsilon(1e-14));
  CHECK(d[2] == doctest::Approx(0.5).epsilon(1e-14));
  // Torus, on its equator plane (z = 0), where the Newton steps follow the radial line: the distance
  // to the tube is | |rho - R| - r |, rho = sqrt(x^2 + y^2). (Off such lines the Newton projection
  // is not the closest point; the distance it gives is then slightly larger.)
  const ImplicitShape torus = make_implicit_shape("torus");
  Eigen::MatrixX3d q(3, 3);
  q << 9.0, 0.0, 0.0, 0.0, 6.5, 0.0, 5.0 * std::cos(0.3), 5.0 * std::sin(0.3), 0.0;
  const Eigen::VectorXd dt = distances_to_surface(torus, q);
  CHECK(dt[0] == doctest::Approx(1.0).epsilon(1e-9));
  CHECK(dt[1] == doctest::Approx(1.5).epsilon(1e-9));
  CHECK(dt[2] == doctest::Approx(1.0).epsilon(1e-9));  // inside the tube
}

TEST_CASE("true_mean_curvatures: H = 1 on the unit sphere, (k1 + k2) / 2 on the torus") {
  const ImplicitShape sphere = make_implicit_shape("sphere1");
  Eigen::MatrixX3d p(2, 3);
  p << 0.0, 0.0, 1.3, 0.6, 0.0, 0.0;  // projected onto the sphere first
  const Eigen::VectorXd H = true_mean_curvatures(sphere, p);
  CHECK(H[0] == doctest::Approx(1.0).epsilon(1e-9));
  CHECK(H[1] == doctest::Approx(1.0).epsilon(1e-9));
  // Torus, outward normals: outer equator k = 1/r and 1/(R + r); inner equator 1/r and -1/(R - r);
  // top circle (rho = R, z = r) 1/r and 0.
  const ImplicitShape torus = make_implicit_shape("torus");
  Eigen::MatrixX3d q(3, 3);
  q << 8.0, 0.0, 0.0, 0.0, -4.0, 0.0, 6.0, 0.0, 2.0;
  const Eigen::VectorXd Ht = true_mean_curvatures(torus, q);
  CHECK(Ht[0] == doctest::Approx((0.5 + 1.0 / 8.0) / 2.0).epsilon(1e-9));
  CHECK(Ht[1] == doctest::Approx((0.5 - 1.0 / 4.0) / 2.0).epsilon(1e-9));
  CHECK(Ht[2] == doctest::Approx(0.25).epsilon(1e-9));
}
