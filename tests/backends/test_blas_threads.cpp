// The OpenBLAS thread policy (backends/detail/blas_threads.hpp): serial scopes nest across threads,
// restore the count they found, and defer explicit changes to their end.
#include <doctest/doctest.h>

#include <corrlap/backends/detail/blas_threads.hpp>
#include <thread>

extern "C" int openblas_get_num_threads() __attribute__((weak));

using corrlap::detail::SerialBlasScope;
using corrlap::detail::set_blas_threads;

TEST_CASE("SerialBlasScope runs OpenBLAS on one thread and restores the count, set_blas_threads waits for it") {
  if (!openblas_get_num_threads) {
    MESSAGE("BLAS is not OpenBLAS: nothing to check");
    return;
  }
  const int original = openblas_get_num_threads();
  set_blas_threads(2);
  REQUIRE(openblas_get_num_threads() == 2);
  {
    const SerialBlasScope outer;
    CHECK(openblas_get_num_threads() == 1);
    std::thread other([] {
      const SerialBlasScope inner;  // overlapping scope on another thread
      CHECK(openblas_get_num_threads() == 1);
    });
    other.join();
    CHECK(openblas_get_num_threads() == 1);  // the inner scope's end did not restore
    set_blas_threads(3);                     // deferred to the end of the last scope
    CHECK(openblas_get_num_threads() == 1);
  }
  CHECK(openblas_get_num_threads() == 3);
  { const SerialBlasScope scope; }
  CHECK(openblas_get_num_threads() == 3);
  set_blas_threads(original);
}
