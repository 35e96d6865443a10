// corrlap eigs: the k smallest values of -lambda for L u = lambda M u (docs/math.md §10.5, §12.3).
// Spectra's shift-invert Lanczos with a linear solver backend (--solver, default cholmod) for
// (L - sigma M)^{-1}; the solver itself takes the dense path where that is cheaper (small n).
#include <algorithm>
#include <chrono>
#include <corrlap/backends/parallel.hpp>
#include <corrlap/backends/registry.hpp>
#include <corrlap/core/error.hpp>
#include <corrlap/io/output_folder.hpp>
#include <corrlap/io/text_io.hpp>
#include <corrlap/pipeline/front_end.hpp>
#include <cstdio>
#include <iostream>
#include <optional>

#if defined(CORRLAP_WITH_PETSC)
#include <corrlap/core/stopwatch.hpp>
#include <corrlap/distributed/distributed_eigs.hpp>
#include <corrlap/distributed/distributed_problem.hpp>
#include <variant>
#endif

#include "command.hpp"
#include "front_end_request.hpp"
#include "operator_options.hpp"
#include "solver_options.hpp"

namespace corrlap::cli {
namespace {

struct EigsArgs {
  OperatorOptions options;
  SolverOptions solver;
  int k = 49;
  std::string out;
  OutputOptions output;
};

#if defined(CORRLAP_WITH_PETSC)
// The command in the terms of choose_front_end (pipeline/front_end.hpp), which decides.
FrontEndRequest front_end_request(const EigsArgs& a) {
  return cli::front_end_request(FrontEndRequest::Task::Eigen, a.options.source, a.options.normals, a.options.method,
                                a.solver);
}
#endif

void print_values(const Eigen::VectorXd& values, std::optional<StagedFile>& out, const OutputUnits& units) {
  if (!out) {
    for (Eigen::Index i = 0; i < values.size(); ++i) std::printf("%.17g\n", values[i]);
    return;
  }
  write_scalars(out->path(), values, units.scalar_comments("eigenvalues mu of -L u = mu M u, ascending", 2));
  out->commit();
}

#if defined(CORRLAP_WITH_PETSC)
// False when the distributed front end refused the input (distributed_problem.hpp): its refusals
// are collective, so every rank then takes the serial front end. The eigenvectors stay
// distributed: the command writes only the values.
bool run_distributed(const EigsArgs& a) {
  // The solver's options first: a bad key fails before the assembly, on every rank.
  SlepcEigenSolver solver;
  solver.configure(a.solver.config());
  std::optional<StagedFile> out;  // checked before the computation; rank 0 writes
  if (!a.out.empty() && is_output_rank()) out.emplace(a.out);
  const SurfaceInput input = a.options.source.input();
  std::string refused;
  const auto problem = make_distributed_problem(
      input, a.options.normals.request(std::holds_alternative<ImplicitShapeInput>(input)), refused);
  if (!problem) {
    if (is_output_rank()) std::cerr << "note: " << refused << "; using the serial front end\n";
    return false;
  }
  const DistributedSurface& surface = problem->surface();
  const Stopwatch watch;
  const EigenResult r =
      distributed_eigs(problem->fem(), int(std::min<std::int64_t>(a.k, surface.num_vertices)), solver);
  const double seconds = watch.elapsed();
  if (!r.values.allFinite()) throw NumericalError("eigs: the eigen solver returned a value that is not finite");
  if (!is_output_rank()) return true;
  const OutputUnits units = a.output.parse(problem->frame());
  print_values(units.inverse_areas(r.values), out, units);
  if (r.values.size() < a.k) std::cerr << "eigs: only " << r.values.size() << " eigenvalues exist\n";
  std::cerr << "eigs: " << r.values.size() << " eigenvalues of a " << surface.num_vertices << " x "
            << surface.num_vertices << " problem with " << r.method << " (" << r.iterations
            << " iterations) on the distributed front end over " << surface.ranks << " ranks in " << seconds
            << " s; values in 1/length^2 of " << units.name() << " units\n";
  return true;
}
#endif

void run(const EigsArgs& a) {
  if (a.k <= 0) throw InputError("-k must be positive");
#if defined(CORRLAP_WITH_PETSC)
  if (choose_front_end(front_end_request(a)) == FrontEnd::Distributed && run_distributed(a)) return;
#endif
  std::optional<StagedFile> out;  // checked before the computation; under mpirun rank 0 writes
  if (!a.out.empty() && is_output_rank()) out.emplace(a.out);
  const OperatorOptions::Input in = a.options.prepare();
  // -lambda has the units 1 / length^2: converted from the computation's world units to the output's.
  const OutputUnits units = a.output.parse(in.frame);
  const Operators ops = a.options.assemble(in);
  if (const BoundaryCondition boundary = boundary_condition(in.mesh); !boundary.closed())
    std::cerr << "eigs: " << boundary.note() << "\n";
  const Eigen::Index n = ops.L.rows();
  Config config = a.solver.config();
  if (!config.has("solver")) config.set("solver", kDefaultLinearSolver);
  // --solver names a linear solver for the shift-invert Lanczos, or an eigen solver of its own
  // (slepc), which then takes the options.
  const std::string named = config.get_string("solver", kDefaultLinearSolver);
  const bool own_eigen_solver = !linear_solver_registry().contains(named) && eigen_solver_registry().contains(named);
  auto eig = make_eigen_solver(own_eigen_solver ? named : kDefaultEigenSolver, config);
  // The unknowns' positions order the factorization (LinearSolver::set_positions).
  eig->set_positions(ops.domain == Operators::Domain::Vertices ? in.mesh.positions : in.mesh.face_centroids());
  const auto t0 = std::chrono::steady_clock::now();
  // values are -lambda >= 0, ascending, when L is negative semi-definite
  const EigenResult r = explain_solver_failure(ops, [&] { return eig->solve(ops.L, ops.M, a.k); });
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!r.values.allFinite()) throw NumericalError("eigs: the eigen solver returned a value that is not finite");
  const Eigen::VectorXd values = units.inverse_areas(r.values);
  if (is_output_rank()) print_values(values, out, units);  // rank 0 prints or writes the values
  // A value -lambda < 0 means L u = lambda M u with lambda > 0: L is not negative semi-definite
  // (tolerance: rounding of the dense or shift-invert solve, relative to the largest value).
  const double scale = std::max(1.0, r.values.size() ? r.values.cwiseAbs().maxCoeff() : 0.0);  // world units
  const Eigen::Index wrong_sign = (r.values.array() < -1e-8 * scale).count();
  if (wrong_sign > 0) {
    std::cerr << "warning: eigs: " << wrong_sign << " of the values -lambda are negative (smallest "
              << values.minCoeff() << "): L is not negative semi-definite";
    if (!ops.contract_risk.empty())
      std::cerr << "; likely cause: " << ops.contract_risk << "; remedy: --orientation clamp (the default)";
    std::cerr << "\n";
  }
  if (r.values.size() < a.k) std::cerr << "eigs: only " << r.values.size() << " eigenvalues exist\n";
  std::cerr << "eigs: " << r.values.size() << " eigenvalues of a " << n << " x " << n << " problem with "
            << (r.method == "dense" ? std::string("the dense solver (cheaper at this size)")
                : own_eigen_solver  ? r.method + " (" + std::to_string(r.iterations) + " iterations)"
                                    : eig->name() + " (" + config.get_string("solver", "") + ", " +
                                         std::to_string(r.iterations) + " restarts)")
            << " in " << seconds << " s; values in 1/length^2 of " << units.name() << " units\n";
}

RegisterCommand reg(31, "eigs", [](CLI::App& app) {
  auto args = std::make_shared<EigsArgs>();
  auto* cmd = app.add_subcommand("eigs", "smallest eigenvalues -lambda of L u = lambda M u");
  args->options.add_options(*cmd);
  cmd->add_option("-k", args->k, "number of eigenvalues (default 49)");
  cmd->add_option("--out", args->out, "write one value per line (ascending, %.17g) instead of printing");
  args->output.add_options(*cmd, /*with_space=*/false);
  args->solver.add_options(*cmd, std::string("linear solver for shift-invert Lanczos (cholmod, eigen-ldlt, "
                                             "eigen-llt, cg, petsc; default ") +
                                     kDefaultLinearSolver +
                                     "; small problems take the dense path when it is cheaper), or an eigen solver of "
                                     "its own: slepc (built with PETSc, under mpirun)");
  cmd->callback([args] { run(*args); });
});

}  // namespace
}  // namespace corrlap::cli
