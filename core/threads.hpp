#pragma once
// One knob for the number of worker threads: TBB (through tbb::global_control) and OpenBLAS.

namespace corrlap {

/// Limits TBB and OpenBLAS to n threads (n <= 0: all hardware threads). Process-wide; the last
/// call wins.
void set_thread_count(int n);

/// Current limit (the hardware concurrency when never set).
int thread_count();

/// Applies the CORRLAP_THREADS environment variable if it is set; returns the value used (0 if unset).
/// Throws InputError when it is not a positive integer.
int apply_thread_count_from_environment();

}  // namespace corrlap
