// Cotan Laplacian and lumped masses on triangle meshes (paper §3.4 comparison).
#include <doctest/doctest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/discretizations/cotan.hpp>
#include <corrlap/discretizations/registry.hpp>
#include <map>

#include "discretizations/test_vrm_support.hpp"
#include "test_support.hpp"

using namespace corrlap;

namespace {

// Icosahedron subdivided `level` times, vertices on the unit sphere (shared test helper).
void icosphere(int level, Eigen::MatrixX3d& V, TriangleIndices& T) {
  const PolygonMesh m = test::icosphere(level);
  V = m.positions;
  T = triangulate(m);
}

Eigen::VectorXd smallest_eigenvalues(const Operators& ops, int k) {
  const Eigen::MatrixXd L(ops.L), M(ops.M);
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(-L, M, Eigen::EigenvaluesOnly);
  return es.eigenvalues().head(k);
}

}  // namespace

TEST_CASE("cotan on a single equilateral triangle: 1/(2 sqrt 3) weights and A/3 masses") {
  Eigen::MatrixX3d V(3, 3);
  V << 0, 0, 0, 1, 0, 0, 0.5, std::sqrt(3.0) / 2, 0;
  TriangleIndices T(1, 3);
  T << 0, 1, 2;
  for (CotanMass m : {CotanMass::Voronoi, CotanMass::Barycentric}) {
    const Operators ops = assemble_cotan(V, T, m);
    const double w = 0.5 / std::sqrt(3.0);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) CHECK(ops.L.coeff(i, j) == doctest::Approx(i == j ? -2 * w : w).epsilon(1e-14));
    // equilateral: the Voronoi cell is exactly a third of the triangle as well
    for (int i = 0; i < 3; ++i) CHECK(ops.M.coeff(i, i) == doctest::Approx(std::sqrt(3.0) / 12).epsilon(1e-14));
  }
}

TEST_CASE("cotan eigenvalues on icospheres converge toward l(l+1), L 1 = 0, symmetric") {
  double prev_err = 1e9;
  for (int level = 2; level <= 3; ++level) {
    Eigen::MatrixX3d V;
    TriangleIndices T;
    icosphere(level, V, T);
    for (CotanMass m : {CotanMass::Voronoi, CotanMass::Barycentric}) {
      const Operators ops = assemble_cotan(V, T, m);
      CHECK((ops.L * Eigen::VectorXd::Ones(V.rows())).cwiseAbs().maxCoeff() < 1e-12);
      CHECK((Eigen::SparseMatrix<double>(ops.L.transpose()) - ops.L).norm() < 1e-14 * ops.L.norm());
      CHECK(ops.M.sum() == doctest::Approx(4 * M_PI).epsilon(0.05));
      const Eigen::VectorXd ev = smallest_eigenvalues(ops, 16);
      CHECK(std::abs(ev[0]) < 1e-9);
      double err = 0;
      const double exact[16] = {0, 2, 2, 2, 6, 6, 6, 6, 6, 12, 12, 12, 12, 12, 12, 12};
      for (int i = 1; i < 16; ++i) err = std::max(err, std::abs(ev[i] - exact[i]) / exact[i]);
      MESSAGE("icosphere level " << level << std::string(m == CotanMass::Voronoi ? " voronoi" : " barycentric")
                                 << ": max relative error of l <= 3 eigenvalues " << err);
      CHECK(err < (level == 2 ? 0.08 : 0.02));
      if (m == CotanMass::Voronoi) {
        CHECK(err < prev_err / 3);  // second order: the error drops by ~4 per subdivision
        prev_err = err;
      }
    }
  }
}

TEST_CASE("cotan registry entry splits quads, flat surfel gives the 5-point-like stencil and h^2 masses") {
  const SurfelMesh sphere = test::sphere1_surface(0.25);
  const Operators ops = make_discretization("cotan")->assemble(sphere, NormalFields(), Config());
  CHECK((ops.L * Eigen::VectorXd::Ones(ops.L.cols())).cwiseAbs().maxCoeff() < 1e-12);
  CHECK(ops.M.sum() == doctest::Approx(sphere.num_faces() * 0.0625).epsilon(1e-12));
  const Operators one = make_discretization("cotan")->assemble(test::single_surfel(0.5), NormalFields(), Config());
  // square split along 0-2: each side is opposite one 45 deg angle (weight cot/2 = 1/2), the diagonal two right angles
  // (0)
  CHECK(one.L.coeff(0, 1) == doctest::Approx(0.5));
  CHECK(one.L.coeff(0, 3) == doctest::Approx(0.5));
  CHECK(std::abs(one.L.coeff(0, 2)) < 1e-15);
  CHECK_THROWS_WITH_AS(
      make_discretization("cotan")->assemble(sphere, NormalFields(), Config::from_key_values({"mass=x"})),
      doctest::Contains("mass"), InputError);
}

TEST_CASE("cotan rejects degenerate triangles and bad indices, naming the triangle") {
  Eigen::MatrixX3d V(4, 3);
  V << 0, 0, 0, 1, 0, 0, 2, 0, 0, 0, 1, 0;
  TriangleIndices T(2, 3);
  T << 0, 1, 3, 0, 1, 2;
  CHECK_THROWS_WITH_AS(assemble_cotan(V, T), doctest::Contains("triangle 1"), InputError);
  T << 0, 1, 3, 0, 1, 7;
  CHECK_THROWS_WITH_AS(assemble_cotan(V, T), doctest::Contains("triangle 1 refers to vertex 7"), InputError);
  T << 0, 1, 3, 1, 1, 3;
  CHECK_THROWS_WITH_AS(assemble_cotan(V, T), doctest::Contains("repeats"), InputError);
}
