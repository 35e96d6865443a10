#pragma once
// Transparent huge pages for large, freshly allocated buffers.
#include <cstddef>

namespace corrlap {

/// Hints the kernel to back the 2 MiB-aligned interior of [p, p + bytes) with transparent huge
/// pages (Linux madvise MADV_HUGEPAGE; no-op elsewhere or for ranges under 4 MiB). Call on freshly
/// allocated buffers before their first write: on this class of machine first-touch page faults
/// of 4 KiB pages cost 0.7-5 ms per MiB, more than filling the buffer. Contents are unaffected.
/// Environment variable CORRLAP_NO_HUGEPAGES (any value) turns the hint off.
void advise_huge_pages(const void* p, std::size_t bytes);

}  // namespace corrlap
