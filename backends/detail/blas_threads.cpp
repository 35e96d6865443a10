#include "blas_threads.hpp"

#include <mutex>

extern "C" void openblas_set_num_threads(int) __attribute__((weak));
extern "C" int openblas_get_num_threads() __attribute__((weak));

namespace corrlap::detail {

namespace {
std::mutex mutex;
int serial_scopes = 0;
int restore_to = 0;  // the count to set when the last scope ends
}  // namespace

void set_blas_threads(int n) {
  if (!openblas_set_num_threads || n < 1) return;
  std::lock_guard<std::mutex> lock(mutex);
  if (serial_scopes > 0)
    restore_to = n;
  else
    openblas_set_num_threads(n);
}

SerialBlasScope::SerialBlasScope() {
  if (!openblas_set_num_threads || !openblas_get_num_threads) return;
  std::lock_guard<std::mutex> lock(mutex);
  if (serial_scopes++ == 0) {
    restore_to = openblas_get_num_threads();
    if (restore_to != 1) openblas_set_num_threads(1);
  }
}

SerialBlasScope::~SerialBlasScope() {
  if (!openblas_set_num_threads || !openblas_get_num_threads) return;
  std::lock_guard<std::mutex> lock(mutex);
  if (--serial_scopes == 0 && restore_to != openblas_get_num_threads()) openblas_set_num_threads(restore_to);
}

}  // namespace corrlap::detail
