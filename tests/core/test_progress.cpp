// Progress by tenths (core/progress.hpp), as the CLI's "ii normals: N%" lines and Python's
// progress= callable receive it: each tenth once and in order, whatever thread reports.
#include <doctest/doctest.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <corrlap/core/progress.hpp>
#include <stdexcept>
#include <string>
#include <vector>

using namespace corrlap;

namespace {
std::vector<std::string> expected_tenths(const std::string& what) {
  std::vector<std::string> lines;
  for (int k = 1; k <= 10; ++k) lines.push_back(what + ": " + std::to_string(10 * k) + "%");
  return lines;
}
}  // namespace

TEST_CASE("tenths_progress reports each tenth once, in order, from any thread") {
  std::vector<std::string> lines;  // appended under the progress function's own lock only
  const ProgressFn progress = tenths_progress("work", [&](const std::string& line) { lines.push_back(line); });
  constexpr std::int64_t total = 100000;
  std::atomic<std::int64_t> done{0};
  tbb::parallel_for(std::int64_t(0), total, std::int64_t(97), [&](std::int64_t begin) {
    const std::int64_t end = std::min(begin + 97, total);
    progress(done += end - begin, total);
  });
  CHECK(lines == expected_tenths("work"));
  // Reports past the end, or repeated, add nothing.
  progress(total, total);
  progress(2 * total, total);
  CHECK(lines.size() == 10);
}

TEST_CASE("tenths_progress: jumps report the tenth reached, short loops and empty lines nothing") {
  std::vector<std::string> lines;
  const ProgressLine keep = [&](const std::string& line) { lines.push_back(line); };
  ProgressFn progress = tenths_progress("ii normals", keep);
  progress(5, 100);   // below the first tenth
  progress(37, 100);  // 30 %: the tenths skipped are not reported
  progress(100, 100);
  CHECK(lines == std::vector<std::string>{"ii normals: 30%", "ii normals: 100%"});
  lines.clear();
  progress = tenths_progress("short", keep, 1000);
  for (int i = 1; i <= 999; ++i) progress(i, 999);
  CHECK(lines.empty());
  progress(0, 0);  // an empty loop
  CHECK(lines.empty());
  CHECK_FALSE(tenths_progress("none", {}));
}

TEST_CASE("tenths_progress: an exception from the line leaves through the report, once") {
  int calls = 0;
  const ProgressFn progress = tenths_progress("stop", [&](const std::string& line) {
    ++calls;
    if (line == "stop: 20%") throw std::runtime_error("asked to stop");
  });
  progress(10, 100);
  CHECK_THROWS_WITH_AS(progress(25, 100), "asked to stop", std::runtime_error);
  CHECK(calls == 2);
  // A late report from another thread does not repeat 20 %; the next tenth is the line's to refuse.
  progress(26, 100);
  CHECK(calls == 2);
  progress(30, 100);
  CHECK(calls == 3);
}
