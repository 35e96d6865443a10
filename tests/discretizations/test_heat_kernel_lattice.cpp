// The compact lattice form of the heat kernel (discretizations/heat_kernel_lattice.hpp) against the
// readable heat_kernel_matrix it says it equals, and the operator CG that consumes it.
#include <doctest/doctest.h>

#include <corrlap/backends/iterative.hpp>
#include <corrlap/backends/registry.hpp>
#include <corrlap/core/error.hpp>
#include <corrlap/core/threads.hpp>
#include <corrlap/discretizations/heat_kernel.hpp>
#include <corrlap/discretizations/heat_kernel_lattice.hpp>
#include <corrlap/discretizations/registry.hpp>
#include <corrlap/estimators/implicit_normals.hpp>
#include <random>

#include "discretizations/test_vrm_support.hpp"

using namespace corrlap;

namespace {

struct Case {
  SurfelMesh mesh;
  NormalFields normals;
};

Case sphere(double h) {
  Case c{test::sphere1_surface(h), {}};
  c.normals.face = true_face_normals(make_implicit_shape("sphere1"), c.mesh);
  return c;
}

double max_abs(const Eigen::SparseMatrix<double>& A) {
  double m = 0;
  for (Eigen::Index k = 0; k < A.nonZeros(); ++k) m = std::max(m, std::abs(A.valuePtr()[k]));
  return m;
}

}  // namespace

TEST_CASE("lattice heat kernel equals the registered heat kernel's L entry for entry") {
  for (double h : {0.2, 0.1}) {
    CAPTURE(h);
    const Case c = sphere(h);
    const Operators ops = make_discretization("heat-kernel")->assemble(c.mesh, c.normals, Config());
    const std::optional<LatticeHeatKernelPair> pair = assemble_heat_kernel_lattice(c.mesh, c.normals, Config());
    REQUIRE(pair.has_value());
    CHECK(pair->L.rows() == ops.L.rows());
    CHECK(pair->L.nonzeros() == ops.L.nonZeros());  // the same pairs pass the cut-off
    const Eigen::SparseMatrix<double> L = pair->L.to_sparse();
    // Entries are products of O(1) rounded factors: 1e-13 of the largest entry is ~500 ulps.
    CHECK(max_abs(L - ops.L) <= 1e-13 * max_abs(ops.L));
    CHECK((pair->mass - ops.M.diagonal()).cwiseAbs().maxCoeff() == 0.0);
    CHECK((pair->L.diagonal() - ops.L.diagonal()).cwiseAbs().maxCoeff() <= 1e-13 * max_abs(ops.L));

    // Products for 1, 2, 3 (fixed-size accumulators) and 20 (the blocked general path) columns.
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> U(-1, 1);
    for (int k : {1, 2, 3, 20}) {
      CAPTURE(k);
      Eigen::MatrixXd X(L.rows(), k);
      for (Eigen::Index i = 0; i < X.size(); ++i) X.data()[i] = U(rng);
      const Eigen::MatrixXd expected = ops.L * X;
      Eigen::MatrixXd Yt;
      pair->L.multiply_transposed(X.transpose(), Yt);
      CHECK((Yt.transpose() - expected).cwiseAbs().maxCoeff() <= 1e-12 * expected.cwiseAbs().maxCoeff());
    }
  }
}

TEST_CASE("lattice heat kernel: products do not depend on the thread count") {
  const Case c = sphere(0.1);
  const auto pair = assemble_heat_kernel_lattice(c.mesh, c.normals, Config());
  REQUIRE(pair.has_value());
  const Eigen::MatrixXd Xt = Eigen::MatrixXd::Random(3, pair->L.rows());
  Eigen::MatrixXd a, b;
  set_thread_count(1);
  pair->L.multiply_transposed(Xt, a);
  const auto single = assemble_heat_kernel_lattice(c.mesh, c.normals, Config());
  set_thread_count(0);
  pair->L.multiply_transposed(Xt, b);
  CHECK(a == b);
  CHECK(single->L.diagonal() == pair->L.diagonal());
}

TEST_CASE("lattice heat kernel applies only where it equals the registered method") {
  const Case c = sphere(0.2);
  for (const char* kv : {"variant=primal", "mass=identity", "distance=tangent"}) {
    CAPTURE(kv);
    CHECK_FALSE(assemble_heat_kernel_lattice(c.mesh, c.normals, Config::from_key_values({kv})).has_value());
  }
  CHECK(assemble_heat_kernel_lattice(c.mesh, c.normals, Config::from_key_values({"cutoff=4", "k=0.2"})).has_value());
  CHECK_THROWS_AS(assemble_heat_kernel_lattice(c.mesh, c.normals, Config::from_key_values({"cutof=4"})), InputError);

  // Points off the lattice, or a step the points do not lie on: nullopt (use heat_kernel_matrix).
  Eigen::MatrixX3d x = c.mesh.face_centroids();
  const Eigen::VectorXd mu = Eigen::VectorXd::Constant(x.rows(), 0.01);
  CHECK(LatticeHeatKernel::build(x, mu, 0.01, 3.0, 0.1).has_value());
  CHECK_FALSE(LatticeHeatKernel::build(x, mu, 0.01, 3.0, 0.07).has_value());
  x(5, 1) += 0.003;
  CHECK_FALSE(LatticeHeatKernel::build(x, mu, 0.01, 3.0, 0.1).has_value());
  CHECK_THROWS_AS(LatticeHeatKernel::build(x, Eigen::VectorXd::Zero(x.rows()), 0.01, 3.0, 0.1), InputError);
  CHECK_THROWS_AS(LatticeHeatKernel::build(x, mu, -1.0, 3.0, 0.1), InputError);
}

TEST_CASE("conjugate_gradient on the lattice operator M - dt L equals the cg backend on the matrix") {
  const Case c = sphere(0.1);
  const Operators ops = make_discretization("heat-kernel")->assemble(c.mesh, c.normals, Config());
  const auto pair = assemble_heat_kernel_lattice(c.mesh, c.normals, Config());
  REQUIRE(pair.has_value());
  const double dt = 0.035 * 0.1;
  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(ops.L.rows(), 3);
  const Eigen::SparseMatrix<double> A = ops.M - dt * ops.L;
  auto cg = make_linear_solver("cg");
  cg->compute(A);
  const Eigen::MatrixXd expected = cg->solve(B);

  SymmetricOperator op;
  op.rows = pair->L.rows();
  op.diagonal = pair->mass - dt * pair->L.diagonal();
  op.multiply_transposed = [&](const Eigen::MatrixXd& Xt, Eigen::MatrixXd& Yt) {
    pair->L.multiply_transposed(Xt, Yt);
    Yt = Xt * pair->mass.asDiagonal() - dt * Yt;
  };
  SolverReport report;
  const Eigen::MatrixXd X = conjugate_gradient(op, B, Config(), &report);
  CHECK(report.status == SolverStatus::Success);
  CHECK(report.iterations == cg->info().iterations);
  CHECK(report.residual <= 1e-9);
  // Both stop at relative residual 1e-10 and A is well conditioned (kappa ~ 1.2): 1e-9 relative.
  CHECK((X - expected).cwiseAbs().maxCoeff() <= 1e-9 * expected.cwiseAbs().maxCoeff());

  // Errors name the problem.
  CHECK_THROWS_AS(conjugate_gradient(op, B, Config::from_key_values({"preconditioner=ichol"})), InputError);
  CHECK_THROWS_AS(conjugate_gradient(op, Eigen::MatrixXd::Ones(3, 1)), SolverError);
  SymmetricOperator indefinite = op;
  indefinite.diagonal[4] = -1.0;
  CHECK_THROWS_WITH_AS(conjugate_gradient(indefinite, B), doctest::Contains("row 4"), SolverError);
  SolverReport failed;
  CHECK_THROWS_WITH_AS(conjugate_gradient(op, B, Config::from_key_values({"max_iterations=1"}), &failed),
                       doctest::Contains("no convergence"), SolverError);
  CHECK(failed.status == SolverStatus::NoConvergence);
}
