// Closest points on triangle meshes (surface/closest_point.hpp): the three regions of a triangle by
// hand, degenerate triangles, and the grid search against brute force on a sphere-like mesh.
#include <doctest/doctest.h>

#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/surface/closest_point.hpp>
#include <corrlap/surface/loop_subdivision.hpp>
#include <random>

#include "surface/icosahedron.hpp"

using namespace corrlap;

TEST_CASE("closest point on a triangle: interior, edge and vertex regions, degenerate triangles") {
  const Eigen::Vector3d a(0, 0, 0), b(2, 0, 0), c(0, 2, 0);
  ClosestPoint q = closest_point_on_triangle({0.5, 0.5, 3}, a, b, c);
  CHECK(q.distance == doctest::Approx(3).epsilon(1e-15));
  CHECK((q.barycentric - Eigen::Vector3d(0.5, 0.25, 0.25)).norm() < 1e-15);
  q = closest_point_on_triangle({1, -1, 0}, a, b, c);  // below edge ab
  CHECK(q.distance == doctest::Approx(1));
  CHECK((q.point - Eigen::Vector3d(1, 0, 0)).norm() < 1e-15);
  CHECK((q.barycentric - Eigen::Vector3d(0.5, 0.5, 0)).norm() < 1e-15);
  q = closest_point_on_triangle({3, -1, 1}, a, b, c);  // beyond vertex b
  CHECK(q.distance == doctest::Approx(std::sqrt(3.0)));
  CHECK((q.barycentric - Eigen::Vector3d(0, 1, 0)).norm() < 1e-15);
  q = closest_point_on_triangle({2, 2, 0}, a, b, c);  // beyond the hypotenuse
  CHECK(q.distance == doctest::Approx(std::sqrt(2.0)));
  // Collinear corners: the nearest point of the segment.
  q = closest_point_on_triangle({1, 1, 0}, a, b, Eigen::Vector3d(4, 0, 0));
  CHECK(q.distance == doctest::Approx(1));
  CHECK((q.point - Eigen::Vector3d(1, 0, 0)).norm() < 1e-15);
}

TEST_CASE("triangle locator: the grid search equals brute force, near and far from the surface") {
  TriangleMesh m = corrlap::test::icosahedron();
  loop_refine(m, 600);
  const TriangleLocator locator(m.positions, m.triangles);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1), r(0.0, 3.0);
  Eigen::MatrixX3d P(400, 3);
  for (Eigen::Index i = 0; i < P.rows(); ++i) {
    Eigen::Vector3d d(u(rng), u(rng), u(rng));
    // Most points near the surface (radius ~1.3-1.6 after subdivision), some far outside the grid.
    P.row(i) = (d.normalized() * (i % 10 == 0 ? 4.0 * r(rng) + 2.0 : 1.0 + 0.6 * u(rng))).transpose();
  }
  const std::vector<ClosestPoint> got = closest_points(locator, P);
  for (Eigen::Index i = 0; i < P.rows(); ++i) {
    const Eigen::Vector3d p = P.row(i);
    double best = INFINITY;
    for (Eigen::Index f = 0; f < m.triangles.rows(); ++f)
      best = std::min(
          best, closest_point_on_triangle(p, m.positions.row(m.triangles(f, 0)), m.positions.row(m.triangles(f, 1)),
                                          m.positions.row(m.triangles(f, 2)))
                    .distance);
    const ClosestPoint& g = got[std::size_t(i)];
    CAPTURE(i);
    CHECK(g.distance == doctest::Approx(best).epsilon(1e-12));
    REQUIRE(g.triangle >= 0);
    Eigen::Vector3d rebuilt = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) rebuilt += g.barycentric[k] * m.positions.row(m.triangles(g.triangle, k)).transpose();
    CHECK((rebuilt - g.point).norm() < 1e-12);
    CHECK(g.barycentric.sum() == doctest::Approx(1));
    CHECK(g.barycentric.minCoeff() >= 0);
  }
  CHECK_THROWS_WITH_AS(locator.closest(Eigen::Vector3d(NAN, 0, 0)), doctest::Contains("not finite"), InputError);
  CHECK_THROWS_WITH_AS(TriangleLocator(Eigen::MatrixX3d(0, 3), TriangleIndices(0, 3)), doctest::Contains("empty"),
                       InputError);
}
