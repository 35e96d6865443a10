#pragma once
// One knob for the number of worker threads: TBB (through tbb::global_control) and OpenBLAS.

namespace corrlap {

/// Limits TBB and OpenBLAS to n threads (n <= 0: all hardware threads). Process-wide; the last
/// call wins.
void set_thread_count(int n);

/// Current limit (the hardware concurrency when never set).
int thread_count();

/// Subnormal numbers flushed to zero (x86-64: the FTZ and DAZ flags of MXCSR) in the calling
/// thread and in OpenBLAS's worker threads, for the rest of the process; elsewhere nothing. For a
/// program's start-up, before any other thread computes: OpenBLAS's workers are stopped and start
/// again at the next BLAS call, from a thread with the flags (new threads inherit them). Why:
/// Cholesky factors at a large diagonal shift (the regularization's B at large alpha on fine
/// surfaces) have entries far from the diagonal below the normal range, where every operation is
/// many times slower, in the BLAS workers too (bench/RESULTS.md, "Subnormal numbers in the
/// factorization"). Returns whether the flags are set.
bool flush_subnormals_in_process();

/// Applies the CORRLAP_THREADS environment variable if it is set; returns the value used (0 if unset).
/// Throws InputError when it is not a positive integer.
int apply_thread_count_from_environment();

}  // namespace corrlap
