// The petsc and slepc backends (built with -DCORRLAP_WITH_PETSC=ON), run by tests/CMakeLists.txt
// under mpirun with 1, 2 and 4 ranks. Every rank hands the same serial matrices to the backend and
// must get the serial backends' results back: CHOLMOD's solutions, Spectra's eigenvalues.
#include <doctest/doctest.h>
#include <mpi.h>

#include <corrlap/backends/parallel.hpp>
#include <corrlap/backends/petsc.hpp>
#include <corrlap/backends/registry.hpp>
#include <corrlap/problems/problems.hpp>
#include <random>
#include <string>

#include "backends/fem_fixture.hpp"

using namespace corrlap;
using SpMat = Eigen::SparseMatrix<double>;

namespace {

// The test surfaces of the backend tests: the unit sphere at h = 0.1 (~1.9k vertices) and the
// torus R = 6, r = 2 at h = 0.5 (genus 1; a different spectrum and graph).
const test::FlatFem& surface(const std::string& name) {
  static const test::FlatFem sphere = test::flat_fem_sphere(0.1);
  static const test::FlatFem torus = test::flat_fem_shape("torus", 0.5, 10.0);
  return name == "torus" ? torus : sphere;
}
const std::vector<std::string> kSurfaces = {"sphere", "torus"};

std::unique_ptr<LinearSolver> petsc(const std::vector<std::string>& items) {
  return make_linear_solver("petsc", Config::from_key_values(items));
}

// The same pseudo-random right-hand sides on every rank (a fixed seed, a portable generator).
Eigen::MatrixXd random_columns(Eigen::Index rows, Eigen::Index cols, unsigned seed) {
  std::mt19937 generator(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  Eigen::MatrixXd B(rows, cols);
  for (Eigen::Index j = 0; j < cols; ++j)
    for (Eigen::Index i = 0; i < rows; ++i) B(i, j) = uniform(generator);
  return B;
}

Eigen::MatrixXd cholmod_solution(const SpMat& A, const Eigen::MatrixXd& B) {
  auto s = make_linear_solver("cholmod");
  s->compute(A);
  return s->solve(B);
}

double relative(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) { return (a - b).norm() / b.norm(); }

int mpi_size() {
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  return size;
}

}  // namespace

TEST_CASE("petsc with MUMPS's Cholesky equals CHOLMOD to 1e-10 on the sphere and the torus") {
  for (const std::string& name : kSurfaces) {
    CAPTURE(name);
    CAPTURE(mpi_size());
    const test::FlatFem& op = surface(name);
    // -L + M, and the pinned -L of the CLI's Poisson problem (problems.hpp).
    for (const SpMat& A : {test::shifted(op, 1.0), pinned_system(op.L)}) {
      const Eigen::MatrixXd B = random_columns(A.rows(), 2, 7);
      auto s = petsc({});  // the default: preonly + cholesky (mumps)
      s->compute(A);
      const Eigen::MatrixXd X = s->solve(B);
      CHECK(relative(X, cholmod_solution(A, B)) < 1e-10);
      CHECK(s->info().status == SolverStatus::Success);
      CHECK(s->info().residual < 1e-12);
      CHECK(s->info().message == "KSP CONVERGED_ITS");  // preonly: one application of the factor
    }
  }
}

TEST_CASE("petsc CG + GAMG and CG + hypre reach the KSP tolerance") {
  const double rtol = 1e-8;
  for (const std::string& name : kSurfaces)
    for (const char* pc : {"pc_type=gamg", "pc_type=hypre"}) {
      CAPTURE(name);
      CAPTURE(pc);
      const SpMat A = test::shifted(surface(name), 1.0);
      const Eigen::MatrixXd B = random_columns(A.rows(), 1, 11);
      auto s = petsc({"ksp_type=cg", pc, "rtol=1e-8"});
      s->compute(A);
      const Eigen::MatrixXd X = s->solve(B);
      // The true residual (the unpreconditioned norm is cg's test), and the error it allows: the
      // condition number of -L + M is below 1e3 on these surfaces.
      CHECK(s->info().residual <= 1.01 * rtol);
      CHECK(relative(X, cholmod_solution(A, B)) < 1e3 * rtol);
      CHECK(s->info().iterations > 1);
      CHECK(s->info().iterations < 100);  // multigrid: a few dozen at most, not CG's ~sqrt(cond)
      CHECK(s->info().message == "KSP CONVERGED_RTOL");
    }
}

TEST_CASE("petsc refactorizes a new matrix of the same pattern") {
  const test::FlatFem& op = surface("sphere");
  auto s = petsc({});
  s->analyze(test::shifted(op, 1.0));
  for (double c : {1.0, 0.25}) {
    CAPTURE(c);
    const SpMat A = test::shifted(op, c);
    s->factorize(A);
    const Eigen::MatrixXd B = random_columns(A.rows(), 1, 3);
    CHECK(relative(s->solve(B), cholmod_solution(A, B)) < 1e-10);
  }
  CHECK_THROWS_AS(s->factorize(pinned_system(op.L)), SolverError);  // another pattern
}

TEST_CASE("petsc on the singular -L: the constant null space, the mean-free solution") {
  const test::FlatFem& op = surface("sphere");
  const SpMat K = -op.L;
  // A compatible right-hand side (mean zero) and CHOLMOD's pinned solution, made mean-free.
  Eigen::VectorXd b = op.M * random_columns(K.rows(), 1, 5).col(0);
  b.array() -= b.mean();
  auto cholmod = make_linear_solver("cholmod");
  cholmod->compute(pinned_system(op.L));  // vertex 0 pinned to 0
  Eigen::VectorXd g = Eigen::VectorXd::Zero(K.rows());
  g.tail(K.rows() - 1) = cholmod->solve(b.tail(K.rows() - 1));
  g.array() -= g.mean();
  for (const std::vector<std::string>& items :
       std::vector<std::vector<std::string>>{{"ksp_type=cg", "pc_type=gamg", "rtol=1e-10"}, {}}) {
    CAPTURE(items.size());
    auto s = petsc(items);
    auto* backend = dynamic_cast<PetscLinearSolver*>(s.get());
    REQUIRE(backend != nullptr);
    s->compute(K);
    CHECK(backend->singular());
    const Eigen::VectorXd x = s->solve(b);
    CHECK(std::abs(x.mean()) < 1e-12 * x.norm());
    CHECK((x - g).norm() / g.norm() < 1e-6);
    CHECK(s->info().residual < 1e-9);
  }
  auto s = petsc({});
  s->compute(test::shifted(op, 1.0));
  CHECK_FALSE(dynamic_cast<PetscLinearSolver*>(s.get())->singular());
}

TEST_CASE("slepc eigenvalues equal the serial shift-invert ones to 1e-8") {
  const int k = 12;
  for (const std::string& name : kSurfaces) {
    CAPTURE(name);
    const test::FlatFem& op = surface(name);
    const EigenResult serial = make_eigen_solver("shift-invert")->solve(op.L, op.M, k);
    const EigenResult r = make_eigen_solver("slepc")->solve(op.L, op.M, k);
    REQUIRE(r.values.size() == k);
    CHECK(r.values[0] > -1e-8);  // -lambda >= 0: the sign convention of every eigen solver
    const double scale = serial.values.cwiseAbs().maxCoeff();
    CHECK((r.values - serial.values).cwiseAbs().maxCoeff() < 1e-8 * scale);
    const Eigen::MatrixXd gram = r.vectors.transpose() * op.M * r.vectors;
    CHECK((gram - Eigen::MatrixXd::Identity(k, k)).cwiseAbs().maxCoeff() < 1e-8);
    // L u = lambda M u for every pair: the residual relative to |M u| lambda's scale.
    const Eigen::MatrixXd residual = -op.L * r.vectors - op.M * r.vectors * r.values.asDiagonal();
    CHECK(residual.norm() < 1e-6 * scale * (op.M * r.vectors).norm());
  }
}

TEST_CASE("slepc LOBPCG with GAMG and hypre finds the same eigenvalues") {
  const test::FlatFem& op = surface("sphere");
  const int k = 9;  // the sphere's 1 + 3 + 5: closed clusters
  const EigenResult serial = make_eigen_solver("shift-invert")->solve(op.L, op.M, k);
  for (const char* pc : {"pc_type=gamg", "pc_type=hypre"}) {
    CAPTURE(pc);
    auto eig = make_eigen_solver("slepc", Config::from_key_values({"method=lobpcg", pc, "tolerance=1e-9"}));
    const EigenResult r = eig->solve(op.L, op.M, k);
    CHECK((r.values - serial.values).cwiseAbs().maxCoeff() < 1e-6 * serial.values.maxCoeff());
  }
}

TEST_CASE("petsc and slepc: bad options and divergence are errors that name the cause") {
  CHECK_THROWS_WITH_AS(petsc({"pc_type=ilu0"}), doctest::Contains("cholesky, gamg, hypre"), InputError);
  CHECK_THROWS_WITH_AS(petsc({"ksp_type=conjugate"}), doctest::Contains("conjugate"), InputError);
  CHECK_THROWS_WITH_AS(petsc({"tolerance=1e-8"}), doctest::Contains("tolerance"), InputError);
  CHECK_THROWS_WITH_AS(petsc({"rtol=2"}), doctest::Contains("rtol"), InputError);
  CHECK_THROWS_WITH_AS(make_eigen_solver("slepc", Config::from_key_values({"method=arnoldi"})),
                       doctest::Contains("shift-invert or lobpcg"), InputError);
  CHECK_THROWS_WITH_AS(make_eigen_solver("slepc", Config::from_key_values({"shift=0"})), doctest::Contains("shift"),
                       InputError);
  const SpMat A = test::shifted(surface("sphere"), 1e-3);
  const Eigen::MatrixXd B = random_columns(A.rows(), 1, 2);
  // Unpreconditioned CG needs far more than 5 iterations here: PETSc's reason is in the message.
  auto s = petsc({"ksp_type=cg", "pc_type=none", "max_it=5"});
  s->compute(A);
  CHECK_THROWS_WITH_AS(s->solve(B), doctest::Contains("DIVERGED_ITS after 5 iterations"), SolverError);
  CHECK(s->info().status == SolverStatus::NoConvergence);
  // A pass-through option with a value PETSc refuses.
  auto bad = petsc({"ksp_type=cg", "pc_type=gamg", "pc_gamg_type=nonsense"});
  CHECK_THROWS_WITH_AS(bad->compute(A), doctest::Contains("nonsense"), InputError);
  // ... and one PETSc takes.
  auto good = petsc({"ksp_type=cg", "pc_type=gamg", "pc_gamg_threshold=0.02", "rtol=1e-8"});
  good->compute(A);
  CHECK(good->solve(B).allFinite());
  // Indefinite (mu = 2 and 6 are the sphere's second and third values): CG stops with PETSc's reason.
  const SpMat indefinite = test::shifted(surface("sphere"), -3.0);
  auto cg = petsc({"ksp_type=cg", "pc_type=none"});
  cg->compute(indefinite);
  CHECK_THROWS_WITH_AS(cg->solve(B), doctest::Contains("DIVERGED_INDEFINITE"), SolverError);
}

TEST_CASE("process_rank is MPI's rank; only rank 0 is the output rank") {
  make_linear_solver("petsc");  // starts MPI
  int rank = -1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  CHECK(process_rank() == rank);
  CHECK(is_output_rank() == (rank == 0));
}
