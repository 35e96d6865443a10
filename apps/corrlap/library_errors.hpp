#pragma once
// Library errors in CLI terms: the library names the parameter at fault (InputError::parameter,
// e.g. "ii_radius"); the CLI adds its flag (--ii-radius) and the command.
#include <corrlap/core/error.hpp>
#include <string>

#include "deprecated.hpp"

namespace corrlap::cli {

/// Runs `f`. An InputError is rethrown (as the same type) with `command` ("regularize") in front
/// when not empty, and the CLI flag of its parameter, if any, at the end.
template <class F>
auto in_cli_terms(F&& f, const std::string& command = {}) -> decltype(f()) {
  try {
    return f();
  } catch (const InputError& e) {
    std::string message = command.empty() ? std::string(e.what()) : command + ": " + e.what();
    if (!e.parameter().empty()) message += " (" + flag_of(e.parameter()) + ")";
    if (dynamic_cast<const IoError*>(&e)) throw IoError(message, e.parameter());
    throw InputError(message, e.parameter());
  }
}

}  // namespace corrlap::cli
