// Linear solver backends behind the LinearSolver contract: accuracy, reuse of the symbolic
// analysis, and failure statuses.
#include <doctest/doctest.h>

#include <cmath>
#include <corrlap/backends/cholmod.hpp>
#include <corrlap/backends/detail/block_cg.hpp>
#include <corrlap/backends/detail/solver_support.hpp>
#include <corrlap/backends/detail/symmetric_product.hpp>
#include <corrlap/backends/eigen_direct.hpp>
#include <corrlap/backends/iterative.hpp>
#include <corrlap/backends/registry.hpp>
#include <random>
#include <string>

#include "backends/fem_fixture.hpp"

using namespace corrlap;
using SpMat = Eigen::SparseMatrix<double>;

namespace {

const test::FlatFem& sphere() {
  static const test::FlatFem op = test::flat_fem_sphere(0.1);  // ~1.9k vertices
  return op;
}

std::unique_ptr<LinearSolver> make(const std::string& items) {
  std::vector<std::string> kv;
  std::string cur;
  for (char c : items + " ") {
    if (c == ' ') {
      if (!cur.empty()) kv.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  return make_linear_solver(Config::from_key_values(kv));
}

// Relative error of the solution of A x = A x* against a random x*. A = -L + M has condition
// number ~ 1e3 here, so a backward-stable direct solver gives ~1e-13; CG is run to 1e-12.
double solve_error(LinearSolver& s, const SpMat& A, unsigned seed = 1) {
  std::srand(seed);
  const Eigen::VectorXd x = Eigen::VectorXd::Random(A.rows());
  const Eigen::VectorXd b = A * x;
  s.compute(A);
  const Eigen::VectorXd y = s.solve(b);
  return (y - x).norm() / x.norm();
}

SolverStatus status_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const SolverError& e) {
    return e.status();
  }
  return SolverStatus::Success;
}

SpMat diagonal(const std::vector<double>& d) {
  SpMat A(Eigen::Index(d.size()), Eigen::Index(d.size()));
  for (std::size_t i = 0; i < d.size(); ++i) A.insert(Eigen::Index(i), Eigen::Index(i)) = d[i];
  A.makeCompressed();
  return A;
}

const std::vector<std::string> kAllConfigs = {
    "solver=eigen-ldlt",
    "solver=eigen-llt",
    "solver=cholmod",
    "solver=cholmod supernodal=simplicial",
    "solver=cholmod supernodal=auto ordering=auto",
    "solver=cholmod ordering=metis",
    "solver=cholmod ordering=nesdis",
    "solver=cholmod ordering=best",
    "solver=cholmod long_index=true",
    "solver=cholmod supernodal=simplicial long_index=true ordering=metis",
    "solver=cholmod openmp_threads=1",
    "solver=cg preconditioner=none tolerance=1e-12",
    "solver=cg preconditioner=jacobi tolerance=1e-12",
    "solver=cg preconditioner=ichol tolerance=1e-12",
};

}  // namespace

TEST_CASE("registry lists every backend") {
  const auto names = linear_solver_registry().names();
  for (const char* n : {"cg", "cholmod", "eigen-ldlt", "eigen-llt"})
    CHECK(std::find(names.begin(), names.end(), n) != names.end());
}

TEST_CASE("every backend solves an SPD sphere system to tolerance") {
  const SpMat A = test::shifted(sphere(), 1.0);
  REQUIRE(A.rows() > 1500);
  for (const auto& cfg : kAllConfigs) {
    CAPTURE(cfg);
    auto s = make(cfg);
    const double err = solve_error(*s, A);
    CHECK(err < (cfg.find("cg") != std::string::npos ? 1e-9 : 1e-11));
    CHECK(s->info().status == SolverStatus::Success);
    if (s->name() == "cg") {
      CHECK(s->info().iterations > 0);
      CHECK(s->info().residual <= 1e-11);
    }
  }
}

TEST_CASE("multiple right-hand sides are solved column by column") {
  const SpMat A = test::shifted(sphere(), 0.5);
  std::srand(3);
  const Eigen::MatrixXd X = Eigen::MatrixXd::Random(A.rows(), 3);
  const Eigen::MatrixXd B = A * X;
  for (const char* cfg : {"solver=eigen-ldlt", "solver=cholmod", "solver=cg tolerance=1e-12"}) {
    CAPTURE(cfg);
    auto s = make(cfg);
    s->compute(A);
    CHECK((s->solve(B) - X).norm() / X.norm() < 1e-9);
  }
}

TEST_CASE("cholmod auto picks supernodal or simplicial and reports the ordering used") {
  CholmodSolver s;
  s.configure(Config::from_key_values({"supernodal=supernodal", "ordering=metis"}));
  s.compute(test::shifted(sphere(), 1.0));
  CHECK(s.is_supernodal());
  CHECK(s.ordering_used() == "metis");
  s.configure(Config::from_key_values({"supernodal=simplicial", "ordering=amd"}));
  s.compute(test::shifted(sphere(), 1.0));
  CHECK_FALSE(s.is_supernodal());
  CHECK(s.ordering_used() == "amd");
}

TEST_CASE("refactorization with new values reuses the symbolic analysis") {
  const SpMat A1 = test::shifted(sphere(), 1.0), A2 = test::shifted(sphere(), 0.01);
  std::srand(7);
  const Eigen::VectorXd x = Eigen::VectorXd::Random(A1.rows());
  SUBCASE("cholmod") {
    for (const char* mode : {"supernodal", "simplicial"}) {
      CAPTURE(mode);
      CholmodSolver s;
      s.configure(Config::from_key_values({std::string("supernodal=") + mode}));
      s.analyze(A1);
      s.factorize(A1);
      CHECK((s.solve(A1 * x) - x).norm() / x.norm() < 1e-11);
      s.factorize(A2);  // new values, same pattern: no new analysis
      CHECK(s.analysis_count() == 1);
      CHECK((s.solve(A2 * x) - x).norm() / x.norm() < 1e-9);
    }
  }
  SUBCASE("eigen") {
    for (auto kind : {EigenDirectSolver::Kind::LDLT, EigenDirectSolver::Kind::LLT}) {
      EigenDirectSolver s(kind);
      s.analyze(A1);
      s.factorize(A1);
      s.factorize(A2);
      CHECK(s.analysis_count() == 1);
      CHECK((s.solve(A2 * x) - x).norm() / x.norm() < 1e-9);
    }
  }
  SUBCASE("a different pattern is rejected, not silently mis-factored") {
    for (const char* cfg : {"solver=cholmod", "solver=eigen-ldlt", "solver=cg"}) {
      CAPTURE(cfg);
      auto s = make(cfg);
      s->analyze(A1);
      const SpMat D = diagonal(std::vector<double>(std::size_t(A1.rows()), 1.0));
      CHECK(status_of([&] { s->factorize(D); }) == SolverStatus::InvalidInput);
    }
  }
}

TEST_CASE("indefinite matrices are reported with the failing column") {
  // Pivot at column 2 is negative; every other one positive.
  const SpMat D = diagonal({1.0, 2.0, -3.0, 4.0, 5.0});
  for (const std::string cfg : {"solver=eigen-ldlt", "solver=eigen-llt", "solver=cholmod",
                                "solver=cholmod supernodal=simplicial", "solver=cg"}) {
    CAPTURE(cfg);
    auto s = make(cfg);
    try {
      s->compute(D);
      FAIL("no error for an indefinite matrix");
    } catch (const SolverError& e) {
      CHECK(e.status() == SolverStatus::NotPositiveDefinite);
      CHECK(std::string(e.what()).find("column 2") != std::string::npos);
    }
    CHECK(s->info().status == SolverStatus::NotPositiveDefinite);
  }
  // A genuinely indefinite FEM system: -L - 3 M has eigenvalues on both sides of 0.
  for (const char* cfg : {"solver=eigen-ldlt", "solver=eigen-llt", "solver=cholmod"}) {
    CAPTURE(cfg);
    auto s = make(cfg);
    CHECK(status_of([&] { s->compute(test::shifted(sphere(), -3.0)); }) == SolverStatus::NotPositiveDefinite);
  }
}

TEST_CASE("NaN/Inf, dimension mismatch and misuse give statuses") {
  SpMat bad = test::shifted(sphere(), 1.0);
  bad.coeffRef(5, 5) = std::nan("");
  const SpMat A = test::shifted(sphere(), 1.0);
  SpMat rect(4, 5);
  rect.insert(0, 0) = 1;
  SpMat nonsym = diagonal({2, 2, 2});
  nonsym.insert(0, 1) = 1.0;
  for (const std::string cfg : {"solver=eigen-ldlt", "solver=eigen-llt", "solver=cholmod", "solver=cg"}) {
    CAPTURE(cfg);
    auto s = make(cfg);
    CHECK(status_of([&] { s->solve(Eigen::VectorXd::Ones(3)); }) == SolverStatus::NotAnalyzed);
    CHECK(status_of([&] { s->compute(bad); }) == SolverStatus::NumericalIssue);
    CHECK(status_of([&] { s->compute(rect); }) == SolverStatus::InvalidInput);
    CHECK(status_of([&] { s->compute(nonsym); }) == SolverStatus::InvalidInput);
    s->compute(A);
    CHECK(status_of([&] { s->solve(Eigen::VectorXd::Ones(A.rows() + 1)); }) == SolverStatus::InvalidInput);
    Eigen::VectorXd b = Eigen::VectorXd::Ones(A.rows());
    b[3] = INFINITY;
    CHECK(status_of([&] { s->solve(b); }) == SolverStatus::NumericalIssue);
  }
}

TEST_CASE("cg non-convergence is an error unless the caller opts into a warning") {
  const SpMat A = test::shifted(sphere(), 1e-3);
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(A.rows());
  auto strict = make("solver=cg preconditioner=none max_iterations=3");
  strict->compute(A);
  try {
    strict->solve(b);
    FAIL("no error");
  } catch (const SolverError& e) {
    CHECK(e.status() == SolverStatus::NoConvergence);
    CHECK(std::string(e.what()).find("3 iterations") != std::string::npos);
  }
  auto lenient = make("solver=cg preconditioner=none max_iterations=3 on_no_convergence=warn");
  lenient->compute(A);
  const Eigen::VectorXd x = lenient->solve(b);
  CHECK(x.size() == A.rows());
  CHECK(lenient->info().status == SolverStatus::NoConvergence);
  CHECK(lenient->info().iterations == 3);
  CHECK(lenient->info().residual > 1e-10);
}

TEST_CASE("ichol needs fewer iterations than jacobi, which needs no more than none") {
  const SpMat A = test::shifted(sphere(), 1e-2);
  std::srand(11);
  const Eigen::VectorXd b = Eigen::VectorXd::Random(A.rows());
  int it[3];
  int i = 0;
  for (const char* p : {"none", "jacobi", "ichol"}) {
    auto s = make(std::string("solver=cg tolerance=1e-10 preconditioner=") + p);
    s->compute(A);
    s->solve(b);
    it[i++] = s->info().iterations;
  }
  MESSAGE("cg iterations none/jacobi/ichol: " << it[0] << " " << it[1] << " " << it[2]);
  CHECK(it[1] <= it[0]);
  CHECK(it[2] < it[1]);
}

TEST_CASE("unknown keys and names list the valid ones, key solver is accepted") {
  for (const char* name : {"eigen-ldlt", "eigen-llt", "cholmod", "cg"}) {
    CAPTURE(name);
    try {
      make(std::string("solver=") + name + " orderin=metis");
      FAIL("no error");
    } catch (const InputError& e) {
      const std::string msg = e.what();
      CHECK(msg.find("orderin") != std::string::npos);
      CHECK(msg.find("valid keys") != std::string::npos);
      CHECK(msg.find("check_symmetry") != std::string::npos);
    }
  }
  CHECK_THROWS_WITH_AS(make("solver=umfpack"), doctest::Contains("cholmod"), InputError);
  CHECK_THROWS_AS(make("solver=cholmod ordering=colamd"), InputError);
  CHECK_THROWS_AS(make("solver=cg preconditioner=ilu"), InputError);
  CHECK_THROWS_AS(make("solver=cg tolerance=2"), InputError);
  CHECK_NOTHROW(make("solver=cholmod ordering=metis supernodal=auto"));
}

TEST_CASE("symmetry_defect equals |A - A^T|_F without forming A^T (mirrors present, absent, uncompressed)") {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  std::uniform_int_distribution<int> index(0, 199);
  for (int trial = 0; trial < 4; ++trial) {
    std::vector<Eigen::Triplet<double>> t;
    for (int k = 0; k < 3000; ++k) {
      const int i = index(rng), j = index(rng);
      const double v = u(rng);
      t.emplace_back(i, j, v);
      // Trial 0: exactly symmetric; 1: mirrors with other values; 2-3: some mirrors missing.
      if (trial == 0 || (trial == 1) || (trial >= 2 && k % 3 != 0))
        t.emplace_back(j, i, trial == 1 ? v + 1e-3 * u(rng) : v);
    }
    Eigen::SparseMatrix<double> A(200, 200);
    A.setFromTriplets(t.begin(), t.end());
    const double readable = (A - Eigen::SparseMatrix<double>(A.transpose())).norm();
    const double fast = corrlap::detail::symmetry_defect(A);
    CAPTURE(trial);
    if (trial == 0) CHECK(fast == 0.0);
    CHECK(fast == doctest::Approx(readable).epsilon(1e-12));
    if (trial == 3) {
      A.coeffRef(5, 7) += 0.5;  // leaves A uncompressed
      REQUIRE(!A.isCompressed());
      CHECK(corrlap::detail::symmetry_defect(A) ==
            doctest::Approx((A - Eigen::SparseMatrix<double>(A.transpose())).norm()).epsilon(1e-12));
    }
  }
}

TEST_CASE("symmetric_product_transposed equals (A X)^T for symmetric A (1, 2, 3, 5 columns, uncompressed)") {
  SpMat A = test::shifted(sphere(), 1.0);
  std::srand(5);
  for (int k : {1, 2, 3, 5}) {  // the fixed-size paths and the general one
    CAPTURE(k);
    const Eigen::MatrixXd X = Eigen::MatrixXd::Random(A.rows(), k);
    const Eigen::MatrixXd readable = (A * X).transpose();
    Eigen::MatrixXd fast;
    corrlap::detail::symmetric_product_transposed(A, X.transpose(), fast);
    REQUIRE(fast.rows() == k);
    // Same terms summed in another order: round-off of a few ulps of the largest term.
    CHECK((fast - readable).cwiseAbs().maxCoeff() <= 1e-12 * readable.cwiseAbs().maxCoeff());
  }
  A.coeffRef(3, 3) += 1.0;  // a stored entry: stays symmetric; force the uncompressed layout
  A.reserve(Eigen::VectorXi::Constant(A.cols(), 2));
  REQUIRE(!A.isCompressed());
  const Eigen::MatrixXd X = Eigen::MatrixXd::Random(A.rows(), 3);
  Eigen::MatrixXd fast;
  corrlap::detail::symmetric_product_transposed(A, X.transpose(), fast);
  CHECK((fast - (A * X).transpose()).cwiseAbs().maxCoeff() <= 1e-12 * (A * X).cwiseAbs().maxCoeff());
}

TEST_CASE("block CG: every column as if solved alone, zero columns stay zero, breakdown is reported") {
  const SpMat A = test::shifted(sphere(), 1e-2);
  std::srand(9);
  Eigen::MatrixXd B = Eigen::MatrixXd::Random(A.rows(), 3);
  B.col(1).setZero();
  const Eigen::VectorXd inverse_diagonal = A.diagonal().cwiseInverse();
  const corrlap::detail::Preconditioner jacobi = [&](const Eigen::MatrixXd& Rt, Eigen::MatrixXd& Zt) {
    Zt = Rt.array().rowwise() * inverse_diagonal.transpose().array();
  };
  const auto block = corrlap::detail::block_conjugate_gradient(A, B, jacobi, 1e-10, 10000);
  REQUIRE(block.converged);
  CHECK(block.breakdown_column == -1);
  CHECK(block.X.col(1).isZero(0.0));
  int slowest = 0;
  for (Eigen::Index c : {0, 2}) {
    const auto alone = corrlap::detail::block_conjugate_gradient(A, B.col(c), jacobi, 1e-10, 10000);
    REQUIRE(alone.converged);
    slowest = std::max(slowest, alone.iterations);
    // The same recurrences, up to the order of the sums in the dot products: far closer than the
    // cond(A) 1e-10 that two solutions with relative residuals 1e-10 may differ by.
    CHECK((block.X.col(c) - alone.X).norm() <= 1e-9 * alone.X.norm());
    CHECK((A * block.X.col(c) - B.col(c)).norm() <= 1e-9 * B.col(c).norm());
  }
  CHECK(block.iterations == slowest);
  // diag(1, -1): p^T A p = 0 for b = (1, 1) in the first step.
  SpMat D = diagonal({1.0, -1.0});
  const auto none = [](const Eigen::MatrixXd& Rt, Eigen::MatrixXd& Zt) { Zt = Rt; };
  const auto broken = corrlap::detail::block_conjugate_gradient(D, Eigen::MatrixXd::Ones(2, 1), none, 1e-10, 100);
  CHECK(!broken.converged);
  CHECK(broken.breakdown_column == 0);
}

TEST_CASE("block CG: the preconditioned stopping test stops each column at its first small r^T P^{-1} r") {
  const SpMat A = test::shifted(sphere(), 1e-2);
  std::srand(10);
  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(A.rows(), 2);
  const Eigen::VectorXd inverse_diagonal = A.diagonal().cwiseInverse();
  const corrlap::detail::Preconditioner jacobi = [&](const Eigen::MatrixXd& Rt, Eigen::MatrixXd& Zt) {
    Zt = Rt.array().rowwise() * inverse_diagonal.transpose().array();
  };
  const auto preconditioned_norm = [&](const Eigen::VectorXd& r) {
    return std::sqrt(r.dot(inverse_diagonal.asDiagonal() * r));
  };
  const double initial = std::min(preconditioned_norm(B.col(0)), preconditioned_norm(B.col(1)));
  for (const double fraction : {1e-2, 1e-5}) {
    CAPTURE(fraction);
    const double target = fraction * initial;
    // The relative test alone would run to 1e-14: the preconditioned one stops first.
    const auto cg = corrlap::detail::block_conjugate_gradient(A, B, jacobi, 1e-14, 10000, target);
    REQUIRE(cg.converged);
    for (Eigen::Index c = 0; c < 2; ++c) {
      CAPTURE(c);
      // The true residual: the recurrence's drift on this well-conditioned system is far below 1%.
      CHECK(preconditioned_norm(B.col(c) - A * cg.X.col(c)) <= 1.01 * target);
      // Each column stops at its first iterate that meets the test: one iteration fewer does not.
      const auto alone = corrlap::detail::block_conjugate_gradient(A, B.col(c), jacobi, 1e-14, 10000, target);
      REQUIRE(alone.converged);
      CHECK((alone.X - cg.X.col(c)).norm() <= 1e-9 * alone.X.norm());
      REQUIRE(alone.iterations >= 1);
      const auto fewer = corrlap::detail::block_conjugate_gradient(A, B.col(c), jacobi, 1e-14, alone.iterations - 1);
      CHECK(preconditioned_norm(B.col(c) - A * fewer.X) > 0.99 * target);
    }
  }
  // The options key: refused when negative.
  SymmetricOperator op;
  op.rows = A.rows();
  op.multiply_transposed = [&](const Eigen::MatrixXd& Xt, Eigen::MatrixXd& Yt) {
    Yt = (A * Xt.transpose()).transpose();
  };
  op.diagonal = A.diagonal();
  Config bad;
  bad.set("preconditioned_tolerance", "-1");
  CHECK_THROWS_AS(conjugate_gradient(op, B, bad), InputError);
}

TEST_CASE("cg: compute(std::move(A)) keeps the matrix without a copy and solves as compute(A)") {
  const SpMat A = test::shifted(sphere(), 1.0);
  std::srand(3);
  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(A.rows(), 2);
  for (const char* cfg : {"solver=cg", "solver=cholmod"}) {
    CAPTURE(cfg);
    auto copied = make(cfg);
    copied->compute(A);
    const Eigen::MatrixXd X = copied->solve(B);
    auto owned = make(cfg);
    SpMat given = A;
    owned->compute(std::move(given));
    CHECK(given.nonZeros() == 0);  // the backend took it (cg) or dropped it (the default)
    const Eigen::MatrixXd Y = owned->solve(B);
    CHECK((X - Y).norm() <= 1e-14 * X.norm());
    // A new matrix with the analyzed pattern refactorizes through the owned path too.
    SpMat scaled = 2.0 * A;
    owned->factorize_owned(std::move(scaled));
    CHECK((owned->solve(B) - 0.5 * X).norm() <= 1e-9 * X.norm());
  }
}
