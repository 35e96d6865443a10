#pragma once
// Progress of long computations, for front ends that show it (the CLI's stderr lines, Python's
// `progress=` callable). The library reports; what to show and where is the front end's.
#include <cstdint>
#include <functional>
#include <string>

namespace corrlap {

/// Progress of one loop: (done, total) in units of the loop's own; may be called from worker
/// threads, concurrently.
using ProgressFn = std::function<void(std::int64_t done, std::int64_t total)>;

/// One line of progress text, e.g. "ii normals: 40%" or "solving with alpha0 = 10".
using ProgressLine = std::function<void(const std::string&)>;

/// A ProgressFn that calls `line` with "<what>: N%" once for each tenth of `total` reached
/// (N = 10, 20, ..., 100), in increasing order, one call at a time whatever thread reports; loops
/// of fewer than `min_total` units call nothing. An empty `line` gives an empty ProgressFn.
/// An exception thrown by `line` leaves through the reporting thread's call (the loop's own
/// exception handling carries it to the caller); that tenth is not reported again.
ProgressFn tenths_progress(std::string what, ProgressLine line, std::int64_t min_total = 0);

}  // namespace corrlap
