#include "spectra_eigs.hpp"

#include <Spectra/SymGEigsShiftSolver.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <corrlap/backends/detail/blas_threads.hpp>
#include <corrlap/backends/detail/block_lanczos.hpp>
#include <corrlap/backends/detail/solver_support.hpp>
#include <new>
#include <random>
#include <sstream>

#include "registry.hpp"

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

/// Spectra operator y = P (K - sigma M)^{-1} x with K = -L, applied by a LinearSolver. P = I is
/// the plain shift-invert; with a deflation basis X (M-orthonormal eigenvectors already found),
/// P = I - X X^T M removes them, so that a later run sees only the rest of the spectrum (P commutes
/// with the operator, which stays self-adjoint for the M inner product).
class ShiftInvertOp {
 public:
  using Scalar = double;
  ShiftInvertOp(const SpMat& L, const SpMat& M, LinearSolver& solver) : L_(L), M_(M), solver_(solver) {}
  Eigen::Index rows() const { return L_.rows(); }
  Eigen::Index cols() const { return L_.rows(); }
  void set_shift(double sigma) {
    if (factorized_ && sigma == sigma_) return;  // deflation runs reuse the factorization
    SpMat A = -L_ - sigma * M_;                  // K - sigma M, SPD for sigma < 0
    A.makeCompressed();
    solver_.compute(A);
    factorized_ = true;
    sigma_ = sigma;
  }
  void perform_op(const double* x_in, double* y_out) const {
    const Eigen::Map<const Eigen::VectorXd> x(x_in, rows());
    Eigen::Map<Eigen::VectorXd> y(y_out, rows());
    y = solver_.solve(x);
    if (X_ != nullptr && X_->cols() > 0) y -= *X_ * (MX_.transpose() * y);
  }
  /// P (K - sigma M)^{-1} M X for a block X given as its M-image MX: the operator S of the block
  /// Lanczos (one multi-column solve). set_shift must have been called.
  Eigen::MatrixXd apply_block(const Eigen::MatrixXd& MX) const {
    Eigen::MatrixXd Y = solver_.solve(MX);
    if (X_ != nullptr && X_->cols() > 0) Y -= *X_ * (MX_.transpose() * Y);
    return Y;
  }
  /// Deflate the columns of X (M-orthonormal); nullptr: none.
  void deflate(const Eigen::MatrixXd* X) {
    X_ = X;
    if (X != nullptr) MX_ = M_ * *X;
  }
  /// P v for a start vector.
  Eigen::VectorXd project(const Eigen::VectorXd& v) const {
    if (X_ == nullptr || X_->cols() == 0) return v;
    return v - *X_ * (MX_.transpose() * v);
  }

 private:
  const SpMat& L_;
  const SpMat& M_;
  LinearSolver& solver_;
  bool factorized_ = false;
  double sigma_ = 0.0;
  const Eigen::MatrixXd* X_ = nullptr;
  Eigen::MatrixXd MX_;
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

/// The Lanczos basis size of a run for `nev` pairs: ncv, or max(2 nev + 1, nev + 20), at most n.
int basis_size(Eigen::Index n, int nev, int ncv) {
  return int(std::min<Eigen::Index>(n, ncv > 0 ? std::max(ncv, nev + 2) : std::max(2 * nev + 1, nev + 20)));
}

/// Whether the dense solver is cheaper than Lanczos with a basis of `basis` vectors. The dense solve
/// costs O(n^3), a shift-invert run O(n basis^2) (orthogonalization against the basis dominates), so
/// the crossing is at n proportional to basis, not at a fixed size; the constant comes from the
/// costs measured on digitized spheres (docs/backends.md, "Dense or Lanczos").
bool dense_is_cheaper(Eigen::Index n, int basis) { return n <= 2 * Eigen::Index(basis); }

/// block_size=auto: blocks pay once the basis no longer fits in cache and streaming it per vector
/// dominates; the threshold is where the two runs cross on digitized spheres (bench/RESULTS.md,
/// "Scale on one machine", eigenpairs again).
int block_size_for(Eigen::Index n) { return n >= 4000 ? 16 : 1; }

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
  r.method = "dense";
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
    throw InputError("dense eigen solver: n = " + std::to_string(L.rows()) +
                     " exceeds max_n = " + std::to_string(max_n_) + "; use the shift-invert solver");
  return dense_solve(L, M, k);
}

// ---------------------------------------------------------------------------------------------

struct ShiftInvertEigenSolver::Impl {
  double shift = -1e-3;
  int ncv = 0;
  int guard = -1;  // -1: automatic
  bool verify = true;
  int max_iterations = 1000;
  double tolerance = 1e-10;
  int dense_threshold = -1;    // -1: by cost (dense_is_cheaper)
  int block_size = 0;          // 0: auto (block_size_for)
  Config linear_config;        // includes "solver"
  Eigen::MatrixX3d positions;  // ordering hint for the linear solver
  SolverReport last_report;
};

ShiftInvertEigenSolver::ShiftInvertEigenSolver() : impl_(std::make_unique<Impl>()) {}
ShiftInvertEigenSolver::~ShiftInvertEigenSolver() = default;

std::vector<ParameterInfo> ShiftInvertEigenSolver::options() const {
  return {
      {"solver", kDefaultLinearSolver, "linear solver for (K - shift M)^{-1}; its options may be given too"},
      {"shift", "-0.001", "shift in units of mu = -lambda; must be < 0 (K - shift M must be positive definite)"},
      {"ncv", "0",
       "Lanczos basis size (0: for m = k + guard, max(2m + 1, m + 20) single-vector, max(3m, m + 8 block_size) "
       "block; at most n)"},
      {"guard", "auto",
       "extra eigenpairs computed and dropped so that a multiple eigenvalue at position k "
       "gets all its copies (auto: max(6, k/4))"},
      {"verify", "true",
       "deflate the pairs found and probe the rest of the spectrum for missed copies (a short block run; "
       "the full search only when the probe does not rule them out)"},
      {"block_size", "auto",
       "vectors per Lanczos block (block Lanczos, BLAS-3 solves and orthogonalization); 1: Spectra's "
       "single-vector Lanczos; auto: 16 from 4 000 unknowns, 1 below (measured)"},
      {"max_iterations", "1000", "restarts of the Lanczos iteration"},
      {"tolerance", "1e-10", "relative accuracy of the Ritz values"},
      {"dense_threshold", "auto",
       "use the dense solver when n <= this; auto: when it is the cheaper one, n <= 2 x the Lanczos basis size "
       "(measured, docs/backends.md)"},
  };
}

void ShiftInvertEigenSolver::configure(const Config& options) {
  auto& s = *impl_;
  std::vector<std::string> own;
  for (const auto& o : this->options()) own.push_back(o.name);
  // Keys other than ours belong to the linear solver; check them against it for a clear error.
  const std::string solver_name = options.get_string("solver", kDefaultLinearSolver);
  auto linear = linear_solver_registry().create(solver_name);
  std::vector<std::string> allowed = own;
  for (const auto& o : linear->options()) allowed.push_back(o.name);
  options.check_keys(allowed, "eigen solver 'shift-invert' (with linear solver '" + solver_name + "')");
  Config linear_config = detail::without_keys(options, own);
  linear_config.set("solver", solver_name);
  linear->configure(linear_config);

  const double shift = options.get_double("shift", s.shift);
  if (!(shift < 0.0))
    throw InputError("eigen solver 'shift-invert': config key 'shift' must be < 0 (mu = -lambda >= 0)");
  const int ncv = options.get_int("ncv", s.ncv);
  const std::string guard_text = options.get_string("guard", "auto");
  const int guard = guard_text == "auto" ? -1 : options.get_int("guard", 0);
  if (guard_text != "auto" && guard < 0) throw InputError("eigen solver 'shift-invert': guard must be >= 0 or auto");
  const int maxit = options.get_int("max_iterations", s.max_iterations);
  const std::string block_text = options.get_string("block_size", "auto");
  const int block = block_text == "auto" ? 0 : options.get_int("block_size", 1);
  if (block_text != "auto" && block < 1)
    throw InputError("eigen solver 'shift-invert': block_size must be >= 1 or auto");
  const double tol = options.get_double("tolerance", s.tolerance);
  const std::string dense_text = options.get_string("dense_threshold", "auto");
  const int dense = dense_text == "auto" ? -1 : options.get_int("dense_threshold", 0);
  if (ncv < 0 || maxit < 1 || !(tol > 0.0) || (dense_text != "auto" && dense < 0))
    throw InputError(
        "eigen solver 'shift-invert': ncv >= 0, max_iterations >= 1, tolerance > 0, dense_threshold >= 0 or auto");
  s.shift = shift;
  s.ncv = ncv;
  s.guard = guard;
  s.verify = options.get_bool("verify", s.verify);
  s.max_iterations = maxit;
  s.block_size = block;
  s.tolerance = tol;
  s.dense_threshold = dense;
  s.linear_config = linear_config;
}

EigenResult ShiftInvertEigenSolver::solve(const SpMat& L, const SpMat& M, int k) {
  auto& s = *impl_;
  check_problem(L, M, k, "shift-invert eigen solver");
  const Eigen::Index n = L.rows();
  // Spectra needs k < ncv <= n; tiny problems go dense.
  const int guard_wanted = s.guard >= 0 ? s.guard : std::max(6, k / 4);
  const int nev = k + int(std::max<Eigen::Index>(0, std::min<Eigen::Index>(guard_wanted, n - 2 - k)));
  const bool dense = s.dense_threshold >= 0 ? n <= s.dense_threshold : dense_is_cheaper(n, basis_size(n, nev, s.ncv));
  if (dense || k + 2 > n) return dense_solve(L, M, k);

  auto linear = make_linear_solver(s.linear_config, kDefaultLinearSolver);
  if (s.positions.rows() == n) linear->set_positions(s.positions);
  ShiftInvertOp op(L, M, *linear);
  MassOp bop(M);
  // The factorization with OpenBLAS as configured; the iteration's many small BLAS calls on one
  // thread (detail/blas_threads.hpp: idle OpenBLAS workers spin, and gain nothing here).
  op.set_shift(s.shift);
  const detail::SerialBlasScope serial_blas;
  int restarts = 0;
  int block_runs = 0;
  const int block_size = s.block_size > 0 ? s.block_size : block_size_for(n);
  // One Lanczos run for the `nev` smallest mu of the (possibly deflated) problem, ascending.
  const auto run = [&](int nev, const Eigen::VectorXd* start, Eigen::VectorXd& values, Eigen::MatrixXd& vectors) {
    if (block_size > 1) {
      // Block Lanczos (detail/block_lanczos.hpp); the single-vector run below is the fallback when
      // it stops without converging (a basis that lost rank, restarts exhausted).
      op.set_shift(s.shift);
      detail::BlockLanczosOptions o;
      o.block_size = block_size;
      o.max_basis = s.ncv;
      o.max_restarts = s.max_iterations;
      o.tolerance = s.tolerance;
      o.wanted = std::min(nev, k);
      o.seed = 12345u + unsigned(block_runs++);
      const detail::BlockLanczosResult r =
          detail::block_lanczos([&](const Eigen::MatrixXd& MX) { return op.apply_block(MX); }, M, nev, o);
      s.last_report = linear->info();
      if (r.converged) {
        restarts += r.restarts;
        values = s.shift + r.theta.cwiseInverse().array();  // theta = 1 / (mu - sigma), descending
        vectors = r.vectors;
        return;
      }
    }
    const int ncv = basis_size(n, nev, s.ncv);
    Spectra::SymGEigsShiftSolver<ShiftInvertOp, MassOp, Spectra::GEigsMode::ShiftInvert> eigs(op, bop, nev, ncv,
                                                                                              s.shift);
    if (start)
      eigs.init(start->data());
    else
      eigs.init();
    const Eigen::Index nconv =
        eigs.compute(Spectra::SortRule::LargestMagn, s.max_iterations, s.tolerance, Spectra::SortRule::SmallestAlge);
    restarts += int(eigs.num_iterations());
    s.last_report = linear->info();
    if (eigs.info() != Spectra::CompInfo::Successful || nconv < nev) {
      std::ostringstream os;
      os << "shift-invert eigen solver: only " << nconv << " of " << nev << " eigenpairs (" << k
         << " asked) converged after " << eigs.num_iterations() << " restarts (ncv " << ncv << ", tolerance "
         << s.tolerance << "); increase ncv or max_iterations";
      throw SolverError(SolverStatus::NoConvergence, os.str());
    }
    values = eigs.eigenvalues();  // mu = -lambda, ascending (SmallestAlge sorting)
    vectors = eigs.eigenvectors();
  };

  // Verification's first step, a probe of the deflated operator (the pairs found projected out):
  // its largest theta = 1 / (mu - shift) is the smallest mu not found. A short block run from a
  // random start estimates it by a Ritz value theta_1 <= theta_max with a residual r_1 that bounds
  // theta_max - theta_1 once theta_1 estimates the top eigenvalue. It stops as soon as that decides
  // against the k-th value: complete (theta_1 + r_1 below its theta) or a copy missed (theta_1
  // above it). It usually decides in a few block steps, far fewer than the full search below
  // (docs/backends.md, "Eigen solvers").
  enum class Probe { Complete, Missed, Undecided };
  const auto probe = [&](double kth) {
    const int b = int(std::min<Eigen::Index>(std::max(block_size, 4), n - 3));
    if (b < 1) return Probe::Undecided;
    const double bound = 1.0 / (kth - 1e-9 * std::max(1.0, std::abs(kth)) - s.shift);
    detail::BlockLanczosOptions o;
    o.block_size = b;
    o.max_restarts = s.max_iterations;
    o.tolerance = s.tolerance;
    o.seed = 777u + unsigned(block_runs++);
    o.stop = [&](const Eigen::VectorXd& theta, const Eigen::VectorXd& r) {
      return theta[0] + r[0] < bound || theta[0] > bound;
    };
    const detail::BlockLanczosResult r =
        detail::block_lanczos([&](const Eigen::MatrixXd& MX) { return op.apply_block(MX); }, M, 1, o);
    if (!r.converged && !r.stopped) return Probe::Undecided;
    restarts += r.restarts;
    if (r.theta[0] + r.residuals[0] < bound) return Probe::Complete;
    return r.theta[0] > bound ? Probe::Missed : Probe::Undecided;
  };

  // Lanczos from one start vector sees the extra copies of a multiple eigenvalue only through
  // rounding, so it can converge with a copy missing and the next eigenvalue in its place (seen on
  // a digitized sphere: 7.897 x3 at positions 10-12 came out as 7.897 x2, 9.607; on a periodic grid
  // whole copies of 4- and 8-fold eigenvalues). Two defences: (1) `guard` extra eigenpairs, dropped
  // at the end; (2) verification: deflate everything found and look for eigenvalues below the k-th
  // in the rest of the spectrum (the probe, then a full search when it does not rule them out); add
  // them and repeat until there are none.
  Eigen::VectorXd values;
  Eigen::MatrixXd vectors;
  run(nev, nullptr, values, vectors);
  std::mt19937 rng(12345);  // fixed: the result is reproducible
  std::normal_distribution<double> normal;
  for (int round = 0; s.verify && round < 64; ++round) {
    const int m = int(std::min<Eigen::Index>(std::max(guard_wanted, 3), n - vectors.cols() - 2));
    if (m < 1) break;  // (almost) the whole space is found: nothing left to verify
    op.deflate(&vectors);
    if (probe(values[k - 1]) == Probe::Complete) {
      op.deflate(nullptr);
      break;
    }
    Eigen::VectorXd start(n);
    for (Eigen::Index i = 0; i < n; ++i) start[i] = normal(rng);
    start = op.project(start);
    Eigen::VectorXd more_values;
    Eigen::MatrixXd more_vectors;
    run(m, &start, more_values, more_vectors);
    op.deflate(nullptr);
    const double kth = values[k - 1];
    if (more_values[0] >= kth - 1e-9 * std::max(1.0, std::abs(kth))) break;  // complete
    // Merge and sort by value (stable: ties keep the earlier pair first).
    const Eigen::Index p = values.size(), q = more_values.size();
    Eigen::VectorXd all_values(p + q);
    all_values << values, more_values;
    Eigen::MatrixXd all_vectors(n, p + q);
    all_vectors << vectors, more_vectors;
    std::vector<Eigen::Index> order(std::size_t(p + q));
    for (Eigen::Index i = 0; i < p + q; ++i) order[std::size_t(i)] = i;
    std::stable_sort(order.begin(), order.end(),
                     [&](Eigen::Index a, Eigen::Index b) { return all_values[a] < all_values[b]; });
    values.resize(p + q);
    vectors.resize(n, p + q);
    for (Eigen::Index i = 0; i < p + q; ++i) {
      values[i] = all_values[order[std::size_t(i)]];
      vectors.col(i) = all_vectors.col(order[std::size_t(i)]);
    }
  }
  EigenResult r;
  r.values = values.head(k);
  r.vectors = vectors.leftCols(k);
  r.iterations = restarts;
  r.method = "lanczos";
  return r;
}

void ShiftInvertEigenSolver::set_positions(const Eigen::MatrixX3d& positions) { impl_->positions = positions; }

SolverReport ShiftInvertEigenSolver::linear_solver_report() const { return impl_->last_report; }

}  // namespace corrlap
