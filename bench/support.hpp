#pragma once
// Helpers shared by the benchmarks: peak memory of the process.
#include <cstddef>

namespace corrlap::bench {
/// Resident set size of this process now, in MiB (VmRSS).
double rss_mib();
/// Peak resident set size of this process so far, in MiB (VmHWM).
double peak_rss_mib();
/// Resets the peak RSS counter (Linux: writes 5 to /proc/self/clear_refs); false if unsupported.
bool reset_peak_rss();
}  // namespace corrlap::bench
