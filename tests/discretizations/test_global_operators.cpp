// Global operators on sphere1 and on a flat plane (docs/math.md §12.3).
#include <doctest/doctest.h>

#include <Eigen/Dense>
#include <corrlap/core/config.hpp>
#include <corrlap/discretizations/registry.hpp>

#include "reference_support.hpp"

using namespace corrlap;
using namespace corrlap::test;

namespace {

Operators build(const std::string& method, const SphereCase& s, Config params = {}) {
  return make_discretization(method)->assemble(s.mesh, s.normals, params);
}

Config with(const std::string& key, Config::Value v) {
  Config c;
  c.set(key, std::move(v));
  return c;
}

// Smallest -lambda of L u = lambda M u (dense; meshes of a few hundred vertices).
Eigen::VectorXd smallest_eigenvalues(const Operators& ops, int k) {
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(-Eigen::MatrixXd(ops.L), Eigen::MatrixXd(ops.M),
                                                               Eigen::EigenvaluesOnly);
  REQUIRE(es.info() == Eigen::Success);
  return es.eigenvalues().head(k);
}

// Distinct values (with multiplicity) of docs/math.md §12.3, to the printed digits.
void check_spectrum(const Eigen::VectorXd& mu, std::initializer_list<std::pair<double, int>> expected, double rel) {
  int i = 1;  // mu[0] ~ 0
  CHECK(std::abs(mu[0]) <= 1e-9);
  for (const auto& [value, mult] : expected)
    for (int m = 0; m < mult; ++m, ++i) {
      const auto value_copy = value;  // clang 14: no structured binding inside CAPTURE/INFO
      INFO("eigenvalue " << i << " = " << mu[i] << ", expected " << value_copy);
      CHECK(std::abs(mu[i] - value) <= rel * value);
    }
}

}  // namespace

TEST_CASE("total mass on sphere1 with radial normals matches the reference (docs/math.md §12.3)") {
  const std::vector<std::pair<double, std::pair<double, double>>> table = {
      {0.5, {11.99117174, 12.31315677}}, {0.25, {12.10987569, 12.19109343}}, {0.1, {12.45922033, 12.47193387}}};
  for (const auto& [h, sums] : table) {
    const SphereCase s = sphere_case(h);
    const auto h_copy = h;  // clang 14: no structured binding inside CAPTURE/INFO
    INFO("h_copy = " << h_copy);
    CHECK(build("interpolated", s).M.sum() == doctest::Approx(sums.first).epsilon(1e-9));
    CHECK(build("fem", s).M.sum() == doctest::Approx(sums.second).epsilon(1e-9));
    CHECK(build("fem", s, with("mass", std::string("lumped"))).M.sum() == doctest::Approx(sums.second).epsilon(1e-9));
    // FEM and Projected PolyDEC share the corrected area with the same u_f.
    CHECK(build("projected-polydec", s).M.sum() == doctest::Approx(sums.second).epsilon(1e-9));
    CHECK(build("polydec", s).M.sum() == doctest::Approx(s.mesh.num_faces() * h * h).epsilon(1e-12));
  }
}

TEST_CASE("sphere1 h=0.25: L1 = 0, L symmetric, largest eigenvalue of L <= 1e-14 for CC, FEM, PolyDEC") {
  const SphereCase s = sphere_case(0.25);
  for (const std::string method : {"interpolated", "fem", "polydec", "projected-polydec"}) {
    const Operators ops = build(method, s);
    const double scale = max_abs(ops.L);
    INFO(method);
    CHECK((ops.L * Eigen::VectorXd::Ones(ops.L.cols())).cwiseAbs().maxCoeff() <= 1e-14 * scale);
    CHECK(max_abs(Eigen::SparseMatrix<double>(ops.L - Eigen::SparseMatrix<double>(ops.L.transpose()))) <=
          1e-15 * scale);
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Eigen::MatrixXd(ops.L), Eigen::EigenvaluesOnly);
    CHECK(es.eigenvalues().maxCoeff() <= 1e-14 * scale);
  }
}

TEST_CASE("sphere1 h=0.25 eigenvalues of every quad method match docs/math.md §12.3") {
  const SphereCase s = sphere_case(0.25);
  check_spectrum(smallest_eigenvalues(build("interpolated", s), 16),
                 {{2.0628, 3}, {6.1661, 3}, {6.3577, 2}, {12.4211, 1}, {12.4221, 3}, {12.9450, 3}}, 1e-4);
  check_spectrum(smallest_eigenvalues(build("fem", s), 16),
                 {{2.0788, 3}, {6.2558, 3}, {6.4183, 2}, {12.676, 3}, {12.768, 1}, {13.162, 3}}, 1e-4);
  check_spectrum(smallest_eigenvalues(build("projected-polydec", s), 16),
                 {{2.0609, 3}, {6.1328, 3}, {6.2378, 2}, {12.188, 3}, {12.354, 3}, {12.571, 1}}, 1e-4);
  check_spectrum(smallest_eigenvalues(build("polydec", s), 9), {{1.4735, 3}, {3.957, 2}, {4.666, 3}}, 1e-4);
  check_spectrum(smallest_eigenvalues(build("interpolated", s, with("assembly", std::string("local"))), 12),
                 {{2.0663, 3}, {6.2039, 3}, {6.3675, 2}, {12.538, 3}}, 1e-4);
}

TEST_CASE("interpolated global and local assemblies differ by about 9% at h=0.25 (docs/math.md §3.6)") {
  const SphereCase s = sphere_case(0.25);
  const Operators a = build("interpolated", s), b = build("interpolated", s, with("assembly", std::string("local")));
  const double rel = Eigen::SparseMatrix<double>(a.L - b.L).norm() / a.L.norm();
  CHECK(rel == doctest::Approx(0.09).epsilon(0.15));
  CHECK(relative_difference(a.M, b.M) == 0.0);
}

TEST_CASE("flat-plane stencils of an interior vertex (docs/math.md §12.3)") {
  const int n = 6;
  const SphereCase s = flat_grid(n, 1.0);
  const int centre = 3 * (n + 1) + 3;
  auto row = [&](const Operators& ops, int dx, int dy) { return ops.L.coeff(centre, centre + dy * (n + 1) + dx); };
  auto nnz_row = [&](const Operators& ops) {
    int c = 0;
    for (int j = 0; j < ops.L.outerSize(); ++j)
      for (Eigen::SparseMatrix<double>::InnerIterator it(ops.L, j); it; ++it)
        if (it.row() == centre && std::abs(it.value()) > 1e-14) ++c;
    return c;
  };
  const Operators fem = build("fem", s);
  CHECK(row(fem, 0, 0) == doctest::Approx(-8.0 / 3.0).epsilon(1e-14));
  for (int dx = -1; dx <= 1; ++dx)
    for (int dy = -1; dy <= 1; ++dy)
      if (dx || dy) CHECK(row(fem, dx, dy) == doctest::Approx(1.0 / 3.0).epsilon(1e-14));
  CHECK(nnz_row(fem) == 9);

  const Operators poly = build("polydec", s);
  CHECK(row(poly, 0, 0) == doctest::Approx(-6.0).epsilon(1e-14));
  CHECK(row(poly, 1, 0) == doctest::Approx(2.0).epsilon(1e-14));
  CHECK(row(poly, 0, -1) == doctest::Approx(2.0).epsilon(1e-14));
  CHECK(row(poly, 1, 1) == doctest::Approx(-0.5).epsilon(1e-14));

  for (double lambda : {0.1, 1.0, 0.37}) {
    INFO("lambda = " << lambda);
    const Operators g = build("interpolated", s, with("lambda", lambda));
    CHECK(row(g, 0, 0) == doctest::Approx(-2.0 - 1.5 * lambda).epsilon(1e-13));
    CHECK(row(g, 1, 0) == doctest::Approx(0.875 * lambda).epsilon(1e-13));
    CHECK(row(g, 0, -1) == doctest::Approx(0.875 * lambda).epsilon(1e-13));
    CHECK(row(g, 1, 1) == doctest::Approx(0.5 - 0.5 * lambda).epsilon(1e-13));
    CHECK(row(g, -2, 0) == doctest::Approx(-0.125 * lambda).epsilon(1e-13));
    CHECK(row(g, 0, 2) == doctest::Approx(-0.125 * lambda).epsilon(1e-13));
    CHECK(row(g, 2, 1) == doctest::Approx(0.0625 * lambda).epsilon(1e-13));
    CHECK(row(g, -1, -2) == doctest::Approx(0.0625 * lambda).epsilon(1e-13));
    CHECK(nnz_row(g) == (lambda == 1.0 ? 17 : 21));  // lambda = 1 cancels the diagonal neighbours
    Config lc = with("lambda", lambda);
    lc.set("assembly", std::string("local"));
    const Operators l = build("interpolated", s, lc);
    CHECK(row(l, 0, 0) == doctest::Approx(-(2.0 + 4.0 * lambda)).epsilon(1e-13));
    CHECK(row(l, -1, 0) == doctest::Approx(2.0 * lambda).epsilon(1e-13));
    CHECK(row(l, 1, -1) == doctest::Approx(0.5 - lambda).epsilon(1e-13));
    CHECK(nnz_row(l) == 9);
  }
}

TEST_CASE("extras: D0, sharp, flat and M1 reproduce L = -D0^T M1 D0 and M1 carries the edge signs") {
  const SphereCase s = sphere_case(0.5);
  Config extras = with("extras", true);
  for (const std::string method : {"polydec", "projected-polydec", "interpolated"}) {
    for (const std::string assembly : {"global", "local"}) {
      if (method != "interpolated" && assembly == "local") continue;
      Config c = extras;
      if (method == "interpolated") c.set("assembly", assembly);
      const Operators ops = build(method, s, c);
      REQUIRE(ops.D0);
      REQUIRE(ops.M1);
      REQUIRE(ops.sharp);
      REQUIRE(ops.flat);
      REQUIRE(ops.M_lumped);
      const Eigen::SparseMatrix<double> L2 = -Eigen::SparseMatrix<double>(ops.D0->transpose() * *ops.M1 * *ops.D0);
      INFO(method << " " << assembly);
      CHECK(relative_difference(L2, ops.L) <= 1e-13);
      CHECK(ops.sharp->rows() == 3 * s.mesh.num_faces());
      CHECK(ops.flat->cols() == 3 * s.mesh.num_faces());
      CHECK(ops.M_lumped->sum() == doctest::Approx(ops.M.sum()).epsilon(1e-13));
    }
  }
  const Operators fem = build("fem", s, extras);
  REQUIRE(fem.M_lumped);
  CHECK(fem.M_lumped->nonZeros() == s.mesh.num_vertices());
  CHECK(fem.M_lumped->sum() == doctest::Approx(fem.M.sum()).epsilon(1e-13));
}
