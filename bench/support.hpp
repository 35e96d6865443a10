#pragma once
// Helpers shared by the benchmarks: peak memory of the process.
#include <Eigen/Sparse>
#include <cstddef>

namespace corrlap::bench {
/// Resident set size of this process now, in MiB (VmRSS).
double rss_mib();
/// Peak resident set size of this process so far, in MiB (VmHWM).
double peak_rss_mib();
/// Bytes of a compressed sparse matrix: values, inner indices and outer offsets.
inline double sparse_bytes(const Eigen::SparseMatrix<double>& A) {
  return double(A.nonZeros()) * (sizeof(double) + sizeof(Eigen::SparseMatrix<double>::StorageIndex)) +
         double(A.outerSize() + 1) * sizeof(Eigen::SparseMatrix<double>::StorageIndex);
}
/// Resets the peak RSS counter (Linux: writes 5 to /proc/self/clear_refs); false if unsupported.
bool reset_peak_rss();
}  // namespace corrlap::bench
