// Backward (Poisson) evaluation of docs/math.md §10.4 on sphere1 with true normals: the corrected methods
// converge with observed order >= 1.5 over h = 0.1, 0.05, 0.025 (the paper reports ~h^1.9).
#include <doctest/doctest.h>

#include <Eigen/SparseCholesky>
#include <cmath>
#include <corrlap/core/config.hpp>
#include <corrlap/discretizations/registry.hpp>

#include "reference_support.hpp"

using namespace corrlap;
using namespace corrlap::test;

namespace {

// M-weighted L2 error of the pinned Poisson solve for f = x^2 (Delta f = 2 - 6x^2 on S^2, docs/math.md §10.2).
double poisson_error(const std::string& method, const SphereCase& s) {
  const Operators ops = make_discretization(method)->assemble(s.mesh, s.normals, Config{});
  const Eigen::Index n = ops.L.rows();
  Eigen::VectorXd f(n), lap(n);
  for (Eigen::Index v = 0; v < n; ++v) {
    const Eigen::Vector3d q = s.mesh.positions.row(v).transpose().normalized();
    f[v] = q.x() * q.x();
    lap[v] = 2.0 - 6.0 * q.x() * q.x();
  }
  const Eigen::VectorXd ones = Eigen::VectorXd::Ones(n);
  const Eigen::VectorXd M1 = ops.M * ones;
  const double mass = ones.dot(M1);
  // Compatibility projection (docs/math.md §10.4): remove the M-mean of b.
  Eigen::VectorXd b = lap.array() - M1.dot(lap) / mass;
  Eigen::VectorXd rhs = ops.M * b;
  // Pin vertex 0: g_0 = f(q_0); replace row/column 0 by the identity, move the column to the rhs.
  Eigen::SparseMatrix<double> A = ops.L;
  for (Eigen::SparseMatrix<double>::InnerIterator it(A, 0); it; ++it) rhs[it.row()] -= it.value() * f[0];
  A.prune([](Eigen::Index r, Eigen::Index c, double) { return r != 0 && c != 0; });
  A.coeffRef(0, 0) = 1.0;
  rhs[0] = f[0];
  // -A is SPD after pinning (L is negative semi-definite with kernel 1).
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(-A);
  REQUIRE(ldlt.info() == Eigen::Success);
  const Eigen::VectorXd g = ldlt.solve(-rhs);
  REQUIRE(ldlt.info() == Eigen::Success);
  Eigen::VectorXd e = (g.array() - M1.dot(g) / mass) - (f.array() - M1.dot(f) / mass);
  return std::sqrt(e.dot(ops.M * e) / mass);
}

}  // namespace

TEST_CASE("backward Poisson error of fem, interpolated and projected-polydec converges with order >= 1.5") {
  const std::vector<double> hs = {0.1, 0.05, 0.025};
  std::vector<SphereCase> cases;
  for (double h : hs) cases.push_back(sphere_case(h));
  for (const std::string method : {"fem", "interpolated", "projected-polydec"}) {
    std::vector<double> err;
    for (const auto& s : cases) err.push_back(poisson_error(method, s));
    // Least-squares slope of log(err) against log(h).
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (std::size_t i = 0; i < hs.size(); ++i) {
      const double x = std::log(hs[i]), y = std::log(err[i]);
      sx += x, sy += y, sxx += x * x, sxy += x * y;
    }
    const double k = double(hs.size());
    const double order = (k * sxy - sx * sy) / (k * sxx - sx * sx);
    MESSAGE(method << ": errors " << err[0] << " " << err[1] << " " << err[2] << ", observed order " << order);
    CHECK(err[1] < err[0]);
    CHECK(err[2] < err[1]);
    CHECK(order >= 1.5);
  }
}

TEST_CASE("backward Poisson errors at h = 0.1 match the reference table of docs/math.md §12.5") {
  const SphereCase s = sphere_case(0.1);
  CHECK(poisson_error("interpolated", s) == doctest::Approx(0.00431).epsilon(0.01));
  CHECK(poisson_error("fem", s) == doctest::Approx(0.00483).epsilon(0.01));
}
