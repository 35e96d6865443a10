#pragma once
// Errors raised by corrlap. Every user-facing failure is an exception derived from corrlap::Error
// whose message names the offending input (file, element, key) and the problem.
#include <stdexcept>
#include <string>

namespace corrlap {

/// Base of every corrlap error.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Bad user input: malformed file, wrong config key, inconsistent normals, empty volume...
class InputError : public Error {
 public:
  using Error::Error;
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
