// Loop subdivision (surface/loop_subdivision.hpp): counts and topology, the interior and boundary
// masks computed by hand, affine invariance, refusal of non-manifold edges.
#include <doctest/doctest.h>

#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/surface/loop_subdivision.hpp>

#include "surface/icosahedron.hpp"

using namespace corrlap;
using corrlap::test::icosahedron;

namespace {
TriangleMesh tetrahedron() {
  TriangleMesh m;
  m.positions.resize(4, 3);
  m.positions << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  m.triangles.resize(4, 3);
  m.triangles << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3;
  return m;
}
}  // namespace

TEST_CASE("loop subdivision: V + E vertices, 4T triangles, Euler characteristic kept") {
  TriangleMesh m = icosahedron();
  for (int step = 0; step < 3; ++step) {
    const Eigen::Index v = m.positions.rows(), t = m.triangles.rows(), e = 3 * t / 2;
    m = loop_subdivide(m);
    CHECK(m.positions.rows() == v + e);
    CHECK(m.triangles.rows() == 4 * t);
    CHECK(m.positions.rows() - 3 * m.triangles.rows() / 2 + m.triangles.rows() == 2);
  }
  TriangleMesh r = icosahedron();
  CHECK(loop_refine(r, 0) == 0);
  CHECK(loop_refine(r, 2500) == 4);
  CHECK(r.positions.rows() == 2562);
  TriangleMesh big = icosahedron();
  CHECK_THROWS_WITH_AS(loop_refine(big, 100000000), doctest::Contains("more than 8"), InputError);
}

TEST_CASE("loop subdivision: Loop's masks on a tetrahedron (valence 3: beta = 3/16)") {
  const TriangleMesh m = tetrahedron();
  const TriangleMesh s = loop_subdivide(m);
  // Old vertex 0: (1 - 3 beta) v0 + beta (v1 + v2 + v3), beta = (5/8 - (3/8 + cos(2 pi/3)/4)^2)/3 = 3/16.
  const Eigen::RowVector3d v0 =
      7.0 / 16.0 * m.positions.row(0) + 3.0 / 16.0 * (m.positions.row(1) + m.positions.row(2) + m.positions.row(3));
  CHECK((s.positions.row(0) - v0).norm() < 1e-15);
  // Edge (0, 1), opposite vertices 2 and 3: 3/8 (v0 + v1) + 1/8 (v2 + v3), wherever it is stored.
  const Eigen::RowVector3d e01 =
      0.375 * (m.positions.row(0) + m.positions.row(1)) + 0.125 * (m.positions.row(2) + m.positions.row(3));
  bool found = false;
  for (Eigen::Index v = 4; v < s.positions.rows(); ++v) found = found || (s.positions.row(v) - e01).norm() < 1e-15;
  CHECK(found);
}

TEST_CASE("loop subdivision: boundary curves refine as cubic B-splines, affine maps commute") {
  TriangleMesh one;
  one.positions.resize(3, 3);
  one.positions << 0, 0, 0, 2, 0, 0, 0, 2, 0;
  one.triangles.resize(1, 3);
  one.triangles << 0, 1, 2;
  const TriangleMesh s = loop_subdivide(one);
  REQUIRE(s.positions.rows() == 6);
  // Corner 0: 3/4 v0 + 1/8 (v1 + v2); edge points are midpoints.
  CHECK((s.positions.row(0) - Eigen::RowVector3d(0.25, 0.25, 0)).norm() < 1e-15);
  for (Eigen::Index v = 3; v < 6; ++v) {
    const Eigen::RowVector3d p = s.positions.row(v);
    const bool midpoint = (p - Eigen::RowVector3d(1, 0, 0)).norm() < 1e-15 ||
                          (p - Eigen::RowVector3d(0, 1, 0)).norm() < 1e-15 ||
                          (p - Eigen::RowVector3d(1, 1, 0)).norm() < 1e-15;
    CHECK(midpoint);
  }
  // The masks are affine combinations: subdividing a transformed mesh = transforming the result.
  Eigen::Matrix3d A;
  A << 2, 0.5, 0, -0.3, 1, 0.2, 0.1, 0, 3;
  const Eigen::RowVector3d b(0.7, -1, 2);
  TriangleMesh ico = icosahedron(), moved = icosahedron();
  moved.positions = (moved.positions * A.transpose()).rowwise() + b;
  const TriangleMesh s1 = loop_subdivide(ico), s2 = loop_subdivide(moved);
  CHECK(s2.triangles == s1.triangles);
  CHECK(((s1.positions * A.transpose()).rowwise() + b - s2.positions).cwiseAbs().maxCoeff() < 1e-13);
}

TEST_CASE("loop subdivision: an edge with three triangles, or a repeated vertex, is refused by name") {
  TriangleMesh fan;
  fan.positions.resize(5, 3);
  fan.positions << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1;
  fan.triangles.resize(3, 3);
  fan.triangles << 0, 1, 2, 1, 0, 3, 0, 1, 4;
  CHECK_THROWS_WITH_AS(loop_subdivide(fan), doctest::Contains("edge (0, 1) has 3 triangles"), InputError);
  fan.triangles.resize(1, 3);
  fan.triangles << 0, 0, 1;
  CHECK_THROWS_WITH_AS(loop_subdivide(fan), doctest::Contains("repeats a vertex"), InputError);
  fan.triangles << 0, 1, 9;
  CHECK_THROWS_WITH_AS(loop_subdivide(fan), doctest::Contains("missing vertex"), InputError);
}
