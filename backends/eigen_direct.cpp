#include "eigen_direct.hpp"

#include <Eigen/SparseCholesky>
#include <corrlap/backends/detail/solver_support.hpp>
#include <new>
#include <sstream>
#include <variant>

namespace corrlap {

using SpMat = Eigen::SparseMatrix<double>;

struct EigenDirectSolver::Impl {
  Kind kind;
  std::variant<Eigen::SimplicialLDLT<SpMat>, Eigen::SimplicialLLT<SpMat>> solver;
  detail::Pattern pattern;
  SolverReport report;
  bool factored = false;
  bool check_symmetry = true;
  int analyses = 0;
  Eigen::Index n = 0;

  explicit Impl(Kind k) : kind(k) {
    if (k == Kind::LLT) solver.emplace<Eigen::SimplicialLLT<SpMat>>();
  }
  std::string name() const { return kind == Kind::LDLT ? "eigen-ldlt" : "eigen-llt"; }

  /// Column (in the original numbering) of the first non-positive pivot of A, found with an LDLT
  /// in the same (AMD) ordering; -1 when every pivot is positive.
  static Eigen::Index first_nonpositive_pivot(const Eigen::SimplicialLDLT<SpMat>& ldlt) {
    const Eigen::VectorXd d = ldlt.vectorD();
    for (Eigen::Index k = 0; k < d.size(); ++k)
      if (!(d[k] > 0.0)) return ldlt.permutationPinv().indices()[k];
    return -1;
  }
};

EigenDirectSolver::EigenDirectSolver(Kind kind) : impl_(std::make_unique<Impl>(kind)) {}
EigenDirectSolver::~EigenDirectSolver() = default;

std::string EigenDirectSolver::name() const { return impl_->name(); }

std::vector<ParameterInfo> EigenDirectSolver::options() const {
  return {{"check_symmetry", "true", "reject matrices with |A - A^T| > 1e-10 |A| (only the lower triangle is used)"}};
}

void EigenDirectSolver::configure(const Config& options) {
  options.check_keys(detail::allowed_keys(this->options()), "linear solver '" + name() + "'");
  impl_->check_symmetry = options.get_bool("check_symmetry", true);
}

void EigenDirectSolver::analyze(const SpMat& A) {
  auto& s = *impl_;
  detail::check_matrix(A, s.name(), false);
  Stopwatch watch;
  try {
    std::visit([&](auto& solver) { solver.analyzePattern(A); }, s.solver);
  } catch (const std::bad_alloc&) {
    throw SolverError(SolverStatus::OutOfMemory, s.name() + ": out of memory in the symbolic analysis");
  }
  s.pattern.assign(A);
  s.n = A.rows();
  s.factored = false;
  ++s.analyses;
  s.report = SolverReport{};
  s.report.status = SolverStatus::Success;
  s.report.analyze_seconds = watch.elapsed();
}

void EigenDirectSolver::factorize(const SpMat& A) {
  auto& s = *impl_;
  detail::check_same_pattern(s.pattern, A, s.name());
  detail::check_matrix(A, s.name(), s.check_symmetry);
  s.factored = false;
  Stopwatch watch;
  try {
    std::visit([&](auto& solver) { solver.factorize(A); }, s.solver);
  } catch (const std::bad_alloc&) {
    s.report.status = SolverStatus::OutOfMemory;
    throw SolverError(SolverStatus::OutOfMemory, s.name() + ": out of memory in the numeric factorization");
  }
  s.report.factorize_seconds = watch.elapsed();
  // SimplicialLDLT only fails on an exactly zero pivot; negative pivots (indefinite A) must be
  // detected here. SimplicialLLT fails on any non-positive pivot without saying where: an LDLT
  // with the same ordering locates it (error path only).
  Eigen::Index column = -1;
  bool failed = false;
  if (auto* ldlt = std::get_if<Eigen::SimplicialLDLT<SpMat>>(&s.solver)) {
    failed = ldlt->info() != Eigen::Success;
    column = Impl::first_nonpositive_pivot(*ldlt);
    failed = failed || column >= 0;
  } else if (std::get<Eigen::SimplicialLLT<SpMat>>(s.solver).info() != Eigen::Success) {
    failed = true;
    Eigen::SimplicialLDLT<SpMat> ldlt;
    ldlt.compute(A);
    column = Impl::first_nonpositive_pivot(ldlt);
  }
  if (failed) {
    std::ostringstream os;
    os << s.name() << ": matrix is not positive definite";
    if (column >= 0) os << " (non-positive pivot at column " << column << ")";
    s.report.status = SolverStatus::NotPositiveDefinite;
    s.report.message = os.str();
    throw SolverError(SolverStatus::NotPositiveDefinite, os.str());
  }
  s.factored = true;
  s.report.status = SolverStatus::Success;
  s.report.message.clear();
}

Eigen::MatrixXd EigenDirectSolver::solve(const Eigen::MatrixXd& B) {
  auto& s = *impl_;
  if (!s.factored)
    throw SolverError(SolverStatus::NotAnalyzed, s.name() + ": solve() called before a successful factorize()");
  detail::check_rhs(B, s.n, s.name());
  Stopwatch watch;
  Eigen::MatrixXd X = std::visit([&](auto& solver) -> Eigen::MatrixXd { return solver.solve(B); }, s.solver);
  s.report.solve_seconds = watch.elapsed();
  if (!X.allFinite()) {
    s.report.status = SolverStatus::NumericalIssue;
    throw SolverError(SolverStatus::NumericalIssue, s.name() + ": solution contains NaN/Inf");
  }
  s.report.status = SolverStatus::Success;
  return X;
}

const SolverReport& EigenDirectSolver::info() const { return impl_->report; }
int EigenDirectSolver::analysis_count() const { return impl_->analyses; }

}  // namespace corrlap
