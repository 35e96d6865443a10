#include "spectra_eigs.hpp"

#include <algorithm>
#include <new>
#include <sstream>

#include <Eigen/Eigenvalues>
#include <Spectra/SymGEigsShiftSolver.h>

#include "registry.hpp"
#include "solver_support.hpp"

namespace corrlap {

using SpMat = Eigen::SparseMatrix<double>;

namespace {

void check_problem(const SpMat& L, const SpMat& M, int k, const std::string& who) {
  if (L.rows() != L.cols() || M.rows() != M.cols() || L.rows() != M.rows() || L.rows() == 0) {
    std::ostringstream os;
    os << who << ": L (" << L.rows() << " x " << L.cols() << ") and M (" << M.rows() << " x " << M.cols()
       << ") must be square, non-empty and of the same size";
    throw SolverError(SolverStatus::InvalidInput, os.str());
  }
  if (k < 1 || k > L.rows()) {
    std::ostringstream os;
    os << who << ": number of eigenpairs k = " << k << " must be in [1, " << L.rows() << "]";
    throw InputError(os.str());
  }
  detail::check_matrix(L, who + " (L)", true);
  detail::check_matrix(M, who + " (M)", true);
}

/// Spectra operator y = (K - sigma M)^{-1} x with K = -L, applied by a LinearSolver.
class ShiftInvertOp {
 public:
  using Scalar = double;
  ShiftInvertOp(const SpMat& L, const SpMat& M, LinearSolver& solver) : L_(L), M_(M), solver_(solver) {}
  Eigen::Index rows() const { return L_.rows(); }
  Eigen::Index cols() const { return L_.rows(); }
  void set_shift(double sigma) {
    SpMat A = -L_ - sigma * M_;  // K - sigma M, SPD for sigma < 0
    A.makeCompressed();
    solver_.compute(A);
  }
  void perform_op(const double* x_in, double* y_out) const {
    const Eigen::Map<const Eigen::VectorXd> x(x_in, rows());
    Eigen::Map<Eigen::VectorXd>(y_out, rows()) = solver_.solve(x);
  }

 private:
  const SpMat& L_;
  const SpMat& M_;
  LinearSolver& solver_;
};

/// Spectra's B operator: y = M x (full symmetric storage).
class MassOp {
 public:
  using Scalar = double;
  explicit MassOp(const SpMat& M) : M_(M) {}
  Eigen::Index rows() const { return M_.rows(); }
  Eigen::Index cols() const { return M_.cols(); }
  void perform_op(const double* x_in, double* y_out) const {
    Eigen::Map<Eigen::VectorXd>(y_out, rows()) = M_ * Eigen::Map<const Eigen::VectorXd>(x_in, rows());
  }

 private:
  const SpMat& M_;
};

EigenResult dense_solve(const SpMat& L, const SpMat& M, int k) {
  const Eigen::MatrixXd K = -Eigen::MatrixXd(L);
  const Eigen::MatrixXd Md = Eigen::MatrixXd(M);
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(K, Md);  // ascending mu
  if (es.info() != Eigen::Success)
    throw SolverError(SolverStatus::NotPositiveDefinite,
                      "dense eigen solver: failed (M must be symmetric positive definite)");
  EigenResult r;
  r.values = es.eigenvalues().head(k);
  r.vectors = es.eigenvectors().leftCols(k);
  return r;
}

}  // namespace

// ---------------------------------------------------------------------------------------------

std::vector<ParameterInfo> DenseEigenSolver::options() const {
  return {{"max_n", "6000", "refuse larger problems (dense O(n^3) time, O(n^2) memory)"}};
}

void DenseEigenSolver::configure(const Config& options) {
  options.check_keys(detail::allowed_keys(this->options()), "eigen solver 'dense'");
  max_n_ = options.get_int("max_n", max_n_);
}

EigenResult DenseEigenSolver::solve(const SpMat& L, const SpMat& M, int k) {
  check_problem(L, M, k, "dense eigen solver");
  if (L.rows() > max_n_)
    throw InputError("dense eigen solver: n = " + std::to_string(L.rows()) + " exceeds max_n = " +
                     std::to_string(max_n_) + "; use the shift-invert solver");
  return dense_solve(L, M, k);
}

// ---------------------------------------------------------------------------------------------

struct ShiftInvertEigenSolver::Impl {
  double shift = -1e-3;
  int ncv = 0;
  int max_iterations = 1000;
  double tolerance = 1e-10;
  int dense_threshold = 400;
  Config linear_config;  // includes "solver"
  SolverReport last_report;
};

ShiftInvertEigenSolver::ShiftInvertEigenSolver() : impl_(std::make_unique<Impl>()) {}
ShiftInvertEigenSolver::~ShiftInvertEigenSolver() = default;

std::vector<ParameterInfo> ShiftInvertEigenSolver::options() const {
  return {
      {"solver", "cholmod", "linear solver for (K - shift M)^{-1}; its options may be given too"},
      {"shift", "-0.001", "shift in units of mu = -lambda; must be < 0 (K - shift M must be positive definite)"},
      {"ncv", "0", "Lanczos basis size (0: max(2k + 1, k + 20), at most n)"},
      {"max_iterations", "1000", "restarts of the Lanczos iteration"},
      {"tolerance", "1e-10", "relative accuracy of the Ritz values"},
      {"dense_threshold", "400", "use the dense solver when n <= this"},
  };
}

void ShiftInvertEigenSolver::configure(const Config& options) {
  auto& s = *impl_;
  std::vector<std::string> own;
  for (const auto& o : this->options()) own.push_back(o.name);
  // Keys other than ours belong to the linear solver; check them against it for a clear error.
  const std::string solver_name = options.get_string("solver", "cholmod");
  auto linear = linear_solver_registry().create(solver_name);
  std::vector<std::string> allowed = own;
  for (const auto& o : linear->options()) allowed.push_back(o.name);
  options.check_keys(allowed, "eigen solver 'shift-invert' (with linear solver '" + solver_name + "')");
  Config linear_config = detail::without_keys(options, own);
  linear_config.set("solver", solver_name);
  linear->configure(linear_config);

  const double shift = options.get_double("shift", s.shift);
  if (!(shift < 0.0)) throw InputError("eigen solver 'shift-invert': config key 'shift' must be < 0 (mu = -lambda >= 0)");
  const int ncv = options.get_int("ncv", s.ncv);
  const int maxit = options.get_int("max_iterations", s.max_iterations);
  const double tol = options.get_double("tolerance", s.tolerance);
  const int dense = options.get_int("dense_threshold", s.dense_threshold);
  if (ncv < 0 || maxit < 1 || !(tol > 0.0) || dense < 0)
    throw InputError("eigen solver 'shift-invert': ncv >= 0, max_iterations >= 1, tolerance > 0, dense_threshold >= 0");
  s.shift = shift;
  s.ncv = ncv;
  s.max_iterations = maxit;
  s.tolerance = tol;
  s.dense_threshold = dense;
  s.linear_config = linear_config;
}

EigenResult ShiftInvertEigenSolver::solve(const SpMat& L, const SpMat& M, int k) {
  auto& s = *impl_;
  check_problem(L, M, k, "shift-invert eigen solver");
  const Eigen::Index n = L.rows();
  // Spectra needs k < ncv <= n; tiny problems go dense.
  if (n <= s.dense_threshold || k + 2 > n) return dense_solve(L, M, k);

  auto linear = make_linear_solver(s.linear_config, "cholmod");
  ShiftInvertOp op(L, M, *linear);
  MassOp bop(M);
  const int ncv = int(std::min<Eigen::Index>(n, s.ncv > 0 ? std::max(s.ncv, k + 2) : std::max(2 * k + 1, k + 20)));
  Spectra::SymGEigsShiftSolver<ShiftInvertOp, MassOp, Spectra::GEigsMode::ShiftInvert> eigs(op, bop, k, ncv, s.shift);
  eigs.init();
  const Eigen::Index nconv =
      eigs.compute(Spectra::SortRule::LargestMagn, s.max_iterations, s.tolerance, Spectra::SortRule::SmallestAlge);
  s.last_report = linear->info();
  if (eigs.info() != Spectra::CompInfo::Successful || nconv < k) {
    std::ostringstream os;
    os << "shift-invert eigen solver: only " << nconv << " of " << k << " eigenpairs converged after "
       << eigs.num_iterations() << " restarts (ncv " << ncv << ", tolerance " << s.tolerance
       << "); increase ncv or max_iterations";
    throw SolverError(SolverStatus::NoConvergence, os.str());
  }
  EigenResult r;
  r.values = eigs.eigenvalues();  // mu = -lambda, ascending (SmallestAlge sorting)
  r.vectors = eigs.eigenvectors();
  r.iterations = int(eigs.num_iterations());
  return r;
}

SolverReport ShiftInvertEigenSolver::linear_solver_report() const { return impl_->last_report; }

}  // namespace corrlap
