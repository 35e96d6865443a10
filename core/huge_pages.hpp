#pragma once
// Transparent huge pages for large, freshly allocated buffers.
#include <cstddef>
#include <vector>

namespace corrlap {

/// Backs [p, p + bytes) with transparent huge pages where Linux allows it (no-op elsewhere or for
/// ranges under 4 MiB): the 2 MiB-aligned interior is hinted (MADV_HUGEPAGE, huge pages on first
/// touch) and the two partly covered 2 MiB blocks at the ends are collapsed into huge pages now
/// (MADV_COLLAPSE, Linux >= 6.1; the kernel keeps whatever else lives in them). Call on freshly
/// allocated buffers before their first write: on this class of machine first-touch page faults
/// of 4 KiB pages cost 0.7-5 ms per MiB, more than filling the buffer. Contents are unaffected and
/// every failure is ignored (it only means 4 KiB pages). Environment variable
/// CORRLAP_NO_HUGEPAGES (any value) turns all of it off.
void advise_huge_pages(const void* p, std::size_t bytes);

/// Moves an already written, long-lived buffer (a cached assembly pattern) onto transparent huge
/// pages: hints the 2 MiB blocks inside it and collapses them now (MADV_COLLAPSE; the kernel
/// copies the contents). No-op under 4 MiB. Costs about one copy of the buffer, once. Worth it for data read on every
/// assembly: on a VM each TLB miss is a two-level page walk, and with 4 KiB pages the streaming
/// pattern reads of the interpolated fill made its steady-state time vary by ~1.7x.
/// Failures are ignored; CORRLAP_NO_HUGEPAGES turns it off.
void collapse_to_huge_pages(const void* p, std::size_t bytes);

template <class T>
void collapse_to_huge_pages(const std::vector<T>& v) {
  collapse_to_huge_pages(v.data(), v.size() * sizeof(T));
}

}  // namespace corrlap
