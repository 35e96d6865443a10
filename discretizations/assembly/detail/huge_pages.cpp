#include "huge_pages.hpp"

#include <sys/mman.h>

#include <cstdint>
#include <cstdlib>

#ifndef MADV_COLLAPSE
#define MADV_COLLAPSE 25  // Linux 6.1; older kernels reject it with EINVAL, which is harmless here
#endif

namespace corrlap {

void advise_huge_pages(const void* p, std::size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  constexpr std::uintptr_t huge = std::uintptr_t(2) << 20;
  static const bool disabled = std::getenv("CORRLAP_NO_HUGEPAGES") != nullptr;
  if (disabled || bytes < 2 * huge) return;
  const std::uintptr_t lo = reinterpret_cast<std::uintptr_t>(p), hi = lo + bytes;
  const std::uintptr_t head = lo & ~(huge - 1), tail = hi & ~(huge - 1);
  const std::uintptr_t b = lo == head ? lo : head + huge;
  // The aligned interior: huge pages on first touch.
  if (tail > b) (void)madvise(reinterpret_cast<void*>(b), tail - b, MADV_HUGEPAGE);  // a hint: failure is harmless
  // The 2 MiB blocks holding the head and the tail are shared with the malloc header and
  // possibly other allocations, and malloc has already touched the header, so a fault there
  // would map 4 KiB pages: up to 511 faults per end (bench/RESULTS.md, "bench_assembly"). Collapsing such a block
  // maps it as one huge page now (existing contents are copied by the kernel). It fails
  // harmlessly when the block is not entirely inside one mapping.
  if (head != lo) (void)madvise(reinterpret_cast<void*>(head), huge, MADV_COLLAPSE);
  if (tail != hi && tail != head) (void)madvise(reinterpret_cast<void*>(tail), huge, MADV_COLLAPSE);
#else
  (void)p;
  (void)bytes;
#endif
}

}  // namespace corrlap
