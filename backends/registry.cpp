#include "registry.hpp"

#include "cholmod.hpp"
#include "eigen_direct.hpp"
#include "iterative.hpp"
#include "spectra_eigs.hpp"
#if defined(CORRLAP_WITH_PETSC)
#include "petsc.hpp"
#endif

namespace corrlap {

namespace {
void register_builtin_linear_solvers(LinearSolverRegistry& r) {
  r.add("eigen-ldlt", "Eigen SimplicialLDLT (sparse LDL^T, AMD ordering)",
        [] { return std::make_unique<EigenDirectSolver>(EigenDirectSolver::Kind::LDLT); });
  r.add("eigen-llt", "Eigen SimplicialLLT (sparse Cholesky LL^T, AMD ordering)",
        [] { return std::make_unique<EigenDirectSolver>(EigenDirectSolver::Kind::LLT); });
  r.add("cholmod", "SuiteSparse CHOLMOD (supernodal/simplicial Cholesky, AMD/METIS/NESDIS, reusable analysis)",
        [] { return std::make_unique<CholmodSolver>(); });
  r.add("cg", "preconditioned conjugate gradient (none/jacobi/ichol)",
        [] { return std::make_unique<ConjugateGradientSolver>(); });
#if defined(CORRLAP_WITH_PETSC)
  r.add("petsc", "PETSc KSP under MPI (MUMPS Cholesky, CG + GAMG/hypre, ...; MPIAIJ assembled through COO)",
        [] { return std::make_unique<PetscLinearSolver>(); });
#endif
}
void register_builtin_eigen_solvers(EigenSolverRegistry& r) {
  r.add("shift-invert", "Spectra SymGEigsShiftSolver, shift-invert with any linear solver; dense below dense_threshold",
        [] { return std::make_unique<ShiftInvertEigenSolver>(); });
  r.add("dense", "Eigen GeneralizedSelfAdjointEigenSolver on dense matrices (small problems)",
        [] { return std::make_unique<DenseEigenSolver>(); });
#if defined(CORRLAP_WITH_PETSC)
  r.add("slepc", "SLEPc EPS under MPI (GHEP, shift-invert with MUMPS, or LOBPCG + GAMG/hypre)",
        [] { return std::make_unique<SlepcEigenSolver>(); });
#endif
}
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
  auto solver = linear_solver_registry().create(config.get_string("solver", fallback));
  solver->configure(config);  // backends accept (and ignore) the key "solver"
  return solver;
}

std::unique_ptr<LinearSolver> make_linear_solver(const std::string& name, const Config& options) {
  auto solver = linear_solver_registry().create(name);
  const std::string named = options.get_string("solver", name);
  if (named != name)
    throw InputError("make_linear_solver: name '" + name + "' but option solver='" + named + "'; give one of them");
  solver->configure(options);
  return solver;
}

std::unique_ptr<EigenSolver> make_eigen_solver(const std::string& name, const Config& options) {
  auto solver = eigen_solver_registry().create(name);
  solver->configure(options);
  return solver;
}

}  // namespace corrlap
