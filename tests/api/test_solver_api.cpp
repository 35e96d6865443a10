// make_linear_solver / make_eigen_solver: the documented entry points and the one default solver.
#include <doctest/doctest.h>

#include <cmath>
#include <corrlap/corrlap.hpp>
#include <tuple>

using namespace corrlap;

namespace {
// -L + M of a path graph: SPD, tridiagonal.
Eigen::SparseMatrix<double> spd(int n) {
  std::vector<Eigen::Triplet<double>> t;
  for (int i = 0; i < n; ++i) {
    t.emplace_back(i, i, 3.0);
    if (i + 1 < n) {
      t.emplace_back(i, i + 1, -1.0);
      t.emplace_back(i + 1, i, -1.0);
    }
  }
  Eigen::SparseMatrix<double> A(n, n);
  A.setFromTriplets(t.begin(), t.end());
  return A;
}
}  // namespace

TEST_CASE("make_linear_solver by name: default cholmod, options, errors listing the names") {
  CHECK(std::string(kDefaultLinearSolver) == "cholmod");
  CHECK(make_linear_solver()->name() == "cholmod");
  CHECK(make_linear_solver(Config())->name() == "cholmod");  // the config form has the same default
  for (const std::string& name : linear_solver_registry().names()) {
    CAPTURE(name);
    auto s = make_linear_solver(name, name == "cg" ? Config::from_key_values({"tolerance=1e-14"}) : Config());
    CHECK(s->name() == name);
    const auto A = spd(50);
    s->compute(A);
    const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(50, -1.0, 2.0);
    const Eigen::VectorXd x = s->solve(b);
    CHECK((A * x - b).norm() / b.norm() < 1e-12);
  }
  CHECK_THROWS_WITH_AS(make_linear_solver("pardiso"),
                       doctest::Contains("unknown linear solver 'pardiso'; available: cg cholmod eigen-ldlt eigen-llt"),
                       InputError);
  CHECK_THROWS_WITH_AS(make_linear_solver("cholmod", Config::from_key_values({"orderin=metis"})),
                       doctest::Contains("orderin"), InputError);
  CHECK_THROWS_WITH_AS(make_linear_solver("cholmod", Config::from_key_values({"solver=cg"})),
                       doctest::Contains("solver='cg'"), InputError);
  CHECK(make_linear_solver("cholmod", Config::from_key_values({"solver=cholmod"}))->name() == "cholmod");
}

TEST_CASE("make_eigen_solver: shift-invert by default, errors listing the names") {
  CHECK(make_eigen_solver()->name() == kDefaultEigenSolver);
  CHECK_THROWS_WITH_AS(make_eigen_solver("arpack"), doctest::Contains("available: dense shift-invert"), InputError);
  // L = -(path Laplacian), M = I: -lambda are 2 - 2 cos(k pi / n), k = 0..n-1 (Neumann path).
  const int n = 40;
  std::vector<Eigen::Triplet<double>> t;
  for (int i = 0; i + 1 < n; ++i)
    for (auto [r, c, v] : {std::tuple{i, i, -1.0}, {i + 1, i + 1, -1.0}, {i, i + 1, 1.0}, {i + 1, i, 1.0}})
      t.emplace_back(r, c, v);
  Eigen::SparseMatrix<double> L(n, n);
  L.setFromTriplets(t.begin(), t.end());
  Eigen::SparseMatrix<double> M(n, n);
  M.setIdentity();
  for (const char* name : {"shift-invert", "dense"}) {
    CAPTURE(name);
    const EigenResult r = make_eigen_solver(name)->solve(L, M, 4);
    REQUIRE(r.values.size() == 4);
    for (int k = 0; k < 4; ++k) CHECK(r.values[k] == doctest::Approx(2.0 - 2.0 * std::cos(k * M_PI / n)).epsilon(1e-9));
  }
}
