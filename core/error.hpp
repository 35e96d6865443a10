#pragma once
// Errors raised by corrlap. Every user-facing failure is an exception derived from corrlap::Error
// whose message names the offending input (file, element, key) and the problem.
#include <stdexcept>
#include <string>
#include <utility>

namespace corrlap {

/// Base of every corrlap error.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Bad user input: malformed file, wrong config key, inconsistent normals, empty volume...
/// The message speaks in library terms. When one parameter is at fault, `parameter()` is its
/// library name ("ii_radius", "lambda"): each front end adds its own spelling of it (the CLI's
/// --ii-radius, a Python keyword) when it reports the error.
class InputError : public Error {
 public:
  explicit InputError(const std::string& what, std::string parameter = {})
      : Error(what), parameter_(std::move(parameter)) {}
  const std::string& parameter() const noexcept { return parameter_; }

 private:
  std::string parameter_;
};

/// A file could not be read or written, or its content is malformed.
class IoError : public InputError {
 public:
  using InputError::InputError;
};

/// A numerical procedure failed (singular system, no convergence...).
class NumericalError : public Error {
 public:
  using Error::Error;
};

}  // namespace corrlap
