#include "petsc.hpp"

#include <petscksp.h>
#include <slepceps.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <corrlap/backends/detail/solver_support.hpp>
#include <cstdio>
#include <iostream>
#include <limits>
#include <numeric>
#include <sstream>

namespace corrlap {

using SpMat = Eigen::SparseMatrix<double>;

namespace {

// ---- runtime: initialized once, finalized at exit -------------------------------------------

// The message of the PETSc call that failed first. PETSc's default handler prints a traceback on
// every rank and carries on returning codes; corrlap turns the code into an exception instead, so
// the message has to be caught here to be part of it.
thread_local std::string first_petsc_message;

PetscErrorCode keep_message(MPI_Comm, int, const char*, const char*, PetscErrorCode code, PetscErrorType type,
                            const char* message, void*) {
  if (type == PETSC_ERROR_INITIAL) first_petsc_message = message != nullptr ? message : "";
  return code;
}

/// SLEPc (and through it PETSc and MPI) for the lifetime of the process: started by the first
/// backend that needs it, finalized when static objects are destroyed. When someone else started
/// PETSc first (petsc4py), they finalize it.
class Runtime {
 public:
  static void ensure() { static Runtime runtime; }

 private:
  Runtime() {
    PetscBool up = PETSC_FALSE;
    SlepcInitialized(&up);
    if (up == PETSC_FALSE) {
      // corrlap's own handlers stay in charge of signals (and of sanitizers' reports).
      PetscOptionsSetValue(nullptr, "-no_signal_handler", nullptr);
      if (SlepcInitialize(nullptr, nullptr, nullptr, nullptr) != 0)
        throw SolverError(SolverStatus::InvalidInput, "petsc: SlepcInitialize failed (is MPI usable here?)");
      owner_ = true;
    }
    PetscPushErrorHandler(keep_message, nullptr);
  }
  ~Runtime() {
    if (owner_) SlepcFinalize();
  }
  bool owner_ = false;
};

/// False after PETSc is finalized: objects destroyed later (static solvers) must not call it.
bool petsc_alive() {
  PetscBool initialized = PETSC_FALSE, finalized = PETSC_FALSE;
  PetscInitialized(&initialized);
  PetscFinalized(&finalized);
  return initialized == PETSC_TRUE && finalized == PETSC_FALSE;
}

/// Throws when a PETSc/SLEPc call failed, with PETSc's own message. `input`: the call applies a
/// user's option, so a failure is the user's to fix (InputError).
void check(PetscErrorCode code, const char* call, bool input = false) {
  if (code == 0) return;
  std::string message = first_petsc_message;
  first_petsc_message.clear();
  if (message.empty()) {
    const char* text = nullptr;
    PetscErrorMessage(code, &text, nullptr);
    message = text != nullptr ? text : "error " + std::to_string(code);
  }
  const std::string what = std::string("petsc: ") + call + ": " + message;
  if (input) throw InputError(what);
  throw SolverError(code == PETSC_ERR_MEM ? SolverStatus::OutOfMemory : SolverStatus::NumericalIssue, what);
}

/// A PETSc object destroyed with its owner (and never after PETSc is finalized).
template <class T, PetscErrorCode (*destroy)(T*)>
class Owned {
 public:
  Owned() = default;
  Owned(const Owned&) = delete;
  Owned& operator=(const Owned&) = delete;
  ~Owned() { reset(); }
  void reset() {
    if (handle_ != nullptr && petsc_alive()) destroy(&handle_);
    handle_ = nullptr;
  }
  /// For the Create calls: the old object is destroyed first.
  T* out() {
    reset();
    return &handle_;
  }
  operator T() const { return handle_; }
  explicit operator bool() const { return handle_ != nullptr; }

 private:
  T handle_ = nullptr;
};
using OwnedMat = Owned<Mat, MatDestroy>;
using OwnedVec = Owned<Vec, VecDestroy>;
using OwnedKsp = Owned<KSP, KSPDestroy>;
using OwnedEps = Owned<EPS, EPSDestroy>;
using OwnedScatter = Owned<VecScatter, VecScatterDestroy>;
using OwnedNullSpace = Owned<MatNullSpace, MatNullSpaceDestroy>;

int world_rank() {
  int rank = 0;
  MPI_Comm_rank(PETSC_COMM_WORLD, &rank);
  return rank;
}

// ---- options --------------------------------------------------------------------------------

/// Keys passed through to PETSc's options database as -key value.
bool is_pass_through(const std::string& key, const std::vector<std::string>& prefixes) {
  return std::any_of(prefixes.begin(), prefixes.end(), [&](const std::string& p) { return key.rfind(p, 0) == 0; });
}

std::string option_text(const Config::Value& value) {
  if (const auto* s = std::get_if<std::string>(&value)) return *s;
  if (const auto* b = std::get_if<bool>(&value)) return *b ? "" : "false";  // "-ksp_monitor" alone is "on"
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", std::get<double>(value));
  return text;
}

/// Options of one solver instance, under a prefix of its own in PETSc's process-wide database, so
/// that two instances never see each other's: set when the objects are set up, removed with them.
class PrefixedOptions {
 public:
  PrefixedOptions() {
    static std::atomic<int> next{0};
    prefix_ = "corrlap" + std::to_string(next++) + "_";
  }
  ~PrefixedOptions() { clear(); }
  PrefixedOptions(const PrefixedOptions&) = delete;
  PrefixedOptions& operator=(const PrefixedOptions&) = delete;

  const std::string& prefix() const { return prefix_; }
  /// Replaces the set of pass-through options (key without its leading '-').
  void assign(std::vector<std::pair<std::string, std::string>> options) {
    clear();
    options_ = std::move(options);
  }
  void add(const std::string& key, const std::string& value) {
    for (const auto& option : options_)
      if (option.first == key) return;
    options_.emplace_back(key, value);
  }
  /// Writes them into PETSc's database (PETSc must be running).
  void apply() const {
    for (const auto& [key, value] : options_)
      check(PetscOptionsSetValue(nullptr, ("-" + prefix_ + key).c_str(), value.empty() ? nullptr : value.c_str()),
            "PetscOptionsSetValue", true);
  }
  /// The pass-through options PETSc never read (a misspelt name, or one for another type).
  std::vector<std::string> unused() const {
    std::vector<std::string> names;
    for (const auto& option : options_) {
      PetscBool used = PETSC_TRUE;
      PetscOptionsUsed(nullptr, (prefix_ + option.first).c_str(), &used);  // the database's names have no '-'

      if (used == PETSC_FALSE) names.push_back(option.first);
    }
    return names;
  }

 private:
  void clear() {
    if (!petsc_alive()) return;
    for (const auto& option : options_) PetscOptionsClearValue(nullptr, ("-" + prefix_ + option.first).c_str());
  }
  std::string prefix_;
  std::vector<std::pair<std::string, std::string>> options_;
};

/// Checks the keys of `options`: documented ones, "solver", or pass-through ones; returns the
/// latter as PETSc option names and values.
std::vector<std::pair<std::string, std::string>> pass_through_options(const Config& options,
                                                                      const std::vector<ParameterInfo>& documented,
                                                                      const std::vector<std::string>& prefixes,
                                                                      const std::string& context) {
  std::vector<std::pair<std::string, std::string>> passed;
  std::vector<std::string> allowed = detail::allowed_keys(documented);
  for (const std::string& key : options.keys()) {
    std::string name = key;
    if (!name.empty() && name[0] == '-') name.erase(0, 1);
    if (std::find(allowed.begin(), allowed.end(), name) != allowed.end() && name == key) continue;
    if (is_pass_through(name, prefixes)) {
      passed.emplace_back(name, option_text(options.get_value(key)));
      allowed.push_back(key);
    }
  }
  options.check_keys(allowed, context);  // anything else: the InputError listing the valid keys
  return passed;
}

void warn_unused(const PrefixedOptions& options, const std::string& who) {
  for (const std::string& name : options.unused())
    if (world_rank() == 0)
      std::cerr << "warning: " << who << ": PETSc did not use option -" << name
                << " (misspelt, or not one of this solver type's)\n";
}

// ---- distribution ---------------------------------------------------------------------------

/// The contiguous block of rows [begin, end) this rank owns among n.
struct RowBlock {
  PetscInt begin = 0, end = 0;
  PetscInt size() const { return end - begin; }
};

RowBlock row_block(Eigen::Index n) {
  int rank = 0, size = 1;
  MPI_Comm_rank(PETSC_COMM_WORLD, &rank);
  MPI_Comm_size(PETSC_COMM_WORLD, &size);
  const auto bound = [&](int r) { return PetscInt(static_cast<long long>(n) * r / size); };
  return {bound(rank), bound(rank + 1)};
}

/// PETSc's indices are 32-bit in Debian's libpetsc-real (docs/backends.md says why that build).
void check_index_range(Eigen::Index n, Eigen::Index nonzeros, const std::string& who) {
  constexpr long long limit = std::numeric_limits<PetscInt>::max();
  if (n > limit || nonzeros > limit)
    throw SolverError(SolverStatus::InvalidInput, who + ": " + std::to_string(n) + " unknowns and " +
                                                      std::to_string(nonzeros) +
                                                      " nonzeros exceed this PETSc build's 32-bit indices");
}

/// An MPIAIJ matrix (SeqAIJ on one rank) with A's pattern, assembled through COO: this rank gives
/// the entries of its rows. A is symmetric, so its columns in the block are those rows.
void create_matrix(const SpMat& A, const RowBlock& rows, OwnedMat& mat) {
  const Eigen::Index n = A.rows();
  check(MatCreate(PETSC_COMM_WORLD, mat.out()), "MatCreate");
  check(MatSetSizes(mat, rows.size(), rows.size(), PetscInt(n), PetscInt(n)), "MatSetSizes");
  check(MatSetType(mat, MATAIJ), "MatSetType");
  const auto* outer = A.outerIndexPtr();
  const PetscCount count = outer[rows.end] - outer[rows.begin];
  std::vector<PetscInt> i(static_cast<std::size_t>(count)), j(static_cast<std::size_t>(count));
  std::size_t e = 0;
  for (PetscInt c = rows.begin; c < rows.end; ++c)
    for (auto k = outer[c]; k < outer[c + 1]; ++k, ++e) {
      i[e] = c;
      j[e] = PetscInt(A.innerIndexPtr()[k]);
    }
  check(MatSetPreallocationCOO(mat, count, i.data(), j.data()), "MatSetPreallocationCOO");
  check(MatSetOption(mat, MAT_SYMMETRIC, PETSC_TRUE), "MatSetOption");
  check(MatSetOption(mat, MAT_SYMMETRY_ETERNAL, PETSC_TRUE), "MatSetOption");
}

/// The values of this rank's block, in the order create_matrix gave the entries (A compressed).
void set_values(const SpMat& A, const RowBlock& rows, Mat mat) {
  check(MatSetValuesCOO(mat, A.valuePtr() + A.outerIndexPtr()[rows.begin], INSERT_VALUES), "MatSetValuesCOO");
}

void set_local(Vec v, const RowBlock& rows, const double* whole) {
  PetscScalar* local = nullptr;
  check(VecGetArray(v, &local), "VecGetArray");
  std::copy(whole + rows.begin, whole + rows.end, local);
  check(VecRestoreArray(v, &local), "VecRestoreArray");
}

/// The whole vector v on every rank.
void gather(Vec v, double* whole) {
  OwnedScatter scatter;
  OwnedVec all;
  check(VecScatterCreateToAll(v, scatter.out(), all.out()), "VecScatterCreateToAll");
  check(VecScatterBegin(scatter, v, all, INSERT_VALUES, SCATTER_FORWARD), "VecScatterBegin");
  check(VecScatterEnd(scatter, v, all, INSERT_VALUES, SCATTER_FORWARD), "VecScatterEnd");
  const PetscScalar* values = nullptr;
  PetscInt n = 0;
  check(VecGetSize(all, &n), "VecGetSize");
  check(VecGetArrayRead(all, &values), "VecGetArrayRead");
  std::copy(values, values + n, whole);
  check(VecRestoreArrayRead(all, &values), "VecRestoreArrayRead");
}

const std::vector<std::string> kPreconditioners = {"cholesky", "gamg", "hypre", "jacobi",
                                                   "bjacobi",  "sor",  "lu",    "none"};

std::string joined(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

bool is_factorization(const std::string& pc) { return pc == "cholesky" || pc == "lu"; }

/// Applies the named options of a KSP and its PC (also the KSP of SLEPc's spectral transform).
void setup_ksp(KSP ksp, const std::string& ksp_type, const std::string& pc_type, const std::string& factor_solver) {
  check(KSPSetType(ksp, ksp_type.c_str()), ("KSPSetType(" + ksp_type + ")").c_str(), true);
  PC pc = nullptr;
  check(KSPGetPC(ksp, &pc), "KSPGetPC");
  check(PCSetType(pc, pc_type.c_str()), ("PCSetType(" + pc_type + ")").c_str(), true);
  if (is_factorization(pc_type))
    check(PCFactorSetMatSolverType(pc, factor_solver.c_str()), "PCFactorSetMatSolverType", true);
}

SolverStatus status_of(KSPConvergedReason reason) {
  switch (reason) {
    case KSP_DIVERGED_NANORINF:
      return SolverStatus::NumericalIssue;
    case KSP_DIVERGED_INDEFINITE_PC:
    case KSP_DIVERGED_INDEFINITE_MAT:
    case KSP_DIVERGED_PC_FAILED:
      return SolverStatus::NotPositiveDefinite;
    default:
      return SolverStatus::NoConvergence;
  }
}

}  // namespace

void ensure_petsc_runtime() { Runtime::ensure(); }

// ---- petsc: the linear solver -----------------------------------------------------------------

struct PetscLinearSolver::Impl {
  std::string ksp_type = "auto";  // preonly after a factorization, cg otherwise
  std::string pc_type = "cholesky";
  std::string factor_solver = "mumps";
  double rtol = 1e-10;
  int max_it = 10000;
  PrefixedOptions passed;

  RowBlock rows;
  detail::Pattern pattern;
  OwnedMat A;
  OwnedKsp ksp;
  OwnedNullSpace null_space;
  bool factored = false, singular = false, warned = false;
  SolverReport report;

  std::string effective_ksp_type() const {
    if (ksp_type != "auto") return ksp_type;
    return is_factorization(pc_type) ? "preonly" : "cg";
  }
  void fail(SolverStatus status, const std::string& message) {
    report.status = status;
    report.message = message;
    throw SolverError(status, message);
  }
};

PetscLinearSolver::PetscLinearSolver() : impl_(std::make_unique<Impl>()) {}
PetscLinearSolver::~PetscLinearSolver() = default;

std::vector<ParameterInfo> PetscLinearSolver::options() const {
  return {
      {"ksp_type", "auto",
       "PETSc Krylov method (cg, gmres, minres, preonly, ...); auto: preonly with cholesky/lu, cg else"},
      {"pc_type", "cholesky", "preconditioner: " + joined(kPreconditioners) + " (cholesky/lu: a direct solve)"},
      {"factor_solver", "mumps", "package of the cholesky/lu factorization (mumps, petsc, cholmod)"},
      {"rtol", "1e-10", "stop when |A x - b| <= rtol |b| (cg: the true, unpreconditioned residual)"},
      {"max_it", "10000", "iteration limit of the Krylov method"},
      {"ksp_*, pc_*, mat_*", "",
       "any other PETSc option of these families, passed on as -ksp_... (e.g. pc_gamg_threshold=0.02)"},
  };
}

void check_petsc_call(int code, const char* call) { check(PetscErrorCode(code), call); }

void PetscLinearSolver::configure(const Config& options) {
  auto& s = *impl_;
  std::vector<ParameterInfo> documented = this->options();
  documented.pop_back();  // the pass-through families are not keys
  auto passed = pass_through_options(options, documented, {"ksp_", "pc_", "mat_"}, "linear solver 'petsc'");
  const std::string pc = options.get_string("pc_type", s.pc_type);
  if (std::find(kPreconditioners.begin(), kPreconditioners.end(), pc) == kPreconditioners.end())
    throw InputError(
        "linear solver 'petsc': config key 'pc_type' must be one of " + joined(kPreconditioners) + ", got '" + pc + "'",
        "pc_type");
  const double rtol = options.get_double("rtol", s.rtol);
  if (!(rtol > 0.0 && rtol < 1.0))
    throw InputError("linear solver 'petsc': config key 'rtol' must be in (0, 1)", "rtol");
  const int max_it = options.get_int("max_it", s.max_it);
  if (max_it < 1) throw InputError("linear solver 'petsc': config key 'max_it' must be >= 1", "max_it");
  Runtime::ensure();
  s.ksp_type = options.get_string("ksp_type", s.ksp_type);
  s.pc_type = pc;
  s.factor_solver = options.get_string("factor_solver", s.factor_solver);
  s.rtol = rtol;
  s.max_it = max_it;
  s.passed.assign(std::move(passed));
  // A KSP now, so that a type PETSc does not know fails here, before the caller's long assembly.
  check(KSPCreate(PETSC_COMM_WORLD, s.ksp.out()), "KSPCreate");
  setup_ksp(s.ksp, s.effective_ksp_type(), s.pc_type, s.factor_solver);
  s.factored = false;
  s.warned = false;
}

void PetscLinearSolver::analyze(const SpMat& A) {
  auto& s = *impl_;
  detail::check_matrix(A, "petsc", false);
  if (!A.isCompressed()) throw SolverError(SolverStatus::InvalidInput, "petsc: the matrix must be compressed");
  check_index_range(A.rows(), A.nonZeros(), "petsc");
  Runtime::ensure();
  if (!s.ksp) configure(Config());
  Stopwatch watch;
  s.report = SolverReport{};
  s.pattern.assign(A);
  s.rows = row_block(A.rows());
  s.factored = false;
  create_matrix(A, s.rows, s.A);
  s.report.status = SolverStatus::Success;
  s.report.ordering = is_factorization(s.pc_type) ? s.factor_solver : "";
  s.report.analyze_seconds = watch.elapsed();
}

void PetscLinearSolver::factorize(const SpMat& A) {
  auto& s = *impl_;
  if (s.pattern.empty()) throw SolverError(SolverStatus::NotAnalyzed, "petsc: factorize() called before analyze()");
  detail::check_same_pattern(s.pattern, A, "petsc");
  detail::check_matrix(A, "petsc", true);
  if (!A.isCompressed()) throw SolverError(SolverStatus::InvalidInput, "petsc: the matrix must be compressed");
  Stopwatch watch;
  s.factored = false;
  set_values(A, s.rows, s.A);
  // A 1 = 0 (within rounding): the constant null space, as of -L on a closed surface. The row sums
  // of this rank's rows (= its columns' sums, A symmetric), the largest over every rank.
  double row_sum = 0.0, row_norm = 0.0;
  for (PetscInt c = s.rows.begin; c < s.rows.end; ++c) {
    double sum = 0.0, norm = 0.0;
    for (SpMat::InnerIterator it(A, c); it; ++it) {
      sum += it.value();
      norm += std::abs(it.value());
    }
    row_sum = std::max(row_sum, std::abs(sum));
    row_norm = std::max(row_norm, norm);
  }
  double local[2] = {row_sum, row_norm}, global[2] = {0.0, 0.0};
  MPI_Allreduce(local, global, 2, MPI_DOUBLE, MPI_MAX, PETSC_COMM_WORLD);
  s.singular = global[0] <= 1e-12 * global[1];
  s.null_space.reset();
  if (s.singular) {
    check(MatNullSpaceCreate(PETSC_COMM_WORLD, PETSC_TRUE, 0, nullptr, s.null_space.out()), "MatNullSpaceCreate");
    // MUMPS stops at a zero pivot unless told to detect it (ICNTL(24)); the solution is then one
    // of the singular system's, made mean-free below.
    if (is_factorization(s.pc_type) && s.factor_solver == "mumps") s.passed.add("mat_mumps_icntl_24", "1");
  }
  check(MatSetNullSpace(s.A, s.null_space), "MatSetNullSpace");
  check(MatSetTransposeNullSpace(s.A, s.null_space), "MatSetTransposeNullSpace");
  s.passed.apply();
  check(KSPSetOperators(s.ksp, s.A, s.A), "KSPSetOperators");
  check(KSPSetTolerances(s.ksp, s.rtol, 0.0, PETSC_DEFAULT, s.max_it), "KSPSetTolerances");
  // cg's rtol then means what it means for the "cg" backend: the true residual.
  if (s.effective_ksp_type() == "cg") check(KSPSetNormType(s.ksp, KSP_NORM_UNPRECONDITIONED), "KSPSetNormType", true);
  check(KSPSetOptionsPrefix(s.ksp, s.passed.prefix().c_str()), "KSPSetOptionsPrefix");
  // The factor (MUMPS) reads its -mat_ options under the matrix's prefix.
  check(MatSetOptionsPrefix(s.A, s.passed.prefix().c_str()), "MatSetOptionsPrefix");
  check(KSPSetFromOptions(s.ksp), "KSPSetFromOptions", true);
  const PetscErrorCode setup = KSPSetUp(s.ksp);
  if (setup != 0) {
    std::string message = first_petsc_message;
    first_petsc_message.clear();
    PC pc = nullptr;
    KSPGetPC(s.ksp, &pc);
    PCFailedReason reason = PC_NOERROR;
    if (pc != nullptr) PCGetFailedReason(pc, &reason);
    s.fail(reason == PC_FACTOR_STRUCT_ZEROPIVOT || reason == PC_FACTOR_NUMERIC_ZEROPIVOT
               ? SolverStatus::NotPositiveDefinite
               : SolverStatus::NumericalIssue,
           "petsc: setting up " + s.effective_ksp_type() + " + " + s.pc_type + " failed: " + message);
  }
  s.report.factorize_seconds = watch.elapsed();
  s.report.status = SolverStatus::Success;
  s.report.message.clear();
  s.factored = true;
}

Eigen::MatrixXd PetscLinearSolver::solve(const Eigen::MatrixXd& B) {
  auto& s = *impl_;
  if (!s.factored)
    throw SolverError(SolverStatus::NotAnalyzed, "petsc: solve() called before a successful factorize()");
  detail::check_rhs(B, s.pattern.rows, "petsc");
  Stopwatch watch;
  OwnedVec b, x, r;
  check(MatCreateVecs(s.A, x.out(), b.out()), "MatCreateVecs");
  check(VecDuplicate(b, r.out()), "VecDuplicate");
  Eigen::MatrixXd X(B.rows(), B.cols());
  int iterations = 0;
  double worst = 0.0;
  for (Eigen::Index c = 0; c < B.cols(); ++c) {
    const Eigen::VectorXd column = B.col(c);
    set_local(b, s.rows, column.data());
    // The compatible part of b (what the null space leaves solvable); the residual is measured on it.
    if (s.singular) check(MatNullSpaceRemove(s.null_space, b), "MatNullSpaceRemove");
    check(KSPSolve(s.ksp, b, x), "KSPSolve");
    KSPConvergedReason reason = KSP_CONVERGED_ITERATING;
    PetscInt its = 0;
    check(KSPGetConvergedReason(s.ksp, &reason), "KSPGetConvergedReason");
    check(KSPGetIterationNumber(s.ksp, &its), "KSPGetIterationNumber");
    iterations = std::max(iterations, int(its));
    s.report.iterations = iterations;
    if (reason < 0) {
      std::ostringstream os;
      os << "petsc: " << s.effective_ksp_type() << " + " << s.pc_type << " diverged: " << KSPConvergedReasons[reason]
         << " after " << its << " iterations (column " << c << ", rtol " << s.rtol << ", max_it " << s.max_it << ")";
      s.report.solve_seconds = watch.elapsed();
      s.fail(status_of(reason), os.str());
    }
    if (s.singular) check(MatNullSpaceRemove(s.null_space, x), "MatNullSpaceRemove");
    PetscReal nb = 0.0, nr = 0.0;
    check(MatMult(s.A, x, r), "MatMult");
    check(VecAYPX(r, -1.0, b), "VecAYPX");
    check(VecNorm(r, NORM_2, &nr), "VecNorm");
    check(VecNorm(b, NORM_2, &nb), "VecNorm");
    const double relative_residual = nb > 0.0 ? double(nr / nb) : double(nr);
    // KSP stops on its recurrence residual; as in the "cg" backend the true one decides, with the
    // same slack. A factorization's rounding is not held to rtol (it was never asked to meet it).
    if (!is_factorization(s.pc_type) && !(relative_residual <= 10.0 * s.rtol)) {
      std::ostringstream os;
      os << "petsc: " << s.effective_ksp_type() << " + " << s.pc_type << ": no convergence: true relative residual "
         << relative_residual << " > 10 rtol = " << 10.0 * s.rtol << " after " << its << " iterations (column " << c
         << "; KSP said " << KSPConvergedReasons[reason] << ")";
      s.report.solve_seconds = watch.elapsed();
      s.fail(SolverStatus::NoConvergence, os.str());
    }
    worst = std::max(worst, relative_residual);
    s.report.message = std::string("KSP ") + KSPConvergedReasons[reason];
    gather(x, X.col(c).data());
  }
  if (!s.warned) {
    warn_unused(s.passed, "linear solver 'petsc'");
    s.warned = true;
  }
  s.report.residual = worst;
  s.report.status = SolverStatus::Success;
  s.report.solve_seconds = watch.elapsed();
  return X;
}

const SolverReport& PetscLinearSolver::info() const { return impl_->report; }

bool PetscLinearSolver::singular() const { return impl_->singular; }

// ---- slepc: the eigen solver ------------------------------------------------------------------

struct SlepcEigenSolver::Impl {
  std::string method = "shift-invert";
  double shift = -1e-3;
  double tolerance = 1e-10;
  int max_iterations = 1000;
  int ncv = 0;
  int guard = -1;
  std::string pc_type = "gamg";  // lobpcg's preconditioner
  PrefixedOptions passed;
};

SlepcEigenSolver::SlepcEigenSolver() : impl_(std::make_unique<Impl>()) {}
SlepcEigenSolver::~SlepcEigenSolver() = default;

std::vector<ParameterInfo> SlepcEigenSolver::options() const {
  return {
      {"method", "shift-invert",
       "shift-invert: Krylov-Schur on (K - shift M)^{-1} M, MUMPS's Cholesky; lobpcg: LOBPCG preconditioned by pc_type "
       "on K - shift M (no factorization)"},
      {"shift", "-0.001", "target in units of mu = -lambda; must be < 0 (K - shift M must be positive definite)"},
      {"tolerance", "1e-10", "relative accuracy of the eigenpairs (SLEPc's convergence test)"},
      {"max_iterations", "1000", "restarts (shift-invert) or iterations (lobpcg)"},
      {"ncv", "0", "subspace size (0: max(3 nev, nev + 40), at most n)"},
      {"guard", "auto",
       "extra eigenpairs computed and dropped, so that a multiple value at position k has all its copies "
       "(auto: max(6, k/4))"},
      {"pc_type", "gamg", "lobpcg's preconditioner: gamg or hypre"},
      {"eps_*, st_*, ksp_*, pc_*, mat_*", "", "any other SLEPc/PETSc option of these families, passed on as -eps_... "},
  };
}

void SlepcEigenSolver::configure(const Config& options) {
  auto& s = *impl_;
  std::vector<ParameterInfo> documented = this->options();
  documented.pop_back();
  auto passed =
      pass_through_options(options, documented, {"eps_", "st_", "ksp_", "pc_", "mat_"}, "eigen solver 'slepc'");
  const std::string method = options.get_string("method", s.method);
  if (method != "shift-invert" && method != "lobpcg")
    throw InputError("eigen solver 'slepc': config key 'method' must be shift-invert or lobpcg, got '" + method + "'",
                     "method");
  const double shift = options.get_double("shift", s.shift);
  if (!(shift < 0.0)) throw InputError("eigen solver 'slepc': config key 'shift' must be < 0", "shift");
  const double tolerance = options.get_double("tolerance", s.tolerance);
  if (!(tolerance > 0.0 && tolerance < 1.0))
    throw InputError("eigen solver 'slepc': config key 'tolerance' must be in (0, 1)", "tolerance");
  const std::string pc = options.get_string("pc_type", s.pc_type);
  if (pc != "gamg" && pc != "hypre")
    throw InputError("eigen solver 'slepc': config key 'pc_type' must be gamg or hypre, got '" + pc + "'", "pc_type");
  const std::string guard = options.has("guard") ? option_text(options.get_value("guard")) : "";
  s.method = method;
  s.shift = shift;
  s.tolerance = tolerance;
  s.max_iterations = options.get_int("max_iterations", s.max_iterations);
  s.ncv = options.get_int("ncv", s.ncv);
  if (!guard.empty()) s.guard = guard == "auto" ? -1 : options.get_int("guard", 0);
  s.pc_type = pc;
  s.passed.assign(std::move(passed));
  Runtime::ensure();
}

EigenResult SlepcEigenSolver::solve(const SpMat& L, const SpMat& M, int k) {
  auto& s = *impl_;
  if (L.rows() != L.cols() || M.rows() != M.cols() || L.rows() != M.rows() || L.rows() == 0)
    throw SolverError(SolverStatus::InvalidInput, "slepc: L and M must be square, non-empty and of the same size");
  if (k < 1 || k > L.rows())
    throw InputError("slepc: number of eigenpairs k = " + std::to_string(k) + " must be in [1, " +
                     std::to_string(L.rows()) + "]");
  detail::check_matrix(L, "slepc (L)", true);
  detail::check_matrix(M, "slepc (M)", true);
  check_index_range(L.rows(), std::max(L.nonZeros(), M.nonZeros()), "slepc");
  Runtime::ensure();
  const Eigen::Index n = L.rows();
  // K = -L is positive semi-definite: mu = -lambda are its eigenvalues for M, the smallest wanted.
  SpMat K = -L, Mc = M;
  K.makeCompressed();
  Mc.makeCompressed();
  // LOBPCG iterates on K - shift M, positive definite: K's exact zero eigenvalue broke the
  // Rayleigh-Ritz step's B-orthogonality (LAPACK sygvd failures). Its values are mu - shift.
  const bool lobpcg = s.method == "lobpcg";
  if (lobpcg) {
    K -= s.shift * Mc;
    K.makeCompressed();
  }
  const RowBlock rows = row_block(n);
  OwnedMat Kp, Mp;
  create_matrix(K, rows, Kp);
  set_values(K, rows, Kp);
  create_matrix(Mc, rows, Mp);
  set_values(Mc, rows, Mp);
  check(MatSetOption(Mp, MAT_SPD, PETSC_TRUE), "MatSetOption");

  const int guard = s.guard >= 0 ? s.guard : std::max(6, k / 4);
  const PetscInt nev = PetscInt(std::min<Eigen::Index>(n, k + guard));
  OwnedEps eps;
  check(EPSCreate(PETSC_COMM_WORLD, eps.out()), "EPSCreate");
  check(EPSSetOperators(eps, Kp, Mp), "EPSSetOperators");
  check(EPSSetProblemType(eps, EPS_GHEP), "EPSSetProblemType");
  // A wide subspace by default: the sphere's eigenvalues come in near-degenerate clusters (2l + 1
  // each), and with SLEPc's default (about 2 nev) a run on two ranks now and then skipped a member.
  const PetscInt ncv =
      s.ncv > 0 ? PetscInt(s.ncv) : std::min<PetscInt>(PetscInt(n), std::max<PetscInt>(3 * nev, nev + 40));
  check(EPSSetDimensions(eps, nev, ncv, PETSC_DEFAULT), "EPSSetDimensions", true);
  check(EPSSetTolerances(eps, s.tolerance, s.max_iterations), "EPSSetTolerances");
  ST st = nullptr;
  KSP ksp = nullptr;
  check(EPSGetST(eps, &st), "EPSGetST");
  if (s.method == "shift-invert") {
    // Every mu >= 0 > shift, so the values nearest the target are exactly the smallest ones, and
    // K - shift M is positive definite although K is singular: a Cholesky factorization exists.
    check(EPSSetType(eps, EPSKRYLOVSCHUR), "EPSSetType");
    check(STSetType(st, STSINVERT), "STSetType");
    check(EPSSetTarget(eps, s.shift), "EPSSetTarget");
    check(EPSSetWhichEigenpairs(eps, EPS_TARGET_MAGNITUDE), "EPSSetWhichEigenpairs");
    check(STGetKSP(st, &ksp), "STGetKSP");
    setup_ksp(ksp, "preonly", "cholesky", "mumps");
  } else {
    // The preconditioner is built from K - shift M itself and never factorized.
    check(EPSSetType(eps, EPSLOBPCG), "EPSSetType");
    check(EPSSetWhichEigenpairs(eps, EPS_SMALLEST_REAL), "EPSSetWhichEigenpairs");
    check(STSetType(st, STPRECOND), "STSetType");
    check(STGetKSP(st, &ksp), "STGetKSP");
    setup_ksp(ksp, "preonly", s.pc_type, "");
  }
  s.passed.apply();
  check(EPSSetOptionsPrefix(eps, s.passed.prefix().c_str()), "EPSSetOptionsPrefix");
  check(EPSSetFromOptions(eps), "EPSSetFromOptions", true);
  check(EPSSolve(eps), "EPSSolve");
  warn_unused(s.passed, "eigen solver 'slepc'");

  PetscInt converged = 0, iterations = 0;
  EPSConvergedReason reason = EPS_CONVERGED_ITERATING;
  check(EPSGetConverged(eps, &converged), "EPSGetConverged");
  check(EPSGetIterationNumber(eps, &iterations), "EPSGetIterationNumber");
  check(EPSGetConvergedReason(eps, &reason), "EPSGetConvergedReason");
  if (converged < k) {
    std::ostringstream os;
    os << "slepc: " << s.method << " found " << converged << " of " << k
       << " eigenpairs: " << EPSConvergedReasons[reason] << " after " << iterations << " iterations (tolerance "
       << s.tolerance << ", max_iterations " << s.max_iterations << ")";
    throw SolverError(SolverStatus::NoConvergence, os.str());
  }
  OwnedVec v;
  check(MatCreateVecs(Kp, v.out(), nullptr), "MatCreateVecs");
  Eigen::VectorXd values(converged);
  Eigen::MatrixXd vectors(n, converged);
  for (PetscInt i = 0; i < converged; ++i) {
    PetscScalar re = 0.0, im = 0.0;
    check(EPSGetEigenpair(eps, i, &re, &im, v, nullptr), "EPSGetEigenpair");
    values[i] = lobpcg ? re + s.shift : re;
    gather(v, vectors.col(i).data());
  }
  std::vector<Eigen::Index> order(static_cast<std::size_t>(converged));
  std::iota(order.begin(), order.end(), Eigen::Index(0));
  std::sort(order.begin(), order.end(), [&](Eigen::Index a, Eigen::Index b) { return values[a] < values[b]; });
  EigenResult result;
  result.values.resize(k);
  result.vectors.resize(n, k);
  for (int i = 0; i < k; ++i) {
    result.values[i] = values[order[std::size_t(i)]];
    const Eigen::VectorXd u = vectors.col(order[std::size_t(i)]);
    result.vectors.col(i) = u / std::sqrt(u.dot(M * u));  // M-normalized, as the other solvers return
  }
  result.iterations = int(iterations);
  result.method = "slepc " + s.method;
  return result;
}

}  // namespace corrlap
