#pragma once
// Storage of the assembly outputs and scratch buffers: the one place (with huge_pages.*) where
// memory is placed on transparent huge pages. Internal header.
#include <Eigen/Sparse>
#include <cstddef>
#include <memory>

#include "huge_pages.hpp"

namespace corrlap::detail {

/// Smallest capacity >= n whose value (8 bytes per entry) and row-index (4 bytes per entry)
/// arrays, each with glibc's 16-byte header and rounded up to 4 KiB pages, are whole multiples of
/// 2 MiB (4 c + 2048 is a multiple of 2 MiB). Linux maps anonymous regions of such lengths at
/// 2 MiB-aligned addresses, so when malloc serves them with their own mapping, both end blocks lie
/// inside it and advise_huge_pages can make the whole array huge pages.
inline Eigen::Index mapping_friendly_capacity(Eigen::Index n) {
  constexpr Eigen::Index step = (Eigen::Index(2) << 20) / 4;  // entries per 2 MiB of indices
  return ((n + 512 + step - 1) / step) * step - 512;
}

/// Sizes A as a V x V matrix with nnz stored entries whose values and row indices the caller will
/// write (contents left uninitialized), keeping A's storage when it is large enough (assemble_into).
/// New storage gets at least 2 MiB of spare capacity past the last entry (a mapping-friendly
/// capacity, above) and advise_huge_pages over all of it: one fresh 2 MiB block then costs one
/// fault instead of up to 512 (fault counts: bench/RESULTS.md, "bench_assembly", findings).
inline void size_for_fill(Eigen::SparseMatrix<double>& A, int V, Eigen::Index nnz) {
  constexpr Eigen::Index kSpare = (Eigen::Index(2) << 20) / Eigen::Index(sizeof(int));  // 2 MiB of indices
  A.resize(V, V);  // keeps the allocation of the values and indices
  if (A.data().allocatedSize() < nnz) {
    A.data().reserve(mapping_friendly_capacity(nnz + kSpare));
    // Only new storage: reused storage (assemble_into) was advised when it was allocated, and a
    // collapse call is not free even on a block that is already a huge page.
    const std::size_t capacity = std::size_t(A.data().allocatedSize());
    advise_huge_pages(A.valuePtr(), capacity * sizeof(double));
    advise_huge_pages(A.innerIndexPtr(), capacity * sizeof(int));
  }
  A.resizeNonZeros(nnz);
}

/// Gives A (already sized n x n, outer index to be written by the caller) exactly nnz stored
/// entries in fresh storage, hinted onto huge pages before the caller's first write: for outputs
/// filled once in a parallel pass (the heat kernel), whose 4 KiB first-touch faults can cost as
/// much as the computation (bench/RESULTS.md, "bench_heat_kernel"). Throws std::bad_alloc like
/// Eigen's resizeNonZeros.
inline void allocate_sparse_storage(Eigen::SparseMatrix<double>& A, Eigen::Index nnz) {
  A.resizeNonZeros(nnz);
  advise_huge_pages(A.innerIndexPtr(), std::size_t(nnz) * sizeof(int));
  advise_huge_pages(A.valuePtr(), std::size_t(nnz) * sizeof(double));
}

/// n uninitialized doubles, hinted onto huge pages: per-face scratch that a parallel kernel loop
/// writes entirely (first-touch faults then spread over the threads, 512x fewer of them).
inline std::unique_ptr<double[]> fresh_buffer(std::size_t n) {
  std::unique_ptr<double[]> b(new double[n]);
  advise_huge_pages(b.get(), n * sizeof(double));
  return b;
}

}  // namespace corrlap::detail
