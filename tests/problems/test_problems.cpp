// Dirichlet and pure-Neumann Poisson helpers (docs/math.md §10.4) with every backend.
#include <doctest/doctest.h>

#include <corrlap/backends/registry.hpp>
#include <corrlap/problems/problems.hpp>

#include "backends/fem_fixture.hpp"

using namespace corrlap;
using SpMat = Eigen::SparseMatrix<double>;

namespace {
const test::FlatFem& sphere() {
  static const test::FlatFem op = test::flat_fem_sphere(0.2);
  return op;
}
std::unique_ptr<LinearSolver> solver(const std::string& name) {
  return make_linear_solver(
      Config::from_key_values({"solver=" + name, name == "cg" ? "tolerance=1e-13" : "check_symmetry=true"}));
}
const char* kNames[] = {"eigen-ldlt", "eigen-llt", "cholmod", "cg"};
}  // namespace

TEST_CASE("Dirichlet: free rows satisfy L u = M f and fixed values are exact") {
  const auto& op = sphere();
  const Eigen::Index n = op.L.rows();
  const Eigen::VectorXd f = op.mesh.positions.col(0).array().square();  // x^2 samples
  const std::vector<int> fixed = {0, 7, int(n / 2), int(n - 1)};
  const Eigen::VectorXd values = Eigen::Vector4d(1.0, -2.0, 0.5, 3.0);
  for (const char* name : kNames) {
    CAPTURE(name);
    auto s = solver(name);
    const Eigen::VectorXd u = solve_dirichlet(op.L, op.M, f, fixed, values, *s);
    Eigen::VectorXd r = op.L * u - op.M * f;
    for (std::size_t i = 0; i < fixed.size(); ++i) {
      CHECK(u[fixed[i]] == values[Eigen::Index(i)]);
      r[fixed[i]] = 0.0;
    }
    CHECK(r.norm() / (op.M * f).norm() < 1e-9);
  }
  auto s = solver("cholmod");
  CHECK_THROWS_AS(solve_dirichlet(op.L, op.M, f, {0, 0}, Eigen::Vector2d(1, 1), *s), InputError);
  CHECK_THROWS_AS(solve_dirichlet(op.L, op.M, f, {int(n)}, Eigen::VectorXd::Ones(1), *s), InputError);
  CHECK_THROWS_AS(solve_dirichlet(op.L, op.M, f, {1}, Eigen::VectorXd::Ones(2), *s), InputError);
  // No fixed vertex: -L is singular (L 1 = 0); refused instead of trusting a rounding-level pivot.
  CHECK_THROWS_WITH_AS(solve_dirichlet(op.L, op.M, f, {}, Eigen::VectorXd(), *s), doctest::Contains("singular"),
                       InputError);
}

TEST_CASE("Neumann Poisson recovers a solution up to a constant and projects incompatible data") {
  const auto& op = sphere();
  const Eigen::Index n = op.L.rows();
  // A smooth field g*, and b with L g* = M b exactly (b = M^{-1} L g*): the solver must return g*.
  const Eigen::VectorXd gstar = (op.mesh.positions.col(0).array() * 2.0).exp() + op.mesh.positions.col(2).array();
  auto msolver = solver("cholmod");
  msolver->compute(op.M);
  const Eigen::VectorXd b = msolver->solve(op.L * gstar);
  for (const char* name : kNames) {
    CAPTURE(name);
    auto s = solver(name);
    const Eigen::VectorXd g = solve_neumann_poisson(op.L, op.M, b, *s, gstar[0]);
    CHECK((g - gstar).lpNorm<Eigen::Infinity>() < 1e-8);
    const PoissonErrors e = poisson_errors(op.M, g, gstar);
    CHECK(e.linf < 1e-8);
    CHECK(e.l2 < 1e-8);
    // b + 5 is incompatible; the projection of docs/math.md §10.4 removes the constant.
    const Eigen::VectorXd g2 = solve_neumann_poisson(op.L, op.M, (b.array() + 5.0).matrix(), *s, gstar[0]);
    CHECK((g2 - gstar).lpNorm<Eigen::Infinity>() < 1e-8);
  }
  // The errors ignore constants and measure the rest.
  const Eigen::VectorXd shifted = (gstar.array() + 3.0).matrix();
  CHECK(poisson_errors(op.M, shifted, gstar).linf < 1e-12);
  Eigen::VectorXd bumped = gstar;
  bumped[n / 3] += 1.0;
  CHECK(poisson_errors(op.M, bumped, gstar).linf > 0.9);
  CHECK(mass_weighted_mean(op.M, Eigen::VectorXd::Constant(n, 2.5)) == doctest::Approx(2.5).epsilon(1e-14));
}

TEST_CASE("solve_neumann_poisson_columns equals one solve_neumann_poisson per column (pin anywhere)") {
  const auto& op = sphere();
  const Eigen::Index n = op.L.rows();
  Eigen::MatrixXd B(n, 3);
  B.col(0) = op.mesh.positions.col(0);
  B.col(1) = op.mesh.positions.col(1).array().square();
  B.col(2) = (op.mesh.positions.col(2).array() + 7.0).matrix();  // incompatible: projected
  const Eigen::Vector3d pins(0.5, -1.0, 2.0);
  for (int pin : {0, int(n / 2), int(n - 1)}) {
    CAPTURE(pin);
    auto s = solver("cholmod");
    const Eigen::MatrixXd G = solve_neumann_poisson_columns(op.L, op.M, B, *s, pins, pin);
    for (int j = 0; j < 3; ++j) {
      auto single = solver("cholmod");
      const Eigen::VectorXd g = solve_neumann_poisson(op.L, op.M, B.col(j), *single, pins[j], pin);
      // Same system and factorization; the multi-column solve may round differently.
      CHECK((G.col(j) - g).lpNorm<Eigen::Infinity>() <= 1e-10 * (1.0 + g.lpNorm<Eigen::Infinity>()));
      CHECK(G(pin, j) == pins[j]);
    }
  }
  auto s = solver("cholmod");
  CHECK_THROWS_AS(solve_neumann_poisson_columns(op.L, op.M, B, *s, Eigen::Vector2d(0, 0), 0), InputError);
  CHECK_THROWS_AS(solve_neumann_poisson_columns(op.L, op.M, B, *s, pins, int(n)), InputError);
}

TEST_CASE("forward_laplacian solves (M - dt L) X = L u, error_norms of a constant are the constant") {
  const auto& op = sphere();
  const Eigen::Index n = op.L.rows();
  const Eigen::VectorXd u = op.mesh.positions.col(0).array().square();
  auto s = solver("cholmod");
  for (double dt : {0.0, 0.007}) {
    CAPTURE(dt);
    const Eigen::VectorXd X = forward_laplacian(op.L, op.M, u, *s, dt);
    const Eigen::VectorXd Lu = op.L * u;
    CHECK((op.M * X - dt * (op.L * X) - Lu).norm() / Lu.norm() < 1e-12);
  }
  // Diffusion smooths: the diffused result has a smaller M-norm than the naive one (L <= 0).
  const ErrorNorms naive = error_norms(op.M, forward_laplacian(op.L, op.M, u, *s, 0.0));
  const ErrorNorms diffused = error_norms(op.M, forward_laplacian(op.L, op.M, u, *s, 0.007));
  CHECK(diffused.l2 < naive.l2);
  const ErrorNorms c = error_norms(op.M, Eigen::VectorXd::Constant(n, -0.25));
  CHECK(c.linf == 0.25);
  CHECK(c.l2 == doctest::Approx(0.25).epsilon(1e-14));
  CHECK_THROWS_AS(forward_laplacian(op.L, op.M, u, *s, -0.1), InputError);
  CHECK_THROWS_AS(error_norms(op.M, Eigen::VectorXd::Ones(n + 1)), InputError);
  // neumann_residual of the Neumann solve: its free rows hold.
  const Eigen::VectorXd b = 2.0 - 6.0 * u.array();
  const Eigen::VectorXd g = solve_neumann_poisson(op.L, op.M, b, *s);
  CHECK(neumann_residual(op.L, op.M, b, g) < 1e-12);
  // g = 0: the residual is M b_c without the pinned row, relative to M b_c.
  Eigen::VectorXd Mbc = op.M * (b.array() - mass_weighted_mean(op.M, b)).matrix();
  const double full = Mbc.norm();
  Mbc[0] = 0.0;
  CHECK(neumann_residual(op.L, op.M, b, Eigen::VectorXd::Zero(n)) == doctest::Approx(Mbc.norm() / full).epsilon(1e-14));
}

TEST_CASE("pinned_system is -L without the pinned row and column, and the solvers get it with the positions") {
  const test::FlatFem fem = test::flat_fem_sphere(0.4);
  const Eigen::Index n = fem.L.rows();
  for (int pin : {0, 7, int(n - 1)}) {
    CAPTURE(pin);
    const SpMat A = pinned_system(fem.L, pin);
    REQUIRE(A.rows() == n - 1);
    Eigen::MatrixXd expected = -Eigen::MatrixXd(fem.L);
    // Remove row and column `pin` of the dense copy.
    Eigen::MatrixXd reduced(n - 1, n - 1);
    for (Eigen::Index i = 0, ri = 0; i < n; ++i) {
      if (i == pin) continue;
      for (Eigen::Index j = 0, rj = 0; j < n; ++j) {
        if (j == pin) continue;
        reduced(ri, rj++) = expected(i, j);
      }
      ++ri;
    }
    CHECK((Eigen::MatrixXd(A) - reduced).norm() == 0.0);  // the same numbers, only moved
    CHECK(A.isCompressed());
  }
  CHECK_THROWS_AS(pinned_system(fem.L, int(n)), InputError);
  CHECK_THROWS_AS(pinned_system(fem.L, -1), InputError);
}
