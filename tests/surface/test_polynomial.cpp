// Polynomial parser and named shapes (docs/math.md §1.1).
#include <doctest/doctest.h>

#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/core/stopwatch.hpp>
#include <corrlap/surface/implicit_shape.hpp>
#include <string>

using namespace corrlap;

TEST_CASE("parser evaluates and differentiates") {
  const Polynomial p = Polynomial::parse("(x^2+y^2+z^2+6*6-2*2)^2-4*6*6*(x^2+y^2)");
  const Eigen::Vector3d q(1.5, -0.25, 2.0);
  const double r2 = q.squaredNorm();
  CHECK(p(q) == doctest::Approx((r2 + 32) * (r2 + 32) - 144 * (q.x() * q.x() + q.y() * q.y())));
  const Eigen::Vector3d g = p.gradient(q);
  const double eps = 1e-6;
  for (int a = 0; a < 3; ++a) {
    Eigen::Vector3d e = Eigen::Vector3d::Zero();
    e[a] = eps;
    CHECK(g[a] == doctest::Approx((p(q + e) - p(q - e)) / (2 * eps)).epsilon(1e-6));
  }
  CHECK(Polynomial::parse("2.5e-1*x - -y / 4")(Eigen::Vector3d(4, 8, 0)) == doctest::Approx(3.0));
  CHECK(Polynomial::parse("0.1*y*y -0.1*x*x - 2.0*z").total_degree() == 2);
}

TEST_CASE("parse errors name the position") {
  CHECK_THROWS_WITH_AS(Polynomial::parse("x^2+"), doctest::Contains("position"), InputError);
  CHECK_THROWS_WITH_AS(Polynomial::parse("x^y"), doctest::Contains("exponent"), InputError);
  CHECK_THROWS_WITH_AS(Polynomial::parse("(x+1"), doctest::Contains("')'"), InputError);
  CHECK_THROWS_WITH_AS(Polynomial::parse("x/y"), doctest::Contains("non-constant"), InputError);
  CHECK_THROWS_WITH_AS(Polynomial::parse("x # 2"), doctest::Contains("unexpected character"), InputError);
  CHECK_THROWS_AS(Polynomial::parse(""), InputError);
  CHECK_THROWS_WITH_AS(make_implicit_shape("spehre1"), doctest::Contains("sphere1"), InputError);
  CHECK_THROWS_AS(make_implicit_shape("3+4"), InputError);
}

TEST_CASE("every named shape parses and has a surface") {
  // A plain variable, not a structured binding: clang 14 cannot capture the latter (CAPTURE is a lambda).
  for (const auto& entry : named_shapes()) {
    const std::string& name = entry.first;
    CAPTURE(name);
    const ImplicitShape s = make_implicit_shape(name);
    CHECK(s.polynomial.total_degree() >= 2);
    // The parser limits leave a wide margin: the named shapes have degree at most 6.
    CHECK(s.polynomial.total_degree() <= 6);
  }
  CHECK(make_implicit_shape("sphere1").sphere_radius() == 1.0);
  CHECK(make_implicit_shape("sphere9").sphere_radius() == 9.0);
  CHECK(make_implicit_shape("torus").sphere_radius() == 0.0);
}

TEST_CASE("interval bounds enclose the values") {
  const Polynomial p = Polynomial::parse("-1*(8-0.03*x^4-0.03*y^4-0.03*z^4+2*x^2+2*y^2+2*z^2)");
  const Eigen::Vector3d lo(-1.2, 0.3, -4), hi(0.7, 2.1, -3.5);
  double mn, mx;
  p.bounds(lo, hi, mn, mx);
  for (int i = 0; i <= 10; ++i)
    for (int j = 0; j <= 10; ++j)
      for (int k = 0; k <= 10; ++k) {
        const Eigen::Vector3d q = lo + (hi - lo).cwiseProduct(Eigen::Vector3d(i, j, k) / 10.0);
        CHECK(p(q) >= mn);
        CHECK(p(q) <= mx);
      }
}

// Reliability probe: hostile strings of a few dozen characters used to overflow the stack
// (30 000 parentheses), expand for seconds and gigabytes (nested powers), or escape as an
// internal error (std::stol out_of_range). Each is now a named InputError, raised quickly.
TEST_CASE("parser limits: nesting depth, total degree, expansion work, exponent and coefficient range") {
  const Stopwatch watch;
  const std::string deep = std::string(30000, '(') + "x" + std::string(30000, ')');
  CHECK_THROWS_WITH_AS(Polynomial::parse(deep), doctest::Contains("nesting deeper than 200 levels"), InputError);
  CHECK_THROWS_WITH_AS(Polynomial::parse(std::string(30000, '-') + "x"), doctest::Contains("nesting deeper than 200"),
                       InputError);
  // 150 levels are fine: x.
  const Polynomial nested = Polynomial::parse(std::string(150, '(') + "x" + std::string(150, ')'));
  CHECK(nested(2.5, 0.0, 0.0) == 2.5);
  CHECK(nested.total_degree() == 1);

  CHECK_THROWS_WITH_AS(Polynomial::parse("((x*y*z)^64)^64"),
                       doctest::Contains("total degree 192 of the power exceeds the limit 64"), InputError);
  CHECK_THROWS_WITH_AS(Polynomial::parse("((x^8)^8)^8"), doctest::Contains("total degree 512"), InputError);
  CHECK_THROWS_WITH_AS(Polynomial::parse("x^40*y^30"),
                       doctest::Contains("total degree 70 exceeds the limit 64 at position 5"), InputError);
  // Degree 64 within the work budget still expands (about 1e7 operations): value (1 + 1e-3)^64.
  const Polynomial full = Polynomial::parse("(x+y+z+1)^64");
  CHECK(full.total_degree() == 64);
  CHECK(full(1e-3, 0.0, 0.0) == doctest::Approx(std::pow(1.001, 64)).epsilon(1e-12));
  // Degree 64 again, but the dense product of two 32nd powers costs 2.4e8 operations.
  CHECK_THROWS_WITH_AS(Polynomial::parse("(x+y+z+1)^32*(x+y+z+1)^32"), doctest::Contains("expansion too large"),
                       InputError);

  CHECK_THROWS_WITH_AS(Polynomial::parse("x^99999999999999999999"),
                       doctest::Contains("exponent 99999999999999999999 exceeds the limit 64 at position 3"),
                       InputError);
  CHECK_THROWS_WITH_AS(Polynomial::parse("x^65"), doctest::Contains("exponent 65 exceeds the limit 64"), InputError);
  CHECK_THROWS_WITH_AS(Polynomial::parse("x^2+1e999"),
                       doctest::Contains("non-finite coefficient '1e999' (out of the range of double) at position 5"),
                       InputError);
  CHECK_THROWS_WITH_AS(Polynomial::parse("1e200*1e200*x"), doctest::Contains("non-finite coefficient after expansion"),
                       InputError);
  CHECK_THROWS_WITH_AS(Polynomial::parse("x/1e-320"), doctest::Contains("non-finite coefficient after expansion"),
                       InputError);
  // Long inputs are shown by their first 80 characters only.
  try {
    Polynomial::parse(std::string(5000, '(') + "x");
    FAIL("expected an error");
  } catch (const InputError& e) {
    CHECK(std::string(e.what()).size() < 200);
  }
  CHECK(watch.elapsed() < 2.0);
}
