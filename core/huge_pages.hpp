#pragma once
// Transparent huge pages for large, freshly allocated buffers.
#include <cstddef>

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

}  // namespace corrlap
