#include "registry.hpp"

namespace corrlap {

namespace {
void register_builtin_linear_solvers(LinearSolverRegistry& r) {
  (void)r;  // each backend's file pair adds one line here
}
void register_builtin_eigen_solvers(EigenSolverRegistry& r) { (void)r; }
}  // namespace

LinearSolverRegistry& linear_solver_registry() {
  static LinearSolverRegistry registry = [] {
    LinearSolverRegistry r("linear solver");
    register_builtin_linear_solvers(r);
    return r;
  }();
  return registry;
}

EigenSolverRegistry& eigen_solver_registry() {
  static EigenSolverRegistry registry = [] {
    EigenSolverRegistry r("eigen solver");
    register_builtin_eigen_solvers(r);
    return r;
  }();
  return registry;
}

std::unique_ptr<LinearSolver> make_linear_solver(const Config& config, const std::string& fallback) {
  const std::string name = config.get_string("solver", fallback);
  auto solver = linear_solver_registry().create(name);
  solver->configure(config);  // backends accept (and ignore) the key "solver"

  return solver;
}

}  // namespace corrlap
