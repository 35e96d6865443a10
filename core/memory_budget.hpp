#pragma once
// The memory budget. Sizes that come from input (a count in a file header, a grid step, a box) are
// checked against it before the memory is allocated, so that an absurd request is refused with
// the numbers in the message instead of thrashing the machine or being killed by the kernel.
// Process-wide, like the thread count: the CLI sets it from --max-memory (or CORRLAP_MAX_MEMORY).
#include <cstdint>
#include <string>

namespace corrlap {

/// Physical memory of this machine in bytes (sysconf); 16 GiB when the system does not say.
std::uint64_t physical_memory_bytes();

/// The current budget in bytes: the last set_memory_budget value, else physical_memory_bytes().
std::uint64_t memory_budget();
/// Sets the budget (bytes > 0); 0 restores the default (the machine's memory). Thread-safe.
void set_memory_budget(std::uint64_t bytes);

/// Throws InputError("<what> needs <bytes>, more than the memory budget of <budget> (...); <remedy>")
/// when bytes exceeds the budget (also for NaN or infinite estimates). `bytes` is a double so that
/// callers can multiply announced counts without overflow.
void check_memory_budget(double bytes, const std::string& what, const std::string& remedy = "");

/// "8G", "512M", "1.5GiB", "64k", "1000000" (bytes; suffixes K, M, G, T with or without "iB" or "B"
/// are powers of 1024) -> bytes. InputError naming the text otherwise (zero, negative, garbage).
std::uint64_t parse_memory_size(const std::string& text);

/// "60 B", "12.3 KiB", "4.0 GiB": sizes in messages.
std::string readable_bytes(double bytes);

/// Applies CORRLAP_MAX_MEMORY if set; returns the budget it set (0 if unset). InputError if malformed.
std::uint64_t apply_memory_budget_from_environment();

}  // namespace corrlap
