#pragma once
// Transparent huge pages for large, freshly allocated buffers.
#include <cstddef>
#include <vector>

namespace corrlap {

/// Backs [p, p + bytes) with transparent huge pages where Linux allows it (no-op elsewhere or for
/// ranges under 4 MiB): the 2 MiB-aligned interior is hinted (MADV_HUGEPAGE, huge pages on first
/// touch) and the two partly covered 2 MiB blocks at the ends are collapsed into huge pages now
/// (MADV_COLLAPSE, Linux >= 6.1; the kernel keeps whatever else lives in them). Call on freshly
/// allocated buffers before their first write: first-touch faults of 4 KiB pages can cost more than
/// filling the buffer (bench/RESULTS.md, "bench_assembly", findings). Contents are unaffected and
/// every failure is ignored (it only means 4 KiB pages). Environment variable
/// CORRLAP_NO_HUGEPAGES (any value) turns all of it off.
void advise_huge_pages(const void* p, std::size_t bytes);

/// v = n copies of value, in new storage that is hinted onto huge pages (advise_huge_pages)
/// before its first write. For large, long-lived or soon fully written buffers (assembly
/// patterns): no 4 KiB first-touch faults, and fewer TLB misses when the buffer is streamed later
/// (a TLB miss is a two-level page walk on a VM). v's old storage is released.
template <class T>
void assign_on_huge_pages(std::vector<T>& v, std::size_t n, const T& value = T()) {
  std::vector<T> fresh;
  fresh.reserve(n);
  advise_huge_pages(fresh.data(), n * sizeof(T));
  fresh.assign(n, value);  // within the reserved storage: no reallocation
  v.swap(fresh);
}

/// The same for a copy of [first, last).
template <class T>
void assign_on_huge_pages(std::vector<T>& v, const T* first, const T* last) {
  std::vector<T> fresh;
  fresh.reserve(std::size_t(last - first));
  advise_huge_pages(fresh.data(), std::size_t(last - first) * sizeof(T));
  fresh.assign(first, last);
  v.swap(fresh);
}

}  // namespace corrlap
