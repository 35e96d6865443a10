// corrlap solve: factorizes and solves one of the systems the paper uses, with any discretization
// and any linear solver backend; prints timings, the residual and the error vs the analytic solution.
//   --system poisson: the pure-Neumann Poisson problem L g = M b of docs/math.md §10.4 (-L pinned);
//   --system heat:    the diffusion step (M - dt L) X = L u of docs/math.md §10.3, dt = dt-factor * h.
#include <cmath>
#include <corrlap/backends/parallel.hpp>
#include <corrlap/backends/registry.hpp>
#include <corrlap/core/error.hpp>
#include <corrlap/core/stopwatch.hpp>
#include <corrlap/discretizations/registry.hpp>
#include <corrlap/io/output_folder.hpp>
#include <corrlap/io/text_io.hpp>
#include <corrlap/pipeline/front_end.hpp>
#include <corrlap/problems/problems.hpp>
#include <corrlap/problems/test_functions.hpp>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>

#if defined(CORRLAP_WITH_PETSC)
#include <corrlap/backends/petsc.hpp>
#include <corrlap/distributed/collectives.hpp>
#include <corrlap/distributed/distributed_mesh_output.hpp>
#include <corrlap/distributed/distributed_poisson.hpp>
#include <corrlap/distributed/distributed_problem.hpp>
#include <variant>
#endif

#include "command.hpp"
#include "deprecated.hpp"
#include "front_end_request.hpp"
#include "method_options.hpp"
#include "normal_options.hpp"
#include "operator_options.hpp"
#include "solver_options.hpp"
#include "surface_source.hpp"

namespace corrlap::cli {
namespace {

struct SolveArgs {
  SurfaceSource source;
  MethodOptions method;
  NormalOptions normals;
  std::string rhs = "x2";
  SolverOptions solver;
  std::string out;
  OutputOptions output;
  std::string system = "poisson";
  double dt_factor = 0.035;
  bool json = false;
};

#if defined(CORRLAP_WITH_PETSC)
// The command in the terms of choose_front_end (pipeline/front_end.hpp), which decides.
FrontEndRequest front_end_request(const SolveArgs& a) {
  FrontEndRequest r =
      cli::front_end_request(a.system == "heat" ? FrontEndRequest::Task::Heat : FrontEndRequest::Task::Poisson,
                             a.source, a.normals, a.method, a.solver);
  r.rhs_from_test_function = has_test_function(a.rhs);
  return r;
}
#endif

#if defined(CORRLAP_WITH_PETSC)
// False when the distributed front end refused the input (distributed_problem.hpp): its refusals
// are collective, so every rank then takes the serial front end.
bool run_distributed(const SolveArgs& a) {
  // The backend's options first: a bad key fails before the assembly, on every rank.
  PetscLinearSolver solver;
  solver.configure(a.solver.config());
  std::optional<StagedFile> out;  // checked before the computation; rank 0 writes
  if (!a.out.empty() && is_output_rank()) out.emplace(a.out);
  const Stopwatch watch;
  const SurfaceInput input = a.source.input();
  std::string refused;
  const auto problem =
      make_distributed_problem(input, a.normals.request(std::holds_alternative<ImplicitShapeInput>(input)), refused);
  if (!problem) {
    if (is_output_rank()) std::cerr << "note: " << refused << "; using the serial front end\n";
    return false;
  }
  const DistributedSurface& surface = problem->surface();
  const DistributedFem& fem = problem->fem();
  const double assemble_s = watch.elapsed();
  const TestFunction& function = test_function(a.rhs);
  // The serial front end's centre of the projections onto the unit sphere (docs/math.md §10.1).
  const Eigen::Vector3d c(a.source.center[0], a.source.center[1], a.source.center[2]);
  const DistributedPoissonResult r = distributed_solve_poisson(surface, fem, function, solver, c);
  // Every rank writes its vertices' values into rank 0's staged file (no gather).
  if (!a.out.empty()) write_distributed_scalars(text_of_rank0(out ? out->path() : std::string()), surface, r.g);
  if (!is_output_rank()) return true;
  const OutputUnits units = a.output.parse(problem->frame());
  const std::string normals = to_string(problem->normals());
  if (out) out->commit();
  // The analytic solution is known on the unit sphere only (docs/math.md §10.2).
  const bool unit_sphere = problem->shape() && std::abs(problem->shape()->sphere_radius() - 1.0) < 1e-12;
  if (a.json) {
    nlohmann::json j;
    j["solver"] = "petsc";
    j["system"] = a.system;
    j["output_units"] = units.name();
    j["method"] = a.method.method;
    j["surface"] = a.source.describe();
    j["normals"] = normals;
    j["rhs"] = a.rhs;
    j["boundary"] = BoundaryCondition{}.label();  // voxel surfaces inside the box are closed
    j["n"] = surface.num_vertices;
    j["front_end"] = to_string(FrontEnd::Distributed);
    j["ranks"] = surface.ranks;
    j["assemble_s"] = assemble_s;
    j["analyze_s"] = 0.0;
    j["factorize_s"] = r.report.factorize_seconds;
    j["ordering"] = r.report.ordering;
    j["factor_nonzeros"] = 0;
    j["factor_flops"] = 0;
    j["solve_s"] = r.report.solve_seconds;
    j["iterations"] = r.report.iterations;
    j["residual"] = r.residual;
    j["status"] = to_string(r.report.status);
    j["error_linf"] = unit_sphere ? nlohmann::json(r.errors.linf) : nlohmann::json(nullptr);
    j["error_l2"] = unit_sphere ? nlohmann::json(r.errors.l2) : nlohmann::json(nullptr);
    std::cout << j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) << "\n";
    return true;
  }
  std::cout << "surface     " << a.source.describe() << " (" << surface.num_vertices << " vertices)\n"
            << "front end   distributed over " << surface.ranks << " ranks (docs/distributed.md)\n"
            << "system      poisson: L g = M b, vertex 0 pinned\n"
            << "method      fem (normals " << normals << ")\n"
            << "solver      petsc\n"
            << "assemble    " << assemble_s << " s\n"
            << "factorize   " << r.report.factorize_seconds << " s"
            << (r.report.ordering.empty() ? std::string() : " (" + r.report.ordering + ")") << "\n"
            << "solve       " << r.report.solve_seconds << " s";
  if (r.report.iterations > 0) std::cout << " (" << r.report.iterations << " iterations)";
  std::cout << "\nresidual    " << r.residual << "\n";
  if (unit_sphere)
    std::cout << "error Linf  " << r.errors.linf << "\nerror L2    " << r.errors.l2
              << " (M-weighted, docs/math.md §10.4)\n";
  else
    std::cout << "error       n/a (analytic solution known for x2/expx/p6 on the unit sphere only)\n";
  return true;
}
#endif

void run(const SolveArgs& a) {
#if defined(CORRLAP_WITH_PETSC)
  if (choose_front_end(front_end_request(a)) == FrontEnd::Distributed && run_distributed(a)) return;
#endif
  // Backend configuration first: a bad key fails before the (possibly long) assembly.
  const Config config = a.solver.config();
  const std::string solver_name = config.get_string("solver", kDefaultLinearSolver);
  auto solver = make_linear_solver(config, kDefaultLinearSolver);

  auto method = make_discretization(a.method.method);
  const Config params = a.method.config();
  const TestFunction* analytic = has_test_function(a.rhs) ? &test_function(a.rhs) : nullptr;

  std::optional<StagedFile> out;  // checked before the computation; under mpirun rank 0 writes
  if (!a.out.empty() && is_output_rank()) out.emplace(a.out);

  const Stopwatch watch;
  const LoadedSurface surface = a.source.load();
  const SurfelMesh& mesh = surface.mesh;
  // Laplacians (b, X) are in 1 / length^2 of these units; potentials and functions (g, u) have no units.
  const OutputUnits units = a.output.parse(surface);
  // The normals of `corrlap operators` for the same options (docs/math.md §1.5, resolve_normals).
  const NormalFields normals = a.normals.resolve(surface, method->required_normals(), a.method.method);
  const std::string kind = method->required_normals() == NormalKind::None ? "none" : a.normals.describe(surface);
  const Operators ops = method->assemble(mesh, normals, params);
  for (const auto& w : ops.warnings) std::cerr << "warning: " << w << "\n";
  const BoundaryCondition boundary = boundary_condition(mesh);
  if (!boundary.closed()) std::cerr << "solve: " << boundary.note() << "\n";
  if (ops.domain != Operators::Domain::Vertices)
    throw InputError("corrlap solve: method '" + a.method.method +
                     "' defines operators on faces; the Poisson problem is set on vertices");
  const double assemble_s = watch.elapsed();
  const Eigen::Index n = ops.L.rows();

  const Eigen::Vector3d c(a.source.center[0], a.source.center[1], a.source.center[2]);
  // The analytic solution is known on the unit sphere only (docs/math.md §10.2).
  const bool unit_sphere = analytic && surface.shape && std::abs(surface.shape->sphere_radius() - 1.0) < 1e-12;
  // The input u (heat) or b (poisson): the test function's samples, or a file of one value per vertex.
  Eigen::VectorXd from_file;
  if (!analytic) {
    if (!std::filesystem::exists(a.rhs)) {
      std::string names;
      for (const auto& t : test_functions()) names += (names.empty() ? "" : ", ") + t.name;
      throw InputError("--rhs '" + a.rhs + "': neither a test function (" + names + ") nor an existing file");
    }
    from_file = read_scalars(a.rhs);
    if (from_file.size() != n)
      throw InputError("right-hand side file '" + a.rhs + "' has " + std::to_string(from_file.size()) +
                       " values, the mesh has " + std::to_string(n) + " vertices");
    // Poisson's b is a Laplacian in the output units: into the computation's world units.
    if (a.system != "heat") from_file *= units.length_scale() * units.length_scale();
  }
  Eigen::VectorXd g;
  double residual = 0.0, dt = 0.0;
  std::optional<ErrorNorms> err;
  if (a.system == "heat") {
    // docs/math.md §10.3: X = (M - dt L)^{-1} L u approximates the Laplacian of u; dt = 0.035 h is the
    // paper's diffusion time. grid_step() is h for digitized surfaces, the mean edge length otherwise.
    dt = a.dt_factor * mesh.grid_step();
    std::optional<TestFunctionSamples> samples;
    if (analytic) samples = sample_on_unit_sphere(*analytic, mesh.positions, c);
    const Eigen::VectorXd& u = analytic ? samples->f : from_file;
    g = explain_solver_failure(ops, [&] { return forward_laplacian(ops.L, ops.M, u, *solver, dt, &mesh.positions); });
    const Eigen::VectorXd Lu = ops.L * u;
    const Eigen::VectorXd r = ops.M * g - dt * (ops.L * g) - Lu;
    residual = Lu.norm() > 0.0 ? r.norm() / Lu.norm() : r.norm();
    if (unit_sphere) err = error_norms(ops.M, g - samples->laplacian);
  } else if (analytic) {
    // Right-hand side b = Delta f at q_v = (x_v - c) / |x_v - c| (docs/math.md §10.1).
    const PoissonResult r =
        explain_solver_failure(ops, [&] { return solve_poisson(ops, mesh.positions, *analytic, *solver, c); });
    g = r.g;
    residual = r.residual;
    if (unit_sphere) err = r.errors;
  } else {
    g = explain_solver_failure(
        ops, [&] { return solve_neumann_poisson(ops.L, ops.M, from_file, *solver, 0.0, 0, &mesh.positions); });
    residual = neumann_residual(ops.L, ops.M, from_file, g, 0);
  }
  const SolverReport report = solver->info();
  if (out) {
    // heat: X is a Laplacian, in 1 / length^2 of the output units; poisson: g is a potential.
    if (a.system == "heat")
      write_scalars(out->path(), units.inverse_areas(g), units.scalar_comments("X: the heat step's Laplacian", 2));
    else
      write_scalars(out->path(), g);
    out->commit();
  }

  if (a.json) {
    nlohmann::json j;
    j["solver"] = solver_name;
    j["system"] = a.system;
    j["output_units"] = units.name();
    if (a.system == "heat") j["dt"] = dt;
    j["method"] = a.method.method;
    j["surface"] = a.source.describe();
    j["normals"] = kind;
    j["rhs"] = a.rhs;
    j["boundary"] = boundary.label();
    j["n"] = n;
    j["front_end"] = to_string(FrontEnd::Serial);
    j["assemble_s"] = assemble_s;
    j["analyze_s"] = report.analyze_seconds;
    j["factorize_s"] = report.factorize_seconds;
    j["ordering"] = report.ordering;
    j["factor_nonzeros"] = report.factor_nonzeros;
    j["factor_flops"] = report.factor_flops;
    j["solve_s"] = report.solve_seconds;
    j["iterations"] = report.iterations;
    j["residual"] = residual;
    j["status"] = to_string(report.status);
    j["error_linf"] = err ? nlohmann::json(err->linf) : nlohmann::json(nullptr);
    j["error_l2"] = err ? nlohmann::json(err->l2) : nlohmann::json(nullptr);
    std::cout << j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) << "\n";
  } else {
    std::cout << "surface     " << a.source.describe() << " (" << n << " vertices)\n"
              << "system      "
              << (a.system == "heat" ? "heat: (M - dt L) X = L u, dt = " + std::to_string(dt)
                                     : std::string("poisson: L g = M b, vertex 0 pinned"))
              << "\n"
              << "method      " << a.method.method << " (normals " << kind << ")\n"
              << "solver      " << solver_name << "\n"
              << "assemble    " << assemble_s << " s\n"
              << "analyze     " << report.analyze_seconds << " s"
              << (report.ordering.empty() ? std::string() : " (ordering " + report.ordering + ")") << "\n"
              << "factorize   " << report.factorize_seconds << " s\n"
              << "solve       " << report.solve_seconds << " s";
    if (report.iterations > 0) std::cout << " (" << report.iterations << " iterations)";
    std::cout << "\nresidual    " << residual << "\n";
    if (err)
      std::cout << "error Linf  " << err->linf << "\nerror L2    " << err->l2 << " (M-weighted, docs/math.md "
                << (a.system == "heat" ? "§10.3, X vs the exact Laplacian" : "§10.4") << ")\n";
    else
      std::cout << "error       n/a (analytic solution known for x2/expx/p6 on the unit sphere only)\n";
  }
  if (report.status != SolverStatus::Success) {
    std::cerr << "warning: " << report.message;
    if (!ops.contract_risk.empty())
      std::cerr << "; likely cause: " << ops.contract_risk << "; remedy: --orientation clamp (the default)";
    std::cerr << "\n";
  }
}

RegisterCommand reg(40, "solve", [](CLI::App& app) {
  auto args = std::make_shared<SolveArgs>();
  auto* cmd = app.add_subcommand(
      "solve",
      "solve the Poisson problem L g = M b (docs/math.md §10.4) or the diffusion step (M - dt L) X = L u (§10.3) "
      "with any method and backend");
  args->source.add_options(*cmd);
  args->method.add_options(*cmd, /*method_flag=*/true, "fem");
  args->normals.add_options(*cmd);
  std::string names;
  for (const auto& t : test_functions()) names += (names.empty() ? "" : ", ") + t.name;
  cmd->add_option(
         "--rhs", args->rhs,
         names +
             " (docs/math.md §10.2, sampled at the projected vertices; poisson: b = Laplacian of f, heat: u = f) or a "
             "file of one value per vertex (b, in 1/length^2 of --output-units, or u)")
      ->capture_default_str();
  args->solver.add_options(
      *cmd, std::string("linear solver backend (see `corrlap backends`; default ") + kDefaultLinearSolver + ")",
      /*positional_alias=*/true);
  add_deprecated_alias(*cmd, "--config", "--solver-config", args->solver.config_file);
  cmd->add_option("--system", args->system,
                  "poisson: L g = M b with -L pinned (docs/math.md §10.4); heat: (M - dt L) X = L u, the paper's "
                  "diffusion matrix (§10.3), rhs = u")
      ->check(CLI::IsMember({"poisson", "heat"}))
      ->capture_default_str();
  auto* dt_factor = cmd->add_option("--dt-factor", args->dt_factor, "heat: dt = dt-factor * h (h: the grid step)")
                        ->check(CLI::PositiveNumber)
                        ->capture_default_str();
  cmd->add_option("--out", args->out,
                  "write the solution g (poisson) or X (heat, in 1/length^2 of --output-units), one value per vertex");
  args->output.add_options(*cmd, /*with_space=*/false);
  cmd->add_flag("--json", args->json, "print one JSON object");
  cmd->callback([args, dt_factor] {
    if (dt_factor->count() > 0 && args->system != "heat")
      throw InputError("--dt-factor applies to --system heat only (the Poisson system has no time step)");
    run(*args);
  });
});

}  // namespace
}  // namespace corrlap::cli
