#include "iterative.hpp"

#include <Eigen/IterativeLinearSolvers>
#include <algorithm>
#include <cmath>
#include <corrlap/backends/detail/solver_support.hpp>
#include <new>
#include <sstream>
#include <variant>

namespace corrlap {

using SpMat = Eigen::SparseMatrix<double>;

namespace {
// Full (both triangles) products: the input matrices are stored symmetric.
constexpr int kUpLo = Eigen::Lower | Eigen::Upper;
using CgNone = Eigen::ConjugateGradient<SpMat, kUpLo, Eigen::IdentityPreconditioner>;
using CgJacobi = Eigen::ConjugateGradient<SpMat, kUpLo, Eigen::DiagonalPreconditioner<double>>;
using CgIchol =
    Eigen::ConjugateGradient<SpMat, kUpLo, Eigen::IncompleteCholesky<double, Eigen::Lower, Eigen::AMDOrdering<int>>>;
}  // namespace

struct ConjugateGradientSolver::Impl {
  std::string preconditioner = "jacobi";
  double tolerance = 1e-10;
  int max_iterations = 0;  // 0: 2 n (CG converges in n steps in exact arithmetic)
  bool warn = false;
  bool check_symmetry = true;

  std::variant<CgNone, CgJacobi, CgIchol> cg;
  SpMat A;  // CG needs the matrix at solve time
  detail::Pattern pattern;
  SolverReport report;
  bool factored = false;
  std::string built_preconditioner;

  void make_solver() {
    if (preconditioner == "none")
      cg.emplace<CgNone>();
    else if (preconditioner == "ichol")
      cg.emplace<CgIchol>();
    else
      cg.emplace<CgJacobi>();
    built_preconditioner = preconditioner;
  }
};

ConjugateGradientSolver::ConjugateGradientSolver() : impl_(std::make_unique<Impl>()) { impl_->make_solver(); }
ConjugateGradientSolver::~ConjugateGradientSolver() = default;

std::vector<ParameterInfo> ConjugateGradientSolver::options() const {
  return {
      {"preconditioner", "jacobi", "none | jacobi | ichol (incomplete Cholesky, AMD ordering)"},
      {"tolerance", "1e-10", "stop when |A x - b| <= tolerance |b| (per column)"},
      {"max_iterations", "0", "iteration limit per column (0: 2 n)"},
      {"on_no_convergence", "error", "error: throw SolverError; warn: return the last iterate, status no convergence"},
      {"check_symmetry", "true", "reject matrices with |A - A^T| > 1e-10 |A|"},
  };
}

void ConjugateGradientSolver::configure(const Config& options) {
  options.check_keys(detail::allowed_keys(this->options()), "linear solver 'cg'");
  auto& s = *impl_;
  const std::string pre = options.get_string("preconditioner", s.preconditioner);
  if (pre != "none" && pre != "jacobi" && pre != "ichol")
    throw InputError("linear solver 'cg': config key 'preconditioner' must be none, jacobi or ichol, got '" + pre +
                     "'");
  const double tol = options.get_double("tolerance", s.tolerance);
  if (!(tol > 0.0 && tol < 1.0)) throw InputError("linear solver 'cg': config key 'tolerance' must be in (0, 1)");
  const int maxit = options.get_int("max_iterations", s.max_iterations);
  if (maxit < 0) throw InputError("linear solver 'cg': config key 'max_iterations' must be >= 0");
  const std::string on = options.get_string("on_no_convergence", s.warn ? "warn" : "error");
  if (on != "error" && on != "warn")
    throw InputError("linear solver 'cg': config key 'on_no_convergence' must be error or warn, got '" + on + "'");
  s.tolerance = tol;
  s.max_iterations = maxit;
  s.warn = on == "warn";
  s.check_symmetry = options.get_bool("check_symmetry", s.check_symmetry);
  if (pre != s.preconditioner) {
    s.preconditioner = pre;
    s.make_solver();
    s.factored = false;
  }
}

void ConjugateGradientSolver::analyze(const SpMat& A) {
  auto& s = *impl_;
  detail::check_matrix(A, "cg", false);
  detail::Stopwatch watch;
  s.pattern.assign(A);
  s.factored = false;
  s.report = SolverReport{};
  s.report.status = SolverStatus::Success;
  s.report.analyze_seconds = watch.seconds();
}

void ConjugateGradientSolver::factorize(const SpMat& A) {
  auto& s = *impl_;
  detail::check_same_pattern(s.pattern, A, "cg");
  detail::check_matrix(A, "cg", s.check_symmetry);
  s.factored = false;
  detail::Stopwatch watch;
  try {
    s.A = A;
    s.A.makeCompressed();
    std::visit([&](auto& cg) { cg.compute(s.A); }, s.cg);
  } catch (const std::bad_alloc&) {
    s.report.status = SolverStatus::OutOfMemory;
    throw SolverError(SolverStatus::OutOfMemory, "cg: out of memory while building the preconditioner");
  }
  if (std::visit([](auto& cg) { return cg.info(); }, s.cg) != Eigen::Success) {
    s.report.status = SolverStatus::NotPositiveDefinite;
    s.report.message =
        "cg: the " + s.preconditioner + " preconditioner could not be built (matrix not positive definite?)";
    throw SolverError(SolverStatus::NotPositiveDefinite, s.report.message);
  }
  // A non-positive diagonal entry makes A indefinite (and breaks the Jacobi preconditioner).
  const Eigen::VectorXd d = s.A.diagonal();
  for (Eigen::Index i = 0; i < d.size(); ++i)
    if (!(d[i] > 0.0)) {
      std::ostringstream os;
      os << "cg: matrix is not positive definite (diagonal entry " << d[i] << " at column " << i << ")";
      s.report.status = SolverStatus::NotPositiveDefinite;
      s.report.message = os.str();
      throw SolverError(SolverStatus::NotPositiveDefinite, os.str());
    }
  s.report.factorize_seconds = watch.seconds();
  s.report.status = SolverStatus::Success;
  s.report.message.clear();
  s.factored = true;
}

Eigen::MatrixXd ConjugateGradientSolver::solve(const Eigen::MatrixXd& B) {
  auto& s = *impl_;
  if (!s.factored) throw SolverError(SolverStatus::NotAnalyzed, "cg: solve() called before a successful factorize()");
  detail::check_rhs(B, s.A.rows(), "cg");
  detail::Stopwatch watch;
  const int maxit = s.max_iterations > 0 ? s.max_iterations : int(2 * s.A.rows());
  Eigen::MatrixXd X(B.rows(), B.cols());
  int iterations = 0;
  double worst = 0.0;
  bool eigen_converged = true;
  Eigen::Index worst_column = 0;
  std::visit(
      [&](auto& cg) {
        cg.setTolerance(s.tolerance);
        cg.setMaxIterations(maxit);
        for (Eigen::Index j = 0; j < B.cols(); ++j) {
          X.col(j) = cg.solve(B.col(j));
          iterations = std::max(iterations, int(cg.iterations()));
          eigen_converged = eigen_converged && cg.info() == Eigen::Success;
          // The true residual, not CG's recurrence estimate.
          const double nb = B.col(j).norm();
          const double r = nb > 0 ? (s.A * X.col(j) - B.col(j)).norm() / nb : (s.A * X.col(j)).norm();
          if (r >= worst) {
            worst = r;
            worst_column = j;
          }
        }
      },
      s.cg);
  s.report.solve_seconds = watch.seconds();
  s.report.iterations = iterations;
  s.report.residual = worst;
  // Eigen stops on its recurrence residual; allow a small slack for the true one.
  if (!eigen_converged || !std::isfinite(worst) || worst > 10.0 * s.tolerance) {
    std::ostringstream os;
    os << "cg: no convergence: relative residual " << worst << " > tolerance " << s.tolerance << " after " << iterations
       << " iterations (column " << worst_column << ", limit " << maxit << ", preconditioner " << s.preconditioner
       << ")";
    s.report.status = SolverStatus::NoConvergence;
    s.report.message = os.str();
    if (!s.warn || !X.allFinite()) throw SolverError(SolverStatus::NoConvergence, os.str());
    return X;
  }
  s.report.status = SolverStatus::Success;
  s.report.message.clear();
  return X;
}

const SolverReport& ConjugateGradientSolver::info() const { return impl_->report; }

}  // namespace corrlap
