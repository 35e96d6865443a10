#include "linear_solver.hpp"

namespace corrlap {

const char* to_string(SolverStatus status) {
  switch (status) {
    case SolverStatus::Success:
      return "success";
    case SolverStatus::NotAnalyzed:
      return "not analyzed";
    case SolverStatus::NotPositiveDefinite:
      return "not positive definite";
    case SolverStatus::NumericalIssue:
      return "numerical issue";
    case SolverStatus::NoConvergence:
      return "no convergence";
    case SolverStatus::InvalidInput:
      return "invalid input";
    case SolverStatus::OutOfMemory:
      return "out of memory";
  }
  return "?";
}

}  // namespace corrlap
