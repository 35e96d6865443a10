#include "progress.hpp"

#include <algorithm>
#include <memory>
#include <mutex>

namespace corrlap {

ProgressFn tenths_progress(std::string what, ProgressLine line, std::int64_t min_total) {
  if (!line) return {};
  // Shared by the copies of the returned function (std::function copies its target).
  struct State {
    std::mutex mutex;
    int reported = 0;  // tenths already reported
  };
  auto state = std::make_shared<State>();
  return [what = std::move(what), line = std::move(line), min_total, state](std::int64_t done, std::int64_t total) {
    if (total <= 0 || total < min_total) return;
    const int tenth = int(10 * std::min(done, total) / total);
    // The lock orders the lines and keeps one call of `line` at a time; the loops report a few
    // hundred times at most, so it is never contended for long.
    std::lock_guard<std::mutex> lock(state->mutex);
    if (tenth <= state->reported) return;
    state->reported = tenth;  // before the call: a throwing line is not called for this tenth again
    line(what + ": " + std::to_string(10 * tenth) + "%");
  };
}

}  // namespace corrlap
