// The geometric nested dissection order (backends/detail/geometric_ordering.hpp) and cholmod's use
// of it: a permutation for any input, less fill than AMD on surfaces, the same solutions.
#include <doctest/doctest.h>

#include <algorithm>
#include <corrlap/backends/cholmod.hpp>
#include <corrlap/backends/detail/geometric_ordering.hpp>
#include <corrlap/core/config.hpp>
#include <corrlap/core/error.hpp>
#include <numeric>

#include "backends/fem_fixture.hpp"

using corrlap::detail::geometric_nested_dissection;
using SpMat = Eigen::SparseMatrix<double>;

namespace {
bool is_permutation_of_n(std::vector<int> order, std::size_t n) {
  if (order.size() != n) return false;
  std::sort(order.begin(), order.end());
  for (std::size_t i = 0; i < n; ++i)
    if (order[i] != int(i)) return false;
  return true;
}

// A path graph 0 - 1 - ... - n-1 (tridiagonal pattern, stored in full).
SpMat path_pattern(int n) {
  std::vector<Eigen::Triplet<double>> t;
  for (int i = 0; i < n; ++i) {
    t.emplace_back(i, i, 2.0);
    if (i + 1 < n) {
      t.emplace_back(i, i + 1, -1.0);
      t.emplace_back(i + 1, i, -1.0);
    }
  }
  SpMat A(n, n);
  A.setFromTriplets(t.begin(), t.end());
  return A;
}
}  // namespace

TEST_CASE("geometric_nested_dissection returns a permutation for any points") {
  const int n = 1000;
  const SpMat A = path_pattern(n);
  Eigen::MatrixX3d points(n, 3);
  for (int i = 0; i < n; ++i) points.row(i) << i, 0.0, 0.0;
  const std::vector<int> order = geometric_nested_dissection(A, points, 16);
  CHECK(is_permutation_of_n(order, n));
  // On a path split at the median, the first separator is one vertex and is eliminated last.
  CHECK(std::abs(order.back() - n / 2) <= 1);
  // Every point at one place: nothing to split, the natural order.
  const std::vector<int> same = geometric_nested_dissection(A, Eigen::MatrixX3d::Zero(n, 3), 16);
  std::vector<int> natural(n);
  std::iota(natural.begin(), natural.end(), 0);
  CHECK(same == natural);
  // 70% on one plane, 30% on another (the median falls on the lowest plane), and disconnected parts.
  Eigen::MatrixX3d two_planes(n, 3);
  for (int i = 0; i < n; ++i) two_planes.row(i) << (i % 10 < 7 ? 0.0 : 1.0), 0.0, double(i % 3);
  CHECK(is_permutation_of_n(geometric_nested_dissection(A, two_planes, 16), n));
  CHECK(is_permutation_of_n(geometric_nested_dissection(SpMat(path_pattern(1)), Eigen::MatrixX3d::Zero(1, 3)), 1));
  CHECK_THROWS(geometric_nested_dissection(A, Eigen::MatrixX3d::Zero(n - 1, 3)));
}

TEST_CASE("cholmod with the vertex positions: geometric nested dissection, less fill than AMD, same solution") {
  using namespace corrlap;
  // -L + M of the flat FEM on a digitized sphere (h = 0.05, 7 496 unknowns): SPD, a surface's pattern.
  const test::FlatFem fem = test::flat_fem_sphere(0.05);
  SpMat A = SpMat(-fem.L) + fem.M;
  A.makeCompressed();
  const Eigen::VectorXd b = fem.M * Eigen::VectorXd::LinSpaced(A.rows(), -1.0, 1.0);

  CholmodSolver amd;
  amd.configure(Config::from_key_values({"ordering=amd"}));
  amd.set_positions(fem.mesh.positions);  // ignored by an explicit amd
  amd.compute(A);
  CHECK(amd.ordering_used() == "amd");
  const Eigen::VectorXd x_amd = amd.solve(b);

  CholmodSolver geometric;  // the default ordering
  geometric.set_positions(fem.mesh.positions);
  geometric.compute(A);
  CHECK(geometric.ordering_used() == "geometric");
  CHECK(geometric.info().ordering == "geometric");
  const Eigen::VectorXd x_geometric = geometric.solve(b);
  // Measured on this system: 2.9e7 flops against AMD's 4.0e7 (0.72); at 47 024 unknowns 0.43 and at
  // 1.2 M 0.25 (bench/RESULTS.md). The bound leaves 10% for other CHOLMOD versions.
  CHECK(geometric.info().factor_flops > 0.0);
  CHECK(geometric.info().factor_flops < 0.8 * amd.info().factor_flops);
  // A different elimination order changes only the rounding.
  CHECK((x_geometric - x_amd).norm() <= 1e-12 * x_amd.norm());

  // Without positions, or with positions of another size, the default falls back to AMD.
  CholmodSolver fallback;
  fallback.compute(A);
  CHECK(fallback.ordering_used() == "amd");
  fallback.set_positions(fem.mesh.positions.topRows(10));
  fallback.compute(A);
  CHECK(fallback.ordering_used() == "amd");
  Eigen::MatrixX3d bad = fem.mesh.positions;
  bad(3, 1) = std::nan("");
  CHECK_THROWS_AS(fallback.set_positions(bad), InputError);
}
