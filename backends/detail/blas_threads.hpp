#pragma once
// OpenBLAS's thread count (internal): the one process-wide BLAS setting, changed only here.
// Debian's pthread OpenBLAS keeps its idle workers spinning in sched_yield for a while after each
// call. That pays off for a large factorization's dense kernels and not for the many small calls
// of an eigen iteration, where the spinning costs system time and, on a busy machine, wall time
// (docs/scale.md "Threads"). Without OpenBLAS every function here does nothing.
namespace corrlap::detail {

/// Sets OpenBLAS to n >= 1 threads. Inside a SerialBlasScope the change takes effect when the last
/// scope ends.
void set_blas_threads(int n);

/// For its lifetime, OpenBLAS runs one thread. Scopes may overlap across threads: the first to
/// start saves the count, the last to end restores it (or the one set_blas_threads asked for
/// meanwhile).
class SerialBlasScope {
 public:
  SerialBlasScope();
  ~SerialBlasScope();
  SerialBlasScope(const SerialBlasScope&) = delete;
  SerialBlasScope& operator=(const SerialBlasScope&) = delete;
};

}  // namespace corrlap::detail
