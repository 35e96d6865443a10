#include "threads.hpp"

#include <tbb/global_control.h>
#include <tbb/info.h>
#if defined(__x86_64__) || defined(__SSE2__)
#include <xmmintrin.h>
#endif

#include <cstdlib>
#include <memory>
#include <mutex>
#include <string>

#include "error.hpp"

// OpenBLAS is optional at link time: the weak symbols are null when OpenBLAS is not loaded.
extern "C" void openblas_set_num_threads(int) __attribute__((weak));
// Stops OpenBLAS's worker threads (its own fork handler); the next parallel call starts them again.
extern "C" int blas_thread_shutdown_(void) __attribute__((weak));

namespace corrlap {

namespace {
std::mutex g_mutex;
std::unique_ptr<tbb::global_control> g_control;
int g_threads = 0;
}  // namespace

void set_thread_count(int n) {
  std::lock_guard<std::mutex> lock(g_mutex);
  const int hw = tbb::info::default_concurrency();
  const int value = n <= 0 ? hw : n;
  g_control.reset();
  g_control = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, std::size_t(value));
  g_threads = value;
  if (openblas_set_num_threads) openblas_set_num_threads(value);
}

bool flush_subnormals_in_process() {
#if defined(__x86_64__) || defined(__SSE2__)
  constexpr unsigned kFlushToZero = 0x8000, kDenormalsAreZero = 0x0040;
  _mm_setcsr(_mm_getcsr() | kFlushToZero | kDenormalsAreZero);
  if (blas_thread_shutdown_) blas_thread_shutdown_();
  return true;
#else
  return false;
#endif
}

int thread_count() {
  std::lock_guard<std::mutex> lock(g_mutex);
  if (g_threads > 0) return g_threads;
  return int(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
}

int apply_thread_count_from_environment() {
  const char* s = std::getenv("CORRLAP_THREADS");
  if (!s || !*s) return 0;
  char* end = nullptr;
  const long n = std::strtol(s, &end, 10);
  if (*end != '\0' || n <= 0 || n > 4096)
    throw InputError(std::string("CORRLAP_THREADS='") + s + "': expected a positive integer");
  set_thread_count(int(n));
  return int(n);
}

}  // namespace corrlap
