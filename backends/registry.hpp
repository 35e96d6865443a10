#pragma once
// Registries of the linear solver backends and eigen solvers, by name.
#include <corrlap/core/linear_solver.hpp>
#include <corrlap/core/registry.hpp>

namespace corrlap {

using LinearSolverRegistry = Registry<LinearSolver>;
using EigenSolverRegistry = Registry<EigenSolver>;

/// Process-wide registries, filled with the built-in backends on first use.
LinearSolverRegistry& linear_solver_registry();
EigenSolverRegistry& eigen_solver_registry();

/// Creates the solver named by config key "solver" (default `fallback`) and configures it with
/// the remaining keys. Unknown names or keys are InputErrors listing the valid ones.
std::unique_ptr<LinearSolver> make_linear_solver(const Config& config, const std::string& fallback = "eigen-ldlt");

}  // namespace corrlap
