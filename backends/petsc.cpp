#include "petsc.hpp"

#include <petscksp.h>
#include <slepceps.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <corrlap/backends/detail/petsc_objects.hpp>
#include <corrlap/backends/detail/solver_support.hpp>
#include <cstdio>
#include <iostream>
#include <limits>
#include <numeric>
#include <sstream>

namespace corrlap {

using SpMat = Eigen::SparseMatrix<double>;

bool detail::petsc_alive() {
  PetscBool initialized = PETSC_FALSE, finalized = PETSC_FALSE;
  PetscInitialized(&initialized);
  PetscFinalized(&finalized);
  return initialized == PETSC_TRUE && finalized == PETSC_FALSE;
}

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

using detail::petsc_alive;
using OwnedMat = detail::PetscMatOwner;
using OwnedVec = detail::PetscVecOwner;
using OwnedKsp = detail::PetscOwned<KSP, KSPDestroy>;
using OwnedEps = detail::PetscOwned<EPS, EPSDestroy>;
using OwnedScatter = detail::PetscOwned<VecScatter, VecScatterDestroy>;
using OwnedNullSpace = detail::PetscOwned<MatNullSpace, MatNullSpaceDestroy>;

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
  bool has(const std::string& key) const {
    return std::any_of(options_.begin(), options_.end(), [&](const auto& option) { return option.first == key; });
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
  // MUMPS's workspace margin ICNTL(14), in percent of the analysis's estimate. Some factorizations
  // need more than the default 20 (sphere1 at h = 0.025 over 2 ranks: INFOG(1) = -9), and a large
  // margin up front costs memory on every run (2.83 against 2.75 GB at h = 0.004 on one rank with
  // 100 %). So it is doubled only when a factorization reports too little, and kept for the
  // refactorizations.
  int mumps_margin = 20;

  RowBlock rows;  // the serial front end's block of the whole matrix
  detail::Pattern pattern;
  OwnedMat A;  // built from the serial matrix, or shared with the distributed front end
  OwnedKsp ksp;
  bool ksp_set_up = false;  // a set-up KSP refactorizes with its factor's settings
  OwnedNullSpace null_space;
  bool factored = false, singular = false, warned = false, distributed = false;
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
  /// A KSP of the configured types (a type PETSc does not know fails here).
  void new_ksp() {
    check(KSPCreate(PETSC_COMM_WORLD, ksp.out()), "KSPCreate");
    setup_ksp(ksp, effective_ksp_type(), pc_type, factor_solver);
    ksp_set_up = false;
  }
  void set_up();
  template <class Fill, class Take>
  void solve_columns(Eigen::Index columns, Fill fill, Take take);
};

/// The KSP on A, which holds its values: the null space when A 1 = 0, the options, and the set-up
/// (the factorization with cholesky/lu), whose outcome every rank agrees on.
void PetscLinearSolver::Impl::set_up() {
  factored = false;
  // A 1 = 0 (within rounding): the constant null space, as of -L on a closed surface.
  // max |A 1| <= 1e-12 max_i sum_j |a_ij|, both over every rank (MatMult and MatNorm are collective).
  OwnedVec ones, product;
  check(MatCreateVecs(A, ones.out(), product.out()), "MatCreateVecs");
  check(VecSet(ones, 1.0), "VecSet");
  check(MatMult(A, ones, product), "MatMult");
  PetscReal row_sum = 0.0, row_norm = 0.0;
  check(VecNorm(product, NORM_INFINITY, &row_sum), "VecNorm");
  check(MatNorm(A, NORM_INFINITY, &row_norm), "MatNorm");
  singular = row_sum <= 1e-12 * row_norm;
  null_space.reset();
  if (singular) {
    check(MatNullSpaceCreate(PETSC_COMM_WORLD, PETSC_TRUE, 0, nullptr, null_space.out()), "MatNullSpaceCreate");
    // MUMPS stops at a zero pivot unless told to detect it (ICNTL(24)); the solution is then one
    // of the singular system's, made mean-free in solve().
    if (is_factorization(pc_type) && factor_solver == "mumps") passed.add("mat_mumps_icntl_24", "1");
  }
  check(MatSetNullSpace(A, null_space), "MatSetNullSpace");
  check(MatSetTransposeNullSpace(A, null_space), "MatSetTransposeNullSpace");
  passed.apply();
  // A margin the user set (mat_mumps_icntl_14) is theirs: no retry.
  const bool mumps = is_factorization(pc_type) && factor_solver == "mumps" && !passed.has("mat_mumps_icntl_14");
  for (;;) {
    check(KSPSetOperators(ksp, A, A), "KSPSetOperators");
    check(KSPSetTolerances(ksp, rtol, 0.0, PETSC_DEFAULT, max_it), "KSPSetTolerances");
    // cg's rtol then means what it means for the "cg" backend: the true residual.
    if (effective_ksp_type() == "cg") check(KSPSetNormType(ksp, KSP_NORM_UNPRECONDITIONED), "KSPSetNormType", true);
    check(KSPSetOptionsPrefix(ksp, passed.prefix().c_str()), "KSPSetOptionsPrefix");
    // The factor (MUMPS) reads its -mat_ options under the matrix's prefix.
    check(MatSetOptionsPrefix(A, passed.prefix().c_str()), "MatSetOptionsPrefix");
    check(KSPSetFromOptions(ksp), "KSPSetFromOptions", true);
    PC pc = nullptr;
    check(KSPGetPC(ksp, &pc), "KSPGetPC");
    if (mumps && !ksp_set_up) {
      Mat factor = nullptr;
      check(PCFactorSetUpMatSolverType(pc), "PCFactorSetUpMatSolverType");
      check(PCFactorGetMatrix(pc, &factor), "PCFactorGetMatrix");
      check(MatMumpsSetIcntl(factor, 14, mumps_margin), "MatMumpsSetIcntl");
    }
    const PetscErrorCode code = KSPSetUp(ksp);
    std::string message;
    if (code != 0) std::swap(message, first_petsc_message);
    PCFailedReason reason = PC_NOERROR;
    if (code == 0) check(PCGetFailedReason(pc, &reason), "PCGetFailedReason");
    // Both are this rank's; the factorization is collective, so every rank takes the same decision
    // (retry, fail or go on) from the worst outcome of all.
    int local[2] = {code != 0 ? 1 : 0, reason > 0 ? int(reason) : 0}, agreed[2] = {0, 0};
    MPI_Allreduce(local, agreed, 2, MPI_INT, MPI_MAX, PETSC_COMM_WORLD);
    const auto failed = PCFailedReason(agreed[1]);
    if (agreed[0] == 0 && failed == PC_FACTOR_OUTMEMORY && mumps && mumps_margin < 1000) {
      mumps_margin *= 2;
      new_ksp();  // a new factor: MUMPS takes ICNTL(14) before its analysis
      continue;
    }
    if (agreed[0] == 0 && failed == PC_NOERROR) break;
    new_ksp();  // the next factorize starts afresh
    std::ostringstream os;
    os << "petsc: setting up " << effective_ksp_type() << " + " << pc_type << " failed: ";
    if (!message.empty())
      os << message;
    else if (failed != PC_NOERROR)
      os << "PC " << PCFailedReasons[failed];
    else
      os << "on another rank (its message is on that rank's stderr)";
    if (failed == PC_FACTOR_OUTMEMORY) os << " (MUMPS's workspace margin ICNTL(14) = " << mumps_margin << " %)";
    fail(failed == PC_FACTOR_OUTMEMORY ? SolverStatus::OutOfMemory
         : failed == PC_FACTOR_STRUCT_ZEROPIVOT || failed == PC_FACTOR_NUMERIC_ZEROPIVOT
             ? SolverStatus::NotPositiveDefinite
             : SolverStatus::NumericalIssue,
         os.str());
  }
  ksp_set_up = true;
}

/// Solves column after column: fill(c, b) writes this rank's rows of column c into b, take(c, x)
/// reads this rank's rows of its solution from x.
template <class Fill, class Take>
void PetscLinearSolver::Impl::solve_columns(Eigen::Index columns, Fill fill, Take take) {
  Stopwatch watch;
  OwnedVec b, x, r;
  check(MatCreateVecs(A, x.out(), b.out()), "MatCreateVecs");
  check(VecDuplicate(b, r.out()), "VecDuplicate");
  int iterations = 0;
  double worst = 0.0;
  for (Eigen::Index c = 0; c < columns; ++c) {
    fill(c, Vec(b));
    // The compatible part of b (what the null space leaves solvable); the residual is measured on it.
    if (singular) check(MatNullSpaceRemove(null_space, b), "MatNullSpaceRemove");
    check(KSPSolve(ksp, b, x), "KSPSolve");
    KSPConvergedReason reason = KSP_CONVERGED_ITERATING;
    PetscInt its = 0;
    check(KSPGetConvergedReason(ksp, &reason), "KSPGetConvergedReason");
    check(KSPGetIterationNumber(ksp, &its), "KSPGetIterationNumber");
    iterations = std::max(iterations, int(its));
    report.iterations = iterations;
    // The reason and the norms below are the same on every rank (reductions), so every rank fails alike.
    if (reason < 0) {
      std::ostringstream os;
      os << "petsc: " << effective_ksp_type() << " + " << pc_type << " diverged: " << KSPConvergedReasons[reason]
         << " after " << its << " iterations (column " << c << ", rtol " << rtol << ", max_it " << max_it << ")";
      report.solve_seconds = watch.elapsed();
      fail(status_of(reason), os.str());
    }
    if (singular) check(MatNullSpaceRemove(null_space, x), "MatNullSpaceRemove");
    PetscReal nb = 0.0, nr = 0.0;
    check(MatMult(A, x, r), "MatMult");
    check(VecAYPX(r, -1.0, b), "VecAYPX");
    check(VecNorm(r, NORM_2, &nr), "VecNorm");
    check(VecNorm(b, NORM_2, &nb), "VecNorm");
    const double relative_residual = nb > 0.0 ? double(nr / nb) : double(nr);
    // KSP stops on its recurrence residual; as in the "cg" backend the true one decides, with the
    // same slack. A factorization's rounding is not held to rtol (it was never asked to meet it).
    if (!is_factorization(pc_type) && !(relative_residual <= 10.0 * rtol)) {
      std::ostringstream os;
      os << "petsc: " << effective_ksp_type() << " + " << pc_type << ": no convergence: true relative residual "
         << relative_residual << " > 10 rtol = " << 10.0 * rtol << " after " << its << " iterations (column " << c
         << "; KSP said " << KSPConvergedReasons[reason] << ")";
      report.solve_seconds = watch.elapsed();
      fail(SolverStatus::NoConvergence, os.str());
    }
    worst = std::max(worst, relative_residual);
    report.message = std::string("KSP ") + KSPConvergedReasons[reason];
    take(c, Vec(x));
  }
  if (!warned) {
    warn_unused(passed, "linear solver 'petsc'");
    warned = true;
  }
  report.residual = worst;
  report.status = SolverStatus::Success;
  report.solve_seconds = watch.elapsed();
}

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
  s.mumps_margin = 20;
  // A KSP now, so that a type PETSc does not know fails here, before the caller's long assembly.
  s.new_ksp();
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
  s.distributed = false;
  create_matrix(A, s.rows, s.A);
  s.new_ksp();  // a new matrix: a new factor (with the current workspace margin)
  s.report.status = SolverStatus::Success;
  s.report.ordering = is_factorization(s.pc_type) ? s.factor_solver : "";
  s.report.analyze_seconds = watch.elapsed();
}

void PetscLinearSolver::factorize(const SpMat& A) {
  auto& s = *impl_;
  if (s.pattern.empty() || s.distributed)
    throw SolverError(SolverStatus::NotAnalyzed, "petsc: factorize() called before analyze()");
  detail::check_same_pattern(s.pattern, A, "petsc");
  detail::check_matrix(A, "petsc", true);
  if (!A.isCompressed()) throw SolverError(SolverStatus::InvalidInput, "petsc: the matrix must be compressed");
  Stopwatch watch;
  s.factored = false;
  set_values(A, s.rows, s.A);
  s.set_up();
  s.report.factorize_seconds = watch.elapsed();
  s.report.status = SolverStatus::Success;
  s.report.message.clear();
  s.factored = true;
}

void PetscLinearSolver::factorize_distributed(const detail::PetscDistributedMatrix& A) {
  auto& s = *impl_;
  Runtime::ensure();
  if (!s.ksp) configure(Config());
  PetscInt rows = 0, columns = 0;
  check(MatGetSize(A.mat, &rows, &columns), "MatGetSize");
  if (rows != columns || rows == 0)
    throw SolverError(SolverStatus::InvalidInput, "petsc: the distributed matrix must be square and non-empty");
  Stopwatch watch;
  s.report = SolverReport{};
  s.report.ordering = is_factorization(s.pc_type) ? s.factor_solver : "";
  s.factored = false;
  s.pattern = detail::Pattern{};
  if (!s.distributed || Mat(s.A) != A.mat) {
    s.A.share(A.mat);
    s.new_ksp();
  }
  s.distributed = true;
  s.set_up();
  s.report.factorize_seconds = watch.elapsed();
  s.report.status = SolverStatus::Success;
  s.report.message.clear();
  s.factored = true;
}

Eigen::MatrixXd PetscLinearSolver::solve(const Eigen::MatrixXd& B) {
  auto& s = *impl_;
  if (!s.factored || s.distributed)
    throw SolverError(SolverStatus::NotAnalyzed, "petsc: solve() called before a successful factorize()");
  detail::check_rhs(B, s.pattern.rows, "petsc");
  Eigen::MatrixXd X(B.rows(), B.cols());
  s.solve_columns(
      B.cols(),
      [&](Eigen::Index c, Vec b) {
        const Eigen::VectorXd column = B.col(c);
        set_local(b, s.rows, column.data());
      },
      [&](Eigen::Index c, Vec x) { gather(x, X.col(c).data()); });
  return X;
}

Eigen::MatrixXd PetscLinearSolver::solve_distributed(const Eigen::MatrixXd& B) {
  auto& s = *impl_;
  if (!s.factored || !s.distributed)
    throw SolverError(SolverStatus::NotAnalyzed,
                      "petsc: solve_distributed() called before a successful factorize_distributed()");
  PetscInt begin = 0, end = 0;
  check(MatGetOwnershipRange(s.A, &begin, &end), "MatGetOwnershipRange");
  // A wrong size on one rank must stop every rank, not leave the others waiting in KSPSolve.
  long long local[2] = {B.rows() == Eigen::Index(end - begin) && B.allFinite() ? 0 : 1, B.cols()}, worst[2] = {0, 0};
  long long least_columns = B.cols();
  MPI_Allreduce(local, worst, 2, MPI_LONG_LONG, MPI_MAX, PETSC_COMM_WORLD);
  MPI_Allreduce(MPI_IN_PLACE, &least_columns, 1, MPI_LONG_LONG, MPI_MIN, PETSC_COMM_WORLD);
  if (worst[0] != 0 || worst[1] != least_columns)
    throw SolverError(SolverStatus::InvalidInput,
                      "petsc: solve_distributed() needs each rank's own rows of the right-hand sides (" +
                          std::to_string(end - begin) + " here, " + std::to_string(B.rows()) +
                          " given), finite, and the same number of columns on every rank");
  Eigen::MatrixXd X(B.rows(), B.cols());
  s.solve_columns(
      B.cols(),
      [&](Eigen::Index c, Vec b) {
        PetscScalar* values = nullptr;
        check(VecGetArray(b, &values), "VecGetArray");
        Eigen::Map<Eigen::VectorXd>(values, B.rows()) = B.col(c);
        check(VecRestoreArray(b, &values), "VecRestoreArray");
      },
      [&](Eigen::Index c, Vec x) {
        const PetscScalar* values = nullptr;
        check(VecGetArrayRead(x, &values), "VecGetArrayRead");
        X.col(c) = Eigen::Map<const Eigen::VectorXd>(values, X.rows());
        check(VecRestoreArrayRead(x, &values), "VecRestoreArrayRead");
      });
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
  int iterations = 0;  // of the last solve

  template <class Take>
  Eigen::VectorXd solve_pencil(Mat K, Mat M, int k, Take take);
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

/// The k smallest eigenpairs of the pencil (K, M), both spread over the ranks: K = -L, or
/// K = -L - shift M for lobpcg (its values are shifted back here). Returns the values, ascending,
/// on every rank, and hands take(i, v) each vector v, M-normalized, in that order. The one EPS
/// set-up of both front ends.
template <class Take>
Eigen::VectorXd SlepcEigenSolver::Impl::solve_pencil(Mat K, Mat M, int k, Take take) {
  PetscInt n = 0;
  check(MatGetSize(K, &n, nullptr), "MatGetSize");
  const bool lobpcg = method == "lobpcg";
  check(MatSetOption(M, MAT_SPD, PETSC_TRUE), "MatSetOption");
  const int extra = guard >= 0 ? guard : std::max(6, k / 4);
  const PetscInt nev = std::min<PetscInt>(n, PetscInt(k + extra));
  OwnedEps eps;
  check(EPSCreate(PETSC_COMM_WORLD, eps.out()), "EPSCreate");
  check(EPSSetOperators(eps, K, M), "EPSSetOperators");
  check(EPSSetProblemType(eps, EPS_GHEP), "EPSSetProblemType");
  // A wide subspace by default: the sphere's eigenvalues come in near-degenerate clusters (2l + 1
  // each), and with SLEPc's default (about 2 nev) a run on two ranks now and then skipped a member.
  const PetscInt subspace = ncv > 0 ? PetscInt(ncv) : std::min<PetscInt>(n, std::max<PetscInt>(3 * nev, nev + 40));
  check(EPSSetDimensions(eps, nev, subspace, PETSC_DEFAULT), "EPSSetDimensions", true);
  check(EPSSetTolerances(eps, tolerance, max_iterations), "EPSSetTolerances");
  ST st = nullptr;
  KSP ksp = nullptr;
  check(EPSGetST(eps, &st), "EPSGetST");
  if (!lobpcg) {
    // Every mu >= 0 > shift, so the values nearest the target are exactly the smallest ones, and
    // K - shift M is positive definite although K is singular: a Cholesky factorization exists.
    check(EPSSetType(eps, EPSKRYLOVSCHUR), "EPSSetType");
    check(STSetType(st, STSINVERT), "STSetType");
    check(EPSSetTarget(eps, shift), "EPSSetTarget");
    check(EPSSetWhichEigenpairs(eps, EPS_TARGET_MAGNITUDE), "EPSSetWhichEigenpairs");
    check(STGetKSP(st, &ksp), "STGetKSP");
    setup_ksp(ksp, "preonly", "cholesky", "mumps");
  } else {
    // The preconditioner is built from K - shift M itself and never factorized.
    check(EPSSetType(eps, EPSLOBPCG), "EPSSetType");
    check(EPSSetWhichEigenpairs(eps, EPS_SMALLEST_REAL), "EPSSetWhichEigenpairs");
    check(STSetType(st, STPRECOND), "STSetType");
    check(STGetKSP(st, &ksp), "STGetKSP");
    setup_ksp(ksp, "preonly", pc_type, "");
  }
  passed.apply();
  check(EPSSetOptionsPrefix(eps, passed.prefix().c_str()), "EPSSetOptionsPrefix");
  check(EPSSetFromOptions(eps), "EPSSetFromOptions", true);
  check(EPSSolve(eps), "EPSSolve");
  warn_unused(passed, "eigen solver 'slepc'");

  PetscInt converged = 0, its = 0;
  EPSConvergedReason reason = EPS_CONVERGED_ITERATING;
  check(EPSGetConverged(eps, &converged), "EPSGetConverged");
  check(EPSGetIterationNumber(eps, &its), "EPSGetIterationNumber");
  check(EPSGetConvergedReason(eps, &reason), "EPSGetConvergedReason");
  iterations = int(its);
  if (converged < k) {
    std::ostringstream os;
    os << "slepc: " << method << " found " << converged << " of " << k << " eigenpairs: " << EPSConvergedReasons[reason]
       << " after " << its << " iterations (tolerance " << tolerance << ", max_iterations " << max_iterations << ")";
    throw SolverError(SolverStatus::NoConvergence, os.str());
  }
  Eigen::VectorXd all(converged);
  for (PetscInt i = 0; i < converged; ++i) {
    PetscScalar re = 0.0, im = 0.0;
    check(EPSGetEigenvalue(eps, i, &re, &im), "EPSGetEigenvalue");
    all[i] = lobpcg ? re + shift : re;
  }
  std::vector<PetscInt> order(static_cast<std::size_t>(converged));
  std::iota(order.begin(), order.end(), PetscInt(0));
  std::sort(order.begin(), order.end(), [&](PetscInt a, PetscInt b) { return all[a] < all[b]; });
  Eigen::VectorXd values(k);
  OwnedVec v, Mv;
  check(MatCreateVecs(K, v.out(), Mv.out()), "MatCreateVecs");
  for (int i = 0; i < k; ++i) {
    const PetscInt j = order[std::size_t(i)];
    values[i] = all[j];
    check(EPSGetEigenvector(eps, j, v, nullptr), "EPSGetEigenvector");
    // M-normalized, as the other solvers return (u^T M u over every rank).
    PetscScalar norm2 = 0.0;
    check(MatMult(M, v, Mv), "MatMult");
    check(VecDot(v, Mv, &norm2), "VecDot");
    check(VecScale(v, 1.0 / std::sqrt(double(norm2))), "VecScale");
    take(i, Vec(v));
  }
  return values;
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
  if (s.method == "lobpcg") {
    K -= s.shift * Mc;
    K.makeCompressed();
  }
  const RowBlock rows = row_block(n);
  OwnedMat Kp, Mp;
  create_matrix(K, rows, Kp);
  set_values(K, rows, Kp);
  create_matrix(Mc, rows, Mp);
  set_values(Mc, rows, Mp);
  EigenResult result;
  result.vectors.resize(n, k);
  result.values = s.solve_pencil(Kp, Mp, k, [&](int i, Vec v) { gather(v, result.vectors.col(i).data()); });
  result.iterations = s.iterations;
  result.method = "slepc " + s.method;
  return result;
}

EigenResult SlepcEigenSolver::solve_distributed(const detail::PetscDistributedMatrix& L,
                                                const detail::PetscDistributedMatrix& M, int k) {
  auto& s = *impl_;
  Runtime::ensure();
  PetscInt n = 0, columns = 0, m = 0, begin = 0, end = 0;
  check(MatGetSize(L.mat, &n, &columns), "MatGetSize");
  check(MatGetSize(M.mat, &m, nullptr), "MatGetSize");
  if (n != columns || n != m || n == 0)
    throw SolverError(SolverStatus::InvalidInput, "slepc: L and M must be square, non-empty and of the same size");
  if (k < 1 || k > n)
    throw InputError("slepc: number of eigenpairs k = " + std::to_string(k) + " must be in [1, " + std::to_string(n) +
                     "]");
  // K = -L (and - shift M for lobpcg, as in solve()), a copy: L stays the caller's.
  OwnedMat K;
  check(MatDuplicate(L.mat, MAT_COPY_VALUES, K.out()), "MatDuplicate");
  check(MatScale(K, -1.0), "MatScale");
  if (s.method == "lobpcg") check(MatAXPY(K, -s.shift, M.mat, DIFFERENT_NONZERO_PATTERN), "MatAXPY");
  check(MatSetOption(K, MAT_SYMMETRIC, PETSC_TRUE), "MatSetOption");
  check(MatGetOwnershipRange(K, &begin, &end), "MatGetOwnershipRange");
  EigenResult result;
  result.vectors.resize(end - begin, k);
  result.values = s.solve_pencil(K, M.mat, k, [&](int i, Vec v) {
    const PetscScalar* values = nullptr;
    check(VecGetArrayRead(v, &values), "VecGetArrayRead");
    result.vectors.col(i) = Eigen::Map<const Eigen::VectorXd>(values, end - begin);
    check(VecRestoreArrayRead(v, &values), "VecRestoreArrayRead");
  });
  result.iterations = s.iterations;
  result.method = "slepc " + s.method;
  return result;
}

}  // namespace corrlap
