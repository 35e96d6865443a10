#pragma once
// Checked sizes and conversions shared by the readers (internal). Every count or size a file
// announces goes through these before it is used to allocate or to loop, so that a corrupt header
// gives an IoError naming the value and the limit instead of a wrap-around, an undefined
// conversion or an allocation of gigabytes.
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/core/memory_budget.hpp>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <istream>
#include <limits>
#include <optional>
#include <string>

namespace corrlap::io_detail {

/// a * b, or nullopt when it does not fit in 64 bits.
inline std::optional<std::uint64_t> checked_mul(std::uint64_t a, std::uint64_t b) {
  std::uint64_t r = 0;
  if (__builtin_mul_overflow(a, b, &r)) return std::nullopt;
  return r;
}

/// "4 294 967 296": digits grouped by three, so that large counts in messages are readable.
inline std::string readable_count(std::uint64_t n) {
  std::string digits = std::to_string(n), out;
  for (std::size_t i = 0; i < digits.size(); ++i) {
    if (i != 0 && (digits.size() - i) % 3 == 0) out += ' ';
    out += digits[i];
  }
  return out;
}

/// "60 B", "12.3 KiB", "4.0 GiB" (core/memory_budget.hpp).
inline std::string readable_bytes(double bytes) { return corrlap::readable_bytes(bytes); }

/// Refuses, as an IoError prefixed by `file_label` (e.g. "PLY file 'x.ply'"), a reader allocation
/// of `bytes` for `what` (e.g. "3 000 000 vertices") above the memory budget (max_memory; the
/// parameter tag is kept).
inline void check_budget(const std::string& file_label, double bytes, const std::string& what) {
  try {
    check_memory_budget(bytes, what, "is the header corrupt?");
  } catch (const InputError& e) {
    throw IoError(file_label + ": " + e.what(), e.parameter());
  }
}

/// A double from a file, printed for a message: at most 6 significant digits, nan/inf spelled out
/// (never a 300-digit expansion, never an undefined conversion to an integer).
inline std::string readable_number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

/// The integer value of v when v is finite, integral and within [lo, hi]; nullopt otherwise
/// (NaN, infinities and out-of-range values, whose conversion to an integer is undefined).
inline std::optional<std::int64_t> checked_integer(double v, std::int64_t lo, std::int64_t hi) {
  if (!std::isfinite(v) || v != std::floor(v)) return std::nullopt;
  // Compare as doubles first: lo and hi up to 2^53 are exact, and v is then in range for int64.
  if (!(v >= double(lo) && v <= double(hi))) return std::nullopt;
  const auto i = static_cast<std::int64_t>(v);
  if (i < lo || i > hi) return std::nullopt;
  return i;
}

/// Bytes from the current position to the end of the stream, without consuming them.
inline std::uint64_t bytes_left(std::istream& in) {
  const auto here = in.tellg();
  if (here < 0) return 0;
  in.seekg(0, std::ios::end);
  const auto end = in.tellg();
  in.seekg(here);
  return end > here ? std::uint64_t(end - here) : 0;
}

/// Size of the file at path in bytes (0 when it cannot be opened).
inline std::uint64_t file_size(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return in ? bytes_left(in) : 0;
}

}  // namespace corrlap::io_detail
