#pragma once
// Library errors in CLI terms: the library names the parameter at fault (InputError::parameter,
// e.g. "ii_radius"). The flag of that parameter (--ii-radius) is added in one place, where main.cpp
// reports the error; this only puts the command in front where the library's message lacks it.
#include <corrlap/core/error.hpp>
#include <string>

namespace corrlap::cli {

/// Runs `f`. An InputError is rethrown (as the same type, with the same parameter) with `command`
/// ("regularize") in front when not empty.
template <class F>
auto in_cli_terms(F&& f, const std::string& command = {}) -> decltype(f()) {
  try {
    return f();
  } catch (const InputError& e) {
    if (command.empty()) throw;
    const std::string message = command + ": " + e.what();
    if (dynamic_cast<const IoError*>(&e)) throw IoError(message, e.parameter());
    throw InputError(message, e.parameter());
  }
}

}  // namespace corrlap::cli
