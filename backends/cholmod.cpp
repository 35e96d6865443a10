#include "cholmod.hpp"

#include <cholmod.h>
#include <omp.h>
#if defined(__x86_64__) || defined(__SSE2__)
#include <xmmintrin.h>
#endif

#include <atomic>
#include <corrlap/backends/detail/blas_threads.hpp>
#include <corrlap/backends/detail/geometric_ordering.hpp>
#include <corrlap/backends/detail/solver_support.hpp>
#include <mutex>
#include <new>
#include <sstream>
#include <string_view>
#include <type_traits>

namespace corrlap {

using SpMat = Eigen::SparseMatrix<double>;

namespace {

// CHOLMOD's int and long APIs differ only by the prefix; this picks one at compile time.
template <class I>
struct Api;
template <>
struct Api<int> {
  static constexpr int itype = CHOLMOD_INT;
  static int start(cholmod_common* c) { return cholmod_start(c); }
  static int finish(cholmod_common* c) { return cholmod_finish(c); }
  static cholmod_factor* analyze(cholmod_sparse* A, cholmod_common* c) { return cholmod_analyze(A, c); }
  static cholmod_factor* analyze_p(cholmod_sparse* A, int* perm, cholmod_common* c) {
    return cholmod_analyze_p(A, perm, nullptr, 0, c);
  }
  static int factorize(cholmod_sparse* A, cholmod_factor* L, cholmod_common* c) { return cholmod_factorize(A, L, c); }
  static cholmod_dense* solve(cholmod_factor* L, cholmod_dense* B, cholmod_common* c) {
    return cholmod_solve(CHOLMOD_A, L, B, c);
  }
  static int free_factor(cholmod_factor** L, cholmod_common* c) { return cholmod_free_factor(L, c); }
  static int free_dense(cholmod_dense** X, cholmod_common* c) { return cholmod_free_dense(X, c); }
};
template <>
struct Api<SuiteSparse_long> {
  static constexpr int itype = CHOLMOD_LONG;
  static int start(cholmod_common* c) { return cholmod_l_start(c); }
  static int finish(cholmod_common* c) { return cholmod_l_finish(c); }
  static cholmod_factor* analyze(cholmod_sparse* A, cholmod_common* c) { return cholmod_l_analyze(A, c); }
  static cholmod_factor* analyze_p(cholmod_sparse* A, SuiteSparse_long* perm, cholmod_common* c) {
    return cholmod_l_analyze_p(A, perm, nullptr, 0, c);
  }
  static int factorize(cholmod_sparse* A, cholmod_factor* L, cholmod_common* c) { return cholmod_l_factorize(A, L, c); }
  static cholmod_dense* solve(cholmod_factor* L, cholmod_dense* B, cholmod_common* c) {
    return cholmod_l_solve(CHOLMOD_A, L, B, c);
  }
  static int free_factor(cholmod_factor** L, cholmod_common* c) { return cholmod_l_free_factor(L, c); }
  static int free_dense(cholmod_dense** X, cholmod_common* c) { return cholmod_l_free_dense(X, c); }
};

// CHOLMOD reports errors through a callback without user data; the message of the last error on
// this thread is kept here (each solver instance is used by one thread at a time).
thread_local std::string last_cholmod_message;
void record_cholmod_error(int status, const char* file, int line, const char* message) {
  std::ostringstream os;
  os << message << " (CHOLMOD status " << status << ", " << file << ":" << line << ")";
  last_cholmod_message = os.str();
}

// Debian's CHOLMOD 3.0.x runs its supernodal kernels with a compiled-in team of 4 OpenMP threads
// (GOMP_parallel with a fixed num_threads), which oversubscribes small machines and TBB workers.
// omp_set_num_threads cannot override that clause; dynamic adjustment (a per-thread ICV) lets
// libgomp shrink the team to the idle cores, and max-active-levels 0 makes it serial. The latter
// ICV is process-wide in libgomp, so serial sections are reference counted.
std::mutex serial_mutex;

// METIS (used by the metis, nesdis, auto and best orderings) keeps its random generator in
// process-wide state (GKlib), so concurrent analyses could race and pick different orderings,
// breaking run-to-run reproducibility. Analyses with those orderings are serialized.
std::mutex metis_mutex;
int serial_users = 0;
int saved_levels = 1;

class OpenMpScope {
 public:
  explicit OpenMpScope(int threads) : serial_(threads == 1) {
    if (serial_) {
      std::lock_guard<std::mutex> lock(serial_mutex);
      if (serial_users++ == 0) {
        saved_levels = omp_get_max_active_levels();
        omp_set_max_active_levels(0);
      }
    } else if (threads == 0) {
      omp_set_dynamic(1);
    } else {
      omp_set_dynamic(0);  // threads > 1: CHOLMOD's own team size
    }
  }
  ~OpenMpScope() {
    if (!serial_) return;
    std::lock_guard<std::mutex> lock(serial_mutex);
    if (--serial_users == 0) omp_set_max_active_levels(saved_levels);
  }
  OpenMpScope(const OpenMpScope&) = delete;
  OpenMpScope& operator=(const OpenMpScope&) = delete;

 private:
  bool serial_;
};

// CHOLMOD's supernodal kernels call BLAS. A multi-threaded OpenBLAS called from several threads
// at once contends on its internal lock and spins (docs/backends.md, "BLAS"). The first time two
// CHOLMOD calls overlap, OpenBLAS is set to one thread for the rest of the process; the
// parallelism then comes from the callers' tasks. OpenBLAS results
// depend on its thread count in the last bits, so callers who need bitwise reproducibility across
// serial and concurrent phases set blas_threads explicitly (which disables the switch).
std::atomic<int> active_calls{0};
std::atomic<bool> concurrency_seen{false};

class ConcurrencyScope {
 public:
  ConcurrencyScope() {
    if (active_calls.fetch_add(1) > 0 && !concurrency_seen.exchange(true)) detail::set_blas_threads(1);
  }
  ~ConcurrencyScope() { active_calls.fetch_sub(1); }
  ConcurrencyScope(const ConcurrencyScope&) = delete;
  ConcurrencyScope& operator=(const ConcurrencyScope&) = delete;
};

// Subnormal numbers flushed to zero on the calling thread for the scope (x86: FTZ and DAZ; elsewhere
// nothing): at a large diagonal shift the factor's entries far from the diagonal fall below the
// normal range, where each operation is many times slower, and values that small are far below the
// rounding of any entry they meet. The CLI sets the flags for the whole process, OpenBLAS's
// workers included (flush_subnormals_in_process); this scope gives library callers the main
// thread's part.
class FlushSubnormalsScope {
 public:
#if defined(__x86_64__) || defined(__SSE2__)
  FlushSubnormalsScope() : saved_(_mm_getcsr() & kFlags) { _mm_setcsr(_mm_getcsr() | kFlags); }
  // The two flags as they were; the exception status bits raised meanwhile stay.
  ~FlushSubnormalsScope() { _mm_setcsr((_mm_getcsr() & ~kFlags) | saved_); }

 private:
  static constexpr unsigned kFlags = 0x8040u;  // FTZ, DAZ
  unsigned saved_;
#else
  FlushSubnormalsScope() = default;
#endif
 public:
  FlushSubnormalsScope(const FlushSubnormalsScope&) = delete;
  FlushSubnormalsScope& operator=(const FlushSubnormalsScope&) = delete;
};

const char* ordering_name(int ordering) {
  switch (ordering) {
    case CHOLMOD_NATURAL:
      return "natural";
    case CHOLMOD_GIVEN:
      return "given";
    case CHOLMOD_AMD:
      return "amd";
    case CHOLMOD_METIS:
      return "metis";
    case CHOLMOD_NESDIS:
      return "nesdis";
    case CHOLMOD_COLAMD:
      return "colamd";
    case CHOLMOD_POSTORDERED:
      return "postordered";
  }
  return "?";
}

}  // namespace

struct CholmodSolver::Impl {
  // options
  std::string supernodal = "supernodal";
  std::string ordering = "geometric";
  bool long_index = false;
  int openmp_threads = 1;
  int blas_threads = 0;
  bool check_symmetry = true;

  // state
  Eigen::MatrixX3d positions;  // set_positions: one point per unknown, for the geometric ordering
  bool geometric_used = false;
  cholmod_common common{};
  bool started = false;
  bool common_long = false;
  cholmod_factor* factor = nullptr;
  detail::Pattern pattern;
  // Index arrays of the matrix for the long API (CHOLMOD needs SuiteSparse_long indices).
  std::vector<SuiteSparse_long> outer_l, inner_l;
  SolverReport report;
  bool factored = false;
  int analyses = 0;
  Eigen::Index n = 0;

  Impl() { start(false); }
  ~Impl() { stop(); }

  void start(bool use_long) {
    stop();
    if (use_long)
      Api<SuiteSparse_long>::start(&common);
    else
      Api<int>::start(&common);
    common_long = use_long;
    started = true;
    common.print = 0;  // errors become exceptions, nothing is printed
    common.error_handler = record_cholmod_error;
  }
  void stop() {
    if (!started) return;
    free_factor();
    if (common_long)
      Api<SuiteSparse_long>::finish(&common);
    else
      Api<int>::finish(&common);
    started = false;
  }
  void free_factor() {
    if (!factor) return;
    if (common_long)
      Api<SuiteSparse_long>::free_factor(&factor, &common);
    else
      Api<int>::free_factor(&factor, &common);
    factor = nullptr;
  }

  void apply_options() {
    common.supernodal = supernodal == "simplicial" ? CHOLMOD_SIMPLICIAL
                        : supernodal == "auto"     ? CHOLMOD_AUTO
                                                   : CHOLMOD_SUPERNODAL;
    if (ordering == "best") {
      common.nmethods = 9;  // CHOLMOD tries every ordering and keeps the one with least fill
    } else if (ordering == "auto") {
      common.nmethods = 0;  // CHOLMOD's default: AMD, then METIS if AMD's fill is high
    } else {
      common.nmethods = 1;
      common.method[0].ordering = ordering == "metis"     ? CHOLMOD_METIS
                                  : ordering == "nesdis"  ? CHOLMOD_NESDIS
                                  : ordering == "natural" ? CHOLMOD_NATURAL
                                                          : CHOLMOD_AMD;  // amd, geometric without points
    }
    common.postorder = 1;
  }

  /// A cholmod_sparse view of A's lower triangle (stype -1: CHOLMOD ignores the upper part).
  template <class I>
  cholmod_sparse view(const SpMat& A) {
    cholmod_sparse s{};
    s.nrow = s.ncol = std::size_t(A.rows());
    s.nzmax = std::size_t(A.nonZeros());
    if constexpr (std::is_same_v<I, int>) {
      s.p = const_cast<int*>(A.outerIndexPtr());
      s.i = const_cast<int*>(A.innerIndexPtr());
    } else {
      outer_l.assign(A.outerIndexPtr(), A.outerIndexPtr() + A.outerSize() + 1);
      inner_l.assign(A.innerIndexPtr(), A.innerIndexPtr() + A.nonZeros());
      s.p = outer_l.data();
      s.i = inner_l.data();
    }
    s.x = const_cast<double*>(A.valuePtr());
    s.stype = -1;
    s.itype = Api<I>::itype;
    s.xtype = CHOLMOD_REAL;
    s.dtype = CHOLMOD_DOUBLE;
    s.sorted = 1;
    s.packed = 1;
    return s;
  }

  [[noreturn]] void fail(SolverStatus status, const std::string& what) {
    report.status = status;
    report.message = "cholmod: " + what;
    throw SolverError(status, report.message);
  }

  /// Translates a CHOLMOD status after a call into a SolverError (or nothing on success).
  void check_status(const char* phase) {
    const int st = common.status;
    if (st == CHOLMOD_OK) return;
    std::string detail = last_cholmod_message.empty() ? "" : ": " + last_cholmod_message;
    last_cholmod_message.clear();
    if (st == CHOLMOD_OUT_OF_MEMORY || st == CHOLMOD_TOO_LARGE)
      fail(SolverStatus::OutOfMemory,
           std::string(phase) + " ran out of memory (CHOLMOD status " + std::to_string(st) + ")" + detail);
    if (st == CHOLMOD_NOT_POSDEF) {
      // L->minor is the failing step in the permuted order; report the original column.
      std::ostringstream os;
      os << "matrix is not positive definite";
      if (factor && factor->minor < factor->n) {
        const std::size_t k = factor->minor;
        long column = long(k);
        if (factor->Perm) {
          column = common_long ? long(static_cast<SuiteSparse_long*>(factor->Perm)[k])
                               : long(static_cast<int*>(factor->Perm)[k]);
        }
        os << " (non-positive pivot at column " << column << ", elimination step " << k << ")";
      }
      fail(SolverStatus::NotPositiveDefinite, os.str());
    }
    if (st == CHOLMOD_DSMALL) return;  // warning: tiny pivot, the factor is still usable
    fail(st < 0 ? SolverStatus::InvalidInput : SolverStatus::NumericalIssue,
         std::string(phase) + " failed (CHOLMOD status " + std::to_string(st) + ")" + detail);
  }

  template <class I>
  void do_analyze(const SpMat& A) {
    cholmod_sparse s = view<I>(A);
    free_factor();
    apply_options();
    // geometric: nested dissection by planes through the points (detail/geometric_ordering.hpp),
    // handed to CHOLMOD as a given order (which it still postorders); without points, AMD.
    geometric_used = ordering == "geometric" && positions.rows() == A.rows() && A.rows() > 1;
    if (geometric_used) {
      common.nmethods = 1;
      common.method[0].ordering = CHOLMOD_GIVEN;  // analyze_p ignores the order for any other method
      const std::vector<int> order = detail::geometric_nested_dissection(A, positions);
      std::vector<I> perm(order.begin(), order.end());
      factor = Api<I>::analyze_p(&s, perm.data(), &common);
    } else {
      std::unique_lock<std::mutex> lock(metis_mutex, std::defer_lock);
      if (ordering != "amd" && ordering != "natural" && ordering != "geometric") lock.lock();
      factor = Api<I>::analyze(&s, &common);
    }
    if (!factor) check_status("analysis");
    if (!factor) fail(SolverStatus::NumericalIssue, "analysis returned no factor");
    check_status("analysis");
  }

  template <class I>
  void do_factorize(const SpMat& A) {
    cholmod_sparse s = view<I>(A);
    ConcurrencyScope concurrent;
    OpenMpScope omp(openmp_threads);
    FlushSubnormalsScope flush;
    Api<I>::factorize(&s, factor, &common);
    check_status("factorization");
    // Simplicial LDL^T only fails on a zero pivot: a negative D(k) (indefinite A) must be caught
    // here. D(k) is the first entry of column k of the factor.
    if (!factor->is_super && !factor->is_ll) {
      const I* colp = static_cast<const I*>(factor->p);
      const I* perm = static_cast<const I*>(factor->Perm);
      const double* x = static_cast<const double*>(factor->x);
      for (std::size_t k = 0; k < factor->n; ++k)
        if (!(x[colp[k]] > 0.0)) {
          std::ostringstream os;
          os << "matrix is not positive definite (non-positive pivot at column " << (perm ? long(perm[k]) : long(k))
             << ", elimination step " << k << ")";
          fail(SolverStatus::NotPositiveDefinite, os.str());
        }
    }
  }

  template <class I>
  Eigen::MatrixXd do_solve(const Eigen::MatrixXd& B) {
    cholmod_dense b{};
    b.nrow = std::size_t(B.rows());
    b.ncol = std::size_t(B.cols());
    b.nzmax = b.nrow * b.ncol;
    b.d = b.nrow;
    b.x = const_cast<double*>(B.data());
    b.xtype = CHOLMOD_REAL;
    b.dtype = CHOLMOD_DOUBLE;
    ConcurrencyScope concurrent;
    cholmod_dense* x = Api<I>::solve(factor, &b, &common);
    if (!x) {
      check_status("solve");
      fail(SolverStatus::NumericalIssue, "solve returned no solution");
    }
    Eigen::MatrixXd X = Eigen::Map<const Eigen::MatrixXd>(static_cast<double*>(x->x), B.rows(), B.cols());
    Api<I>::free_dense(&x, &common);
    check_status("solve");
    return X;
  }
};

CholmodSolver::CholmodSolver() : impl_(std::make_unique<Impl>()) {}
CholmodSolver::~CholmodSolver() = default;

std::vector<ParameterInfo> CholmodSolver::options() const {
  return {
      {"supernodal", "supernodal", "supernodal | simplicial | auto (CHOLMOD's choice by flop count)"},
      {"ordering", "geometric",
       "geometric (nested dissection by planes through the unknowns' positions when the caller gives them, "
       "else amd) | amd | metis | nesdis | natural | auto (AMD, METIS if fill is high) | best (try all)"},
      {"long_index", "false", "use CHOLMOD's 64-bit index API (very large systems)"},
      {"openmp_threads", "1",
       "1: serial, the parallelism comes from BLAS (default); 0: let OpenMP shrink CHOLMOD's team to idle cores "
       "(dynamic); >1: CHOLMOD's built-in team"},
      {"blas_threads", "0",
       "0: OpenBLAS as configured, switched to 1 thread once CHOLMOD calls overlap; n: set OpenBLAS to n threads "
       "(process-wide; use 1 for bitwise-reproducible concurrent use)"},
      {"check_symmetry", "true", "reject matrices with |A - A^T| > 1e-10 |A| (only the lower triangle is used)"},
  };
}

void CholmodSolver::configure(const Config& options) {
  options.check_keys(detail::allowed_keys(this->options()), "linear solver 'cholmod'");
  auto& s = *impl_;
  const std::string supernodal = options.get_string("supernodal", s.supernodal);
  if (supernodal != "supernodal" && supernodal != "simplicial" && supernodal != "auto")
    throw InputError("linear solver 'cholmod': config key 'supernodal' must be supernodal, simplicial or auto, got '" +
                     supernodal + "'");
  const std::string ordering = options.get_string("ordering", s.ordering);
  if (ordering != "geometric" && ordering != "amd" && ordering != "metis" && ordering != "nesdis" &&
      ordering != "natural" && ordering != "auto" && ordering != "best")
    throw InputError(
        "linear solver 'cholmod': config key 'ordering' must be geometric, amd, metis, nesdis, natural, auto or best, "
        "got '" +
        ordering + "'");
  const int threads = options.get_int("openmp_threads", s.openmp_threads);
  if (threads < 0) throw InputError("linear solver 'cholmod': config key 'openmp_threads' must be >= 0");
  const int blas = options.get_int("blas_threads", s.blas_threads);
  if (blas < 0) throw InputError("linear solver 'cholmod': config key 'blas_threads' must be >= 0");
  if (blas > 0) {
    concurrency_seen = true;  // explicit choice: no automatic switch
    detail::set_blas_threads(blas);
  }
  s.blas_threads = blas;
  s.supernodal = supernodal;
  s.ordering = ordering;
  s.openmp_threads = threads;
  s.check_symmetry = options.get_bool("check_symmetry", s.check_symmetry);
  const bool long_index = options.get_bool("long_index", s.long_index);
  if (long_index != s.long_index) {
    s.long_index = long_index;
    s.start(long_index);  // the common must match the API; any previous analysis is dropped
    s.pattern = {};
    s.factored = false;
  }
}

void CholmodSolver::analyze(const SpMat& A) {
  auto& s = *impl_;
  detail::check_matrix(A, "cholmod", false);
  SpMat compressed;
  const SpMat* a = &A;
  if (!A.isCompressed()) {
    compressed = A;
    compressed.makeCompressed();
    a = &compressed;
  }
  s.report = SolverReport{};
  s.factored = false;
  s.pattern = {};
  Stopwatch watch;
  try {
    if (s.long_index)
      s.do_analyze<SuiteSparse_long>(*a);
    else
      s.do_analyze<int>(*a);
  } catch (const std::bad_alloc&) {
    s.fail(SolverStatus::OutOfMemory, "out of memory in the symbolic analysis");
  }
  s.pattern.assign(*a);
  s.n = a->rows();
  ++s.analyses;
  s.report.status = SolverStatus::Success;
  s.report.analyze_seconds = watch.elapsed();
  s.report.ordering = ordering_used();
  s.report.factor_nonzeros = s.common.lnz;
  s.report.factor_flops = s.common.fl;
}

void CholmodSolver::set_positions(const Eigen::MatrixX3d& positions) {
  if (!positions.allFinite()) throw InputError("linear solver 'cholmod': set_positions: the positions must be finite");
  impl_->positions = positions;
}

void CholmodSolver::factorize(const SpMat& A) {
  auto& s = *impl_;
  detail::check_same_pattern(s.pattern, A, "cholmod");
  detail::check_matrix(A, "cholmod", s.check_symmetry);
  SpMat compressed;
  const SpMat* a = &A;
  if (!A.isCompressed()) {
    compressed = A;
    compressed.makeCompressed();
    a = &compressed;
  }
  s.factored = false;
  Stopwatch watch;
  try {
    if (s.long_index)
      s.do_factorize<SuiteSparse_long>(*a);
    else
      s.do_factorize<int>(*a);
  } catch (const std::bad_alloc&) {
    s.fail(SolverStatus::OutOfMemory, "out of memory in the numeric factorization");
  }
  s.report.factorize_seconds = watch.elapsed();
  s.report.status = SolverStatus::Success;
  s.report.message.clear();
  s.factored = true;
}

Eigen::MatrixXd CholmodSolver::solve(const Eigen::MatrixXd& B) {
  auto& s = *impl_;
  if (!s.factored)
    throw SolverError(SolverStatus::NotAnalyzed, "cholmod: solve() called before a successful factorize()");
  detail::check_rhs(B, s.n, "cholmod");
  Stopwatch watch;
  Eigen::MatrixXd X = s.long_index ? s.do_solve<SuiteSparse_long>(B) : s.do_solve<int>(B);
  s.report.solve_seconds = watch.elapsed();
  if (!X.allFinite()) s.fail(SolverStatus::NumericalIssue, "solution contains NaN/Inf");
  s.report.status = SolverStatus::Success;
  return X;
}

const SolverReport& CholmodSolver::info() const { return impl_->report; }
int CholmodSolver::analysis_count() const { return impl_->analyses; }
bool CholmodSolver::is_supernodal() const { return impl_->factor && impl_->factor->is_super; }
std::string CholmodSolver::ordering_used() const {
  if (!impl_->factor) return "";
  return impl_->geometric_used ? "geometric" : ordering_name(impl_->factor->ordering);
}

}  // namespace corrlap
