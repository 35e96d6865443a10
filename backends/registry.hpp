#pragma once
// Registries of the linear solver backends and eigen solvers, by name, and the two entry points
// that create a configured solver: make_linear_solver and make_eigen_solver.
#include <corrlap/core/linear_solver.hpp>
#include <corrlap/core/registry.hpp>
#include <memory>
#include <string>

namespace corrlap {

using LinearSolverRegistry = Registry<LinearSolver>;
using EigenSolverRegistry = Registry<EigenSolver>;

/// Process-wide registries, filled with the built-in backends on first use.
LinearSolverRegistry& linear_solver_registry();
EigenSolverRegistry& eigen_solver_registry();

/// A linear solver for the SPD systems -L + ... of the problems (docs/math.md §10), configured with
/// `options` (backend keys, see `corrlap backends`), e.g.
///   auto solver = make_linear_solver("cholmod");
///   solver->compute(A);  Eigen::MatrixXd X = solver->solve(B);
/// Names: cholmod (kDefaultLinearSolver), eigen-ldlt, eigen-llt, cg; petsc in a build with
/// -DCORRLAP_WITH_PETSC=ON (backends/petsc.hpp). An unknown name or key is an
/// InputError listing the valid ones; a key "solver" in `options` naming another backend too.
std::unique_ptr<LinearSolver> make_linear_solver(const std::string& name = kDefaultLinearSolver,
                                                 const Config& options = {});

/// The same from one configuration: the backend named by its key "solver" (default `fallback`),
/// configured with the remaining keys (the form the CLI's --config files use).
std::unique_ptr<LinearSolver> make_linear_solver(const Config& config,
                                                 const std::string& fallback = kDefaultLinearSolver);

/// An eigen solver for L u = lambda M u (docs/math.md §10.5): "shift-invert" (kDefaultEigenSolver,
/// Spectra's shift-invert Lanczos; its linear solver is options' key "solver", default
/// kDefaultLinearSolver) or "dense"; "slepc" with -DCORRLAP_WITH_PETSC=ON. Its solve(L, M, k) returns the k values
/// -lambda >= 0 of smallest magnitude, ascending. Unknown names or keys are InputErrors listing the valid ones.
std::unique_ptr<EigenSolver> make_eigen_solver(const std::string& name = kDefaultEigenSolver,
                                               const Config& options = {});

}  // namespace corrlap
