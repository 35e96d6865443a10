#include "iterative.hpp"

#include <Eigen/IterativeLinearSolvers>
#include <algorithm>
#include <cmath>
#include <corrlap/backends/detail/block_cg.hpp>
#include <corrlap/backends/detail/solver_support.hpp>
#include <corrlap/backends/detail/symmetric_product.hpp>
#include <new>
#include <optional>
#include <sstream>

namespace corrlap {

using SpMat = Eigen::SparseMatrix<double>;

namespace {
using IncompleteCholesky = Eigen::IncompleteCholesky<double, Eigen::Lower, Eigen::AMDOrdering<int>>;
}  // namespace

// The iteration is detail::block_conjugate_gradient (every right-hand side in one pass over A);
// the preconditioners are applied to its k x n residual blocks.
struct ConjugateGradientSolver::Impl {
  std::string preconditioner = "jacobi";
  double tolerance = 1e-10;
  int max_iterations = 0;  // 0: 2 n (CG converges in n steps in exact arithmetic)
  bool warn = false;
  bool check_symmetry = true;

  SpMat A;                                  // CG needs the matrix at solve time
  Eigen::RowVectorXd inverse_diagonal;      // jacobi
  std::optional<IncompleteCholesky> ichol;  // ichol
  detail::Pattern pattern;
  SolverReport report;
  bool factored = false;

  void precondition(const Eigen::MatrixXd& Rt, Eigen::MatrixXd& Zt) const {
    if (preconditioner == "none") {
      Zt = Rt;
    } else if (preconditioner == "jacobi") {
      Zt = Rt.array().rowwise() * inverse_diagonal.array();
    } else {
      Zt.resize(Rt.rows(), Rt.cols());
      for (Eigen::Index c = 0; c < Rt.rows(); ++c) Zt.row(c) = ichol->solve(Rt.row(c).transpose()).transpose();
    }
  }
  void factorize_kept_matrix();
};

ConjugateGradientSolver::ConjugateGradientSolver() : impl_(std::make_unique<Impl>()) {}
ConjugateGradientSolver::~ConjugateGradientSolver() = default;

std::vector<ParameterInfo> ConjugateGradientSolver::options() const {
  return {
      {"preconditioner", "jacobi", "none | jacobi | ichol (incomplete Cholesky, AMD ordering)"},
      {"tolerance", "1e-10", "stop when |A x - b| <= tolerance |b| (per column)"},
      {"max_iterations", "0", "iteration limit per column (0: 2 n)"},
      {"on_no_convergence", "error", "error: throw SolverError; warn: return the last iterate, status no convergence"},
      {"check_symmetry", "true", "reject matrices with |A - A^T| > 1e-10 |A| (false: the caller vouches; A^T is used)"},
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
    s.factored = false;
  }
}

void ConjugateGradientSolver::analyze(const SpMat& A) {
  auto& s = *impl_;
  detail::check_matrix(A, "cg", false);
  Stopwatch watch;
  s.pattern.assign(A);
  s.factored = false;
  s.report = SolverReport{};
  s.report.status = SolverStatus::Success;
  s.report.analyze_seconds = watch.elapsed();
}

void ConjugateGradientSolver::factorize(const SpMat& A) {
  auto& s = *impl_;
  detail::check_same_pattern(s.pattern, A, "cg");
  detail::check_matrix(A, "cg", s.check_symmetry);
  s.factored = false;
  try {
    s.A = A;
  } catch (const std::bad_alloc&) {
    s.report.status = SolverStatus::OutOfMemory;
    throw SolverError(SolverStatus::OutOfMemory, "cg: out of memory while keeping the matrix");
  }
  s.factorize_kept_matrix();
}

void ConjugateGradientSolver::factorize_owned(SpMat&& A) {
  auto& s = *impl_;
  detail::check_same_pattern(s.pattern, A, "cg");
  detail::check_matrix(A, "cg", s.check_symmetry);
  s.factored = false;
  s.A.swap(A);  // kept without a copy; the caller's matrix is left empty
  A = SpMat();
  s.factorize_kept_matrix();
}

void ConjugateGradientSolver::Impl::factorize_kept_matrix() {
  Stopwatch watch;
  A.makeCompressed();
  // A non-positive diagonal entry makes A indefinite (and breaks the Jacobi preconditioner).
  const Eigen::VectorXd d = A.diagonal();
  for (Eigen::Index i = 0; i < d.size(); ++i)
    if (!(d[i] > 0.0)) {
      std::ostringstream os;
      os << "cg: matrix is not positive definite (diagonal entry " << d[i] << " at column " << i << ")";
      report.status = SolverStatus::NotPositiveDefinite;
      report.message = os.str();
      throw SolverError(SolverStatus::NotPositiveDefinite, os.str());
    }
  inverse_diagonal.resize(0);
  ichol.reset();
  try {
    if (preconditioner == "jacobi") inverse_diagonal = d.cwiseInverse().transpose();
    if (preconditioner == "ichol") {
      ichol.emplace();
      ichol->compute(A);
      if (ichol->info() != Eigen::Success) {
        report.status = SolverStatus::NotPositiveDefinite;
        report.message = "cg: the ichol preconditioner could not be built (matrix not positive definite?)";
        throw SolverError(SolverStatus::NotPositiveDefinite, report.message);
      }
    }
  } catch (const std::bad_alloc&) {
    report.status = SolverStatus::OutOfMemory;
    throw SolverError(SolverStatus::OutOfMemory, "cg: out of memory while building the preconditioner");
  }
  report.factorize_seconds = watch.elapsed();
  report.status = SolverStatus::Success;
  report.message.clear();
  factored = true;
}

namespace {

// Block CG on A X = B from X = 0, then the true residuals |A X - B| / |B| (not CG's recurrence
// estimates) checked against the tolerance. Fills `report` (iterations, residual, status, message);
// throws SolverError on a breakdown or no convergence (warn: returns the last finite iterate).
Eigen::MatrixXd run_block_cg(const detail::TransposedProduct& multiply, const Eigen::MatrixXd& B,
                             const detail::Preconditioner& precondition, double tolerance, int maxit,
                             const std::string& preconditioner, bool warn, SolverReport& report,
                             double preconditioned_tolerance = 0.0, const detail::ColumnSums& sum_over_parts = {}) {
  const detail::BlockCgResult cg = detail::block_conjugate_gradient(multiply, B, precondition, tolerance, maxit,
                                                                    preconditioned_tolerance, sum_over_parts);
  if (cg.breakdown_column >= 0) {
    std::ostringstream os;
    os << "cg: matrix is not positive definite (p^T A p = " << cg.breakdown_value << " in column "
       << cg.breakdown_column << " of the right-hand side, iteration " << cg.iterations + 1 << ")";
    report.status = SolverStatus::NotPositiveDefinite;
    report.message = os.str();
    throw SolverError(SolverStatus::NotPositiveDefinite, os.str());
  }
  const Eigen::MatrixXd& X = cg.X;
  Eigen::MatrixXd AXt;
  multiply(X.transpose(), AXt);
  // Squared norms per column of B, of the residual and of A X, over every process's rows.
  Eigen::ArrayXd squares(3 * B.cols());
  for (Eigen::Index j = 0; j < B.cols(); ++j) {
    squares[3 * j] = B.col(j).squaredNorm();
    squares[3 * j + 1] = (AXt.row(j).transpose() - B.col(j)).squaredNorm();
    squares[3 * j + 2] = AXt.row(j).squaredNorm();
  }
  if (sum_over_parts) sum_over_parts(squares);
  double worst = 0.0;
  Eigen::Index worst_column = 0;
  for (Eigen::Index j = 0; j < B.cols(); ++j) {
    const double nb = std::sqrt(squares[3 * j]);
    const double r = nb > 0 ? std::sqrt(squares[3 * j + 1]) / nb : std::sqrt(squares[3 * j + 2]);
    if (r >= worst) {
      worst = r;
      worst_column = j;
    }
  }
  report.iterations = cg.iterations;
  report.residual = worst;
  // CG stops on its recurrence residual; allow a small slack for the true one. The preconditioned
  // test is the caller's to check on the true residual (it costs one more application of P^{-1}).
  const bool accepted = preconditioned_tolerance > 0.0 || worst <= 10.0 * tolerance;
  if (!cg.converged || !std::isfinite(worst) || !accepted) {
    std::ostringstream os;
    os << "cg: no convergence: relative residual " << worst << " > tolerance " << tolerance << " after "
       << cg.iterations << " iterations (column " << worst_column << ", limit " << maxit << ", preconditioner "
       << preconditioner << ")";
    report.status = SolverStatus::NoConvergence;
    report.message = os.str();
    if (!warn || !X.allFinite()) throw SolverError(SolverStatus::NoConvergence, os.str());
    return X;
  }
  report.status = SolverStatus::Success;
  report.message.clear();
  return X;
}

}  // namespace

Eigen::MatrixXd ConjugateGradientSolver::solve(const Eigen::MatrixXd& B) {
  auto& s = *impl_;
  if (!s.factored) throw SolverError(SolverStatus::NotAnalyzed, "cg: solve() called before a successful factorize()");
  detail::check_rhs(B, s.A.rows(), "cg");
  Stopwatch watch;
  const int maxit = s.max_iterations > 0 ? s.max_iterations : int(2 * s.A.rows());
  try {
    Eigen::MatrixXd X = run_block_cg(
        [&](const Eigen::MatrixXd& Pt, Eigen::MatrixXd& Qt) { detail::symmetric_product_transposed(s.A, Pt, Qt); }, B,
        [&](const Eigen::MatrixXd& Rt, Eigen::MatrixXd& Zt) { s.precondition(Rt, Zt); }, s.tolerance, maxit,
        s.preconditioner, s.warn, s.report);
    s.report.solve_seconds = watch.elapsed();
    return X;
  } catch (const SolverError&) {
    s.report.solve_seconds = watch.elapsed();
    throw;
  }
}

Eigen::MatrixXd conjugate_gradient(const SymmetricOperator& A, const Eigen::MatrixXd& B, const Config& options,
                                   SolverReport* report) {
  options.check_keys({"tolerance", "preconditioned_tolerance", "max_iterations", "on_no_convergence"},
                     "conjugate_gradient");
  const double tol = options.get_double("tolerance", 1e-10);
  if (!(tol > 0.0 && tol < 1.0)) throw InputError("conjugate_gradient: config key 'tolerance' must be in (0, 1)");
  const double ptol = options.get_double("preconditioned_tolerance", 0.0);
  if (!(ptol >= 0.0) || !std::isfinite(ptol))
    throw InputError("conjugate_gradient: config key 'preconditioned_tolerance' must be a finite number >= 0");
  const int maxit_option = options.get_int("max_iterations", 0);
  if (maxit_option < 0) throw InputError("conjugate_gradient: config key 'max_iterations' must be >= 0");
  const std::string on = options.get_string("on_no_convergence", "error");
  if (on != "error" && on != "warn")
    throw InputError("conjugate_gradient: config key 'on_no_convergence' must be error or warn, got '" + on + "'");
  if (!A.multiply_transposed) throw InputError("conjugate_gradient: the operator has no product");
  const bool jacobi = !A.precondition_transposed;
  if (jacobi && A.diagonal.size() != A.rows)
    throw InputError("conjugate_gradient: diagonal of size " + std::to_string(A.diagonal.size()) + " for " +
                     std::to_string(A.rows) + " rows");
  detail::check_rhs(B, A.rows, "cg");
  SolverReport local;
  SolverReport& r = report ? *report : local;
  r = SolverReport{};
  for (Eigen::Index i = 0; i < A.diagonal.size(); ++i)
    if (!(A.diagonal[i] > 0.0)) {
      std::ostringstream os;
      os << "cg: operator is not positive definite (diagonal entry " << A.diagonal[i] << " at row " << i << ")";
      r.status = SolverStatus::NotPositiveDefinite;
      r.message = os.str();
      throw SolverError(SolverStatus::NotPositiveDefinite, os.str());
    }
  const Eigen::RowVectorXd inverse_diagonal =
      jacobi ? Eigen::RowVectorXd(A.diagonal.cwiseInverse().transpose()) : Eigen::RowVectorXd();
  Stopwatch watch;
  const int maxit = maxit_option > 0 ? maxit_option : int(2 * A.rows);
  const auto precondition = [&](const Eigen::MatrixXd& Rt, Eigen::MatrixXd& Zt) {
    if (jacobi)
      Zt = Rt.array().rowwise() * inverse_diagonal.array();
    else
      A.precondition_transposed(Rt, Zt);
  };
  Eigen::MatrixXd X = run_block_cg(A.multiply_transposed, B, precondition, tol, maxit, jacobi ? "jacobi" : "custom",
                                   on == "warn", r, ptol, A.sum_over_parts);
  r.solve_seconds = watch.elapsed();
  return X;
}

const SolverReport& ConjugateGradientSolver::info() const { return impl_->report; }

}  // namespace corrlap
