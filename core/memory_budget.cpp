#include "memory_budget.hpp"

#include <unistd.h>

#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "error.hpp"

namespace corrlap {
namespace {
std::atomic<std::uint64_t> budget_bytes{0};  // 0: the default
}  // namespace

std::uint64_t physical_memory_bytes() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  if (pages <= 0 || page <= 0) return std::uint64_t{16} << 30;
  return std::uint64_t(pages) * std::uint64_t(page);
}

std::uint64_t memory_budget() {
  const std::uint64_t set = budget_bytes.load(std::memory_order_relaxed);
  return set ? set : physical_memory_bytes();
}

void set_memory_budget(std::uint64_t bytes) { budget_bytes.store(bytes, std::memory_order_relaxed); }

std::string readable_bytes(double bytes) {
  static const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  if (!std::isfinite(bytes)) return "an unbounded amount";
  int u = 0;
  while (bytes >= 1024.0 && u < 6) {
    bytes /= 1024.0;
    ++u;
  }
  char buf[48];
  if (u == 0)
    std::snprintf(buf, sizeof buf, "%.0f B", bytes);
  else
    std::snprintf(buf, sizeof buf, "%.1f %s", bytes, units[u]);
  return buf;
}

void check_memory_budget(double bytes, const std::string& what, const std::string& remedy) {
  const std::uint64_t budget = memory_budget();
  if (bytes <= double(budget)) return;  // false for NaN: refused below
  const bool default_budget = budget_bytes.load(std::memory_order_relaxed) == 0;
  std::string message = what + " needs " + readable_bytes(bytes) + ", more than the memory budget of " +
                        readable_bytes(double(budget)) +
                        (default_budget ? " (this machine's memory; max_memory sets it)" : " (max_memory)");
  if (!remedy.empty()) message += "; " + remedy;
  throw InputError(message, "max_memory");
}

std::uint64_t parse_memory_size(const std::string& text) {
  const auto fail = [&]() -> std::uint64_t {
    throw InputError("memory size '" + text +
                     "': expected a positive size such as 8G, 512M, 1.5GiB or 1000000 (bytes)");
  };
  std::size_t i = 0;
  while (i < text.size() && (std::isdigit(static_cast<unsigned char>(text[i])) || text[i] == '.')) ++i;
  if (i == 0) return fail();
  char* end = nullptr;
  const std::string number = text.substr(0, i);
  const double value = std::strtod(number.c_str(), &end);
  if (end != number.c_str() + number.size() || !std::isfinite(value) || !(value > 0)) return fail();
  std::string unit = text.substr(i);
  if (!unit.empty() && unit.front() == ' ') unit.erase(0, 1);
  for (char& c : unit) c = char(std::toupper(static_cast<unsigned char>(c)));
  double scale = 0;
  if (unit.empty() || unit == "B")
    scale = 1;
  else {
    const std::string prefix = unit.substr(0, 1), rest = unit.substr(1);
    if (!(rest.empty() || rest == "B" || rest == "IB")) return fail();
    if (prefix == "K") scale = 1024.0;
    if (prefix == "M") scale = 1024.0 * 1024.0;
    if (prefix == "G") scale = 1024.0 * 1024.0 * 1024.0;
    if (prefix == "T") scale = 1024.0 * 1024.0 * 1024.0 * 1024.0;
    if (scale == 0) return fail();
  }
  const double bytes = std::floor(value * scale);
  if (!(bytes >= 1.0) || bytes > 9.0e18) return fail();
  return std::uint64_t(bytes);
}

std::uint64_t apply_memory_budget_from_environment() {
  const char* env = std::getenv("CORRLAP_MAX_MEMORY");
  if (!env || !*env) return 0;
  std::uint64_t bytes = 0;
  try {
    bytes = parse_memory_size(env);
  } catch (const InputError& e) {
    throw InputError(std::string("CORRLAP_MAX_MEMORY: ") + e.what());
  }
  set_memory_budget(bytes);
  return bytes;
}

}  // namespace corrlap
