#pragma once
// Shared by the libFuzzer targets: the readers take file names, so each input is written to a
// file in a RAM-backed folder with the extension the reader dispatches on. Expected failures are
// corrlap::Error (bad input gets a named error); anything else escaping a reader is a finding
// (a crash, a sanitizer report, or a std::exception that would reach the user as "internal error").
#include <unistd.h>

#include <corrlap/core/error.hpp>
#include <corrlap/core/memory_budget.hpp>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace corrlap::fuzz {

/// CORRLAP_MAX_MEMORY is honoured as by the command line: a long run can refuse large announced
/// volumes at the budget check (the check itself stays fuzzed) and spend its executions on the
/// parsing instead of filling a 256^3 grid per input.
inline const bool budget_from_environment = (apply_memory_budget_from_environment(), true);

/// Writes the input to <dir>/corrlap-fuzz-<pid><extension> (dir: $TMPDIR, else /dev/shm, else /tmp)
/// and returns the path. The same file is reused by every run of the process.
inline std::string write_input(const std::uint8_t* data, std::size_t size, const char* extension) {
  static const std::string dir = [] {
    if (const char* t = std::getenv("TMPDIR")) return std::string(t);
    return std::string(access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp");
  }();
  const std::string path = dir + "/corrlap-fuzz-" + std::to_string(getpid()) + extension;
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) std::abort();
  if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
  std::fclose(f);
  return path;
}

/// Runs `read` and swallows corrlap's own errors only.
template <class Read>
void expect_named_errors(Read&& read) {
  try {
    read();
  } catch (const corrlap::Error&) {
  }
}

}  // namespace corrlap::fuzz
