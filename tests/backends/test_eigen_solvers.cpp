// Generalized eigen solvers (docs/math.md §10.5): shift-invert Lanczos over any LinearSolver agrees with
// the dense solver; eigenvalues are reported as -lambda >= 0 ascending (docs/math.md §12.3).
#include <doctest/doctest.h>

#include <corrlap/backends/detail/block_lanczos.hpp>
#include <corrlap/backends/detail/symmetric_product.hpp>
#include <corrlap/backends/registry.hpp>
#include <corrlap/backends/spectra_eigs.hpp>
#include <corrlap/core/error.hpp>

#include "backends/fem_fixture.hpp"

using namespace corrlap;
using SpMat = Eigen::SparseMatrix<double>;

namespace {
const test::FlatFem& sphere() {
  static const test::FlatFem op = test::flat_fem_sphere(0.2);  // ~460 vertices: dense is cheap
  return op;
}
}  // namespace

TEST_CASE("dense eigen solver: constant kernel, -lambda >= 0 ascending, M-orthonormal vectors") {
  const auto& op = sphere();
  DenseEigenSolver dense;
  const EigenResult r = dense.solve(op.L, op.M, 16);
  REQUIRE(r.values.size() == 16);
  CHECK(std::abs(r.values[0]) < 1e-10);  // L 1 = 0
  for (int i = 1; i < 16; ++i) CHECK(r.values[i] >= r.values[i - 1]);
  // The flat-normal FEM on a digital sphere approximates l(l+1) = 2 only roughly (no correction):
  // it must at least be clearly positive and of the right order.
  CHECK(r.values[1] > 0.5);
  CHECK(r.values[1] < 4.0);
  const Eigen::MatrixXd G = r.vectors.transpose() * (op.M * r.vectors);
  CHECK((G - Eigen::MatrixXd::Identity(16, 16)).norm() < 1e-9);
  // L u = lambda M u with lambda = -value.
  const Eigen::MatrixXd R = op.L * r.vectors + op.M * r.vectors * r.values.asDiagonal();
  CHECK(R.norm() / (op.L * r.vectors).norm() < 1e-9);
}

TEST_CASE("shift-invert eigen solver with every linear solver matches the dense solver") {
  const auto& op = sphere();
  DenseEigenSolver dense;
  const EigenResult ref = dense.solve(op.L, op.M, 12);
  for (const std::string cfg : {"solver=cholmod", "solver=eigen-ldlt", "solver=eigen-llt",
                                "solver=cholmod ordering=metis", "solver=cg tolerance=1e-13 preconditioner=ichol"}) {
    CAPTURE(cfg);
    std::vector<std::string> kv;
    std::istringstream is(cfg);
    for (std::string t; is >> t;) kv.push_back(t);
    kv.push_back("dense_threshold=0");  // force Lanczos on this small problem
    ShiftInvertEigenSolver eigs;
    eigs.configure(Config::from_key_values(kv));
    const EigenResult r = eigs.solve(op.L, op.M, 12);
    REQUIRE(r.values.size() == 12);
    CHECK(r.iterations >= 1);
    // Ritz values converge to 1e-10 relative; the degenerate triplets (l = 1, 2) have no
    // unique eigenvectors, so only values and residuals are compared.
    CHECK((r.values - ref.values).lpNorm<Eigen::Infinity>() < 1e-7);
    const Eigen::MatrixXd R = op.L * r.vectors + op.M * r.vectors * r.values.asDiagonal();
    CHECK(R.norm() / (op.L * r.vectors).norm() < 1e-6);
    const Eigen::MatrixXd G = r.vectors.transpose() * (op.M * r.vectors);
    CHECK((G - Eigen::MatrixXd::Identity(12, 12)).norm() < 1e-8);
  }
}

namespace {
// Graph Laplacian of an m x m periodic grid (M = I): eigenvalues 4 - 2cos(2 pi a/m) - 2cos(2 pi b/m),
// exactly 4- and 8-fold. Lanczos from one start vector misses copies of such eigenvalues unless
// they are searched for (the solver deflates and verifies).
SpMat periodic_grid_laplacian(int m) {
  std::vector<Eigen::Triplet<double>> t;
  const auto id = [m](int i, int j) { return ((i + m) % m) * m + (j + m) % m; };
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j)
      for (const int b : {id(i + 1, j), id(i - 1, j), id(i, j + 1), id(i, j - 1)}) {
        t.emplace_back(id(i, j), b, 1.0);
        t.emplace_back(id(i, j), id(i, j), -1.0);
      }
  SpMat L(m * m, m * m);
  L.setFromTriplets(t.begin(), t.end());
  return L;
}
}  // namespace

TEST_CASE("shift-invert eigen solver finds every copy of multiple eigenvalues (k cutting a cluster)") {
  const SpMat L = periodic_grid_laplacian(20);
  SpMat M(L.rows(), L.cols());
  M.setIdentity();
  DenseEigenSolver dense;
  const EigenResult ref = dense.solve(L, M, 40);
  for (const std::string guard : {"auto", "0"})
    for (const int k : {5, 9, 13, 17, 21, 25, 40}) {
      CAPTURE(guard);
      CAPTURE(k);
      ShiftInvertEigenSolver eigs;
      eigs.configure(Config::from_key_values({"dense_threshold=0", "guard=" + guard}));
      const EigenResult r = eigs.solve(L, M, k);
      CHECK((r.values - ref.values.head(k)).lpNorm<Eigen::Infinity>() < 1e-9);
      const Eigen::MatrixXd G = r.vectors.transpose() * r.vectors;
      CHECK((G - Eigen::MatrixXd::Identity(k, k)).norm() < 1e-8);
    }
  ShiftInvertEigenSolver eigs;
  CHECK_THROWS_WITH_AS(eigs.configure(Config::from_key_values({"guard=-2"})), doctest::Contains("guard"), InputError);
  CHECK_THROWS_AS(eigs.configure(Config::from_key_values({"verify=maybe"})), InputError);
  // Without verification and guard pairs, single-vector Lanczos does miss copies here: the cases
  // above are a test of the verification (its probe, then the full search), not of luck.
  int missed = 0;
  for (const int k : {5, 9, 13, 17, 21, 25, 40}) {
    ShiftInvertEigenSolver unverified;
    unverified.configure(Config::from_key_values({"dense_threshold=0", "guard=0", "verify=false", "block_size=1"}));
    missed += (unverified.solve(L, M, k).values - ref.values.head(k)).lpNorm<Eigen::Infinity>() > 1e-6;
  }
  CHECK(missed > 0);
  // The block run (its start block sees several copies at once) with the probe, on the same cuts.
  for (const int k : {5, 9, 13, 17}) {
    CAPTURE(k);
    ShiftInvertEigenSolver blocks;
    blocks.configure(Config::from_key_values({"dense_threshold=0", "guard=0", "block_size=8"}));
    CHECK((blocks.solve(L, M, k).values - ref.values.head(k)).lpNorm<Eigen::Infinity>() < 1e-9);
  }
  // Guard pairs alone (no verification) still give a correct, M-orthonormal result when the cut
  // does not fall inside a cluster that Lanczos missed.
  eigs.configure(Config::from_key_values({"dense_threshold=0", "verify=false"}));
  const EigenResult r = eigs.solve(L, M, 5);
  CHECK((r.values - ref.values.head(5)).lpNorm<Eigen::Infinity>() < 1e-9);
}

TEST_CASE("eigen solvers are registered and check their input") {
  auto eigs = eigen_solver_registry().create("shift-invert");
  CHECK_THROWS_WITH_AS(eigs->configure(Config::from_key_values({"shift=0.5"})), doctest::Contains("shift"), InputError);
  // Unknown key: the error names both the eigen solver's and the linear solver's keys.
  CHECK_THROWS_WITH_AS(eigs->configure(Config::from_key_values({"solver=cholmod", "nvc=30"})),
                       doctest::Contains("ordering"), InputError);
  CHECK_NOTHROW(eigs->configure(Config::from_key_values({"solver=cholmod", "ordering=metis", "ncv=40"})));
  const auto& op = sphere();
  CHECK_THROWS_AS(eigs->solve(op.L, op.M, 0), InputError);
  const SpMat small = op.M.topLeftCorner(10, 10);
  CHECK_THROWS_AS(eigs->solve(op.L, small, 4), SolverError);
  CHECK(eigen_solver_registry().contains("dense"));
}

TEST_CASE("block Lanczos and Spectra's single-vector Lanczos give the same pairs") {
  const auto& op = sphere();
  ShiftInvertEigenSolver block, single;
  block.configure(Config::from_key_values({"dense_threshold=0", "block_size=16"}));
  single.configure(Config::from_key_values({"dense_threshold=0", "block_size=1"}));
  const EigenResult a = block.solve(op.L, op.M, 12), b = single.solve(op.L, op.M, 12);
  CHECK(a.method == "lanczos");
  // Both converge to residuals of 1e-10 relative; the values agree far below that (measured 1e-14).
  CHECK((a.values - b.values).lpNorm<Eigen::Infinity>() < 1e-9 * b.values.cwiseAbs().maxCoeff());
  const Eigen::MatrixXd R = op.L * a.vectors + op.M * a.vectors * a.values.asDiagonal();
  CHECK(R.norm() / (op.L * a.vectors).norm() < 1e-6);
  CHECK_THROWS_AS(block.configure(Config::from_key_values({"block_size=0"})), InputError);
}

TEST_CASE("detail::block_lanczos: the largest eigenvalues of a known operator, and a breakdown is reported") {
  const int n = 600;
  SpMat M(n, n);
  M.setIdentity();
  // S = diag(1 / (1 + i)): the largest nev eigenvalues are 1, 1/2, 1/3, ...
  Eigen::VectorXd d(n);
  for (int i = 0; i < n; ++i) d[i] = 1.0 / (1.0 + i);
  const auto apply = [&](const Eigen::MatrixXd& X) -> Eigen::MatrixXd { return d.asDiagonal() * X; };
  detail::BlockLanczosOptions o;
  o.block_size = 8;
  const detail::BlockLanczosResult r = detail::block_lanczos(apply, M, 10, o);
  REQUIRE(r.converged);
  for (int i = 0; i < 10; ++i) CHECK(r.theta[i] == doctest::Approx(1.0 / (1.0 + i)).epsilon(1e-12));
  const Eigen::MatrixXd G = r.vectors.transpose() * r.vectors;
  CHECK((G - Eigen::MatrixXd::Identity(10, 10)).norm() < 1e-10);
  // Two distinct eigenvalues only: the Krylov space of a 16-block is exhausted after one step. The
  // result is then either exact or reported as not converged (the solver falls back to Spectra).
  Eigen::VectorXd two(n);
  for (int i = 0; i < n; ++i) two[i] = i % 2 ? 1.0 : 0.5;
  o.block_size = 16;
  const detail::BlockLanczosResult t =
      detail::block_lanczos([&](const Eigen::MatrixXd& X) -> Eigen::MatrixXd { return two.asDiagonal() * X; }, M, 4, o);
  if (t.converged)
    for (int i = 0; i < 4; ++i) CHECK(t.theta[i] == doctest::Approx(1.0).epsilon(1e-10));
  // Too small for a block: not converged, nothing computed.
  CHECK_FALSE(detail::block_lanczos(apply, SpMat(M.topLeftCorner(20, 20)), 10, o).converged);
  // An early stop: the question "is the largest theta above 0.9?" is answered by the first Ritz
  // value (a lower bound of it) before the pair converges.
  o.block_size = 4;
  o.tolerance = 1e-14;
  int calls = 0;
  o.stop = [&](const Eigen::VectorXd& theta, const Eigen::VectorXd& residuals) {
    ++calls;
    CHECK(residuals.size() == theta.size());
    return theta[0] > 0.9;
  };
  const detail::BlockLanczosResult s = detail::block_lanczos(apply, M, 1, o);
  CHECK(s.stopped);
  CHECK_FALSE(s.converged);
  CHECK(calls == s.block_steps - 1);  // asked from the second step on (basis of nev + block_size)
  CHECK(s.theta[0] > 0.9);
  CHECK(s.theta[0] <= 1.0 + 1e-12);
  CHECK(s.residuals[0] > 0.0);
}

TEST_CASE("detail::symmetric_times equals M * X entry by entry") {
  const auto& op = sphere();  // an assembled mass matrix, exactly symmetric
  REQUIRE((SpMat(op.M.transpose()) - op.M).norm() == 0.0);
  for (const int b : {1, 3, 16}) {
    const Eigen::MatrixXd X = Eigen::MatrixXd::Random(op.M.rows(), b);
    const Eigen::MatrixXd expected = op.M * X;
    CHECK((detail::symmetric_times(op.M, X).array() == expected.array()).all());
  }
}
