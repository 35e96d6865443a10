// corrlap solve: pure-Neumann Poisson problem of docs/math.md §10.4 with any discretization and any
// linear solver backend; prints timings, the residual and the error vs the analytic solution.
#include <chrono>
#include <cmath>
#include <corrlap/backends/registry.hpp>
#include <corrlap/core/error.hpp>
#include <corrlap/discretizations/registry.hpp>
#include <corrlap/io/text_io.hpp>
#include <corrlap/problems/problems.hpp>
#include <corrlap/problems/test_functions.hpp>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>

#include "command.hpp"
#include "normal_options.hpp"
#include "operator_options.hpp"
#include "surface_source.hpp"

namespace corrlap::cli {
namespace {

struct SolveArgs {
  SurfaceSource source;
  std::string method = "fem";
  NormalOptions normals;
  std::vector<std::string> params;
  std::string orientation;
  std::string rhs = "x2";
  std::string solver;
  std::string config_file;
  std::vector<std::string> options;
  std::string out;
  bool json = false;
};

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void run(const SolveArgs& a) {
  // Backend configuration first: a bad key fails before the (possibly long) assembly.
  Config config;
  if (!a.config_file.empty()) config = Config::from_json_file(a.config_file);
  config.merge(Config::from_key_values(a.options));
  if (!a.solver.empty()) config.set("solver", a.solver);
  const std::string solver_name = config.get_string("solver", kDefaultLinearSolver);
  auto solver = make_linear_solver(config, kDefaultLinearSolver);

  auto method = make_discretization(a.method);
  Config params = Config::from_key_values(a.params);
  if (!a.orientation.empty()) params.set("orientation", a.orientation);
  const TestFunction* analytic = has_test_function(a.rhs) ? &test_function(a.rhs) : nullptr;

  const auto t0 = std::chrono::steady_clock::now();
  const LoadedSurface surface = a.source.load();
  const SurfelMesh& mesh = surface.mesh;
  // The normals of `corrlap operators` for the same options (docs/math.md §1.5, resolve_normals).
  const NormalFields normals = a.normals.resolve(surface, method->required_normals(), a.method);
  const std::string kind = method->required_normals() == NormalKind::None ? "none" : a.normals.describe(surface);
  const Operators ops = method->assemble(mesh, normals, params);
  for (const auto& w : ops.warnings) std::cerr << "warning: " << w << "\n";
  const BoundaryCondition boundary = boundary_condition(mesh);
  if (!boundary.closed()) std::cerr << "solve: " << boundary.note() << "\n";
  if (ops.domain != Operators::Domain::Vertices)
    throw InputError("corrlap solve: method '" + a.method +
                     "' defines operators on faces; the Poisson problem is set on vertices");
  const double assemble_s = seconds_since(t0);
  const Eigen::Index n = ops.L.rows();

  // Right-hand side b = Delta f at q_v = (x_v - c) / |x_v - c| (docs/math.md §10.1), or from a file.
  const Eigen::Vector3d c(a.source.center[0], a.source.center[1], a.source.center[2]);
  Eigen::VectorXd g;
  double residual = 0.0;
  std::optional<PoissonErrors> err;
  if (analytic) {
    const PoissonResult r =
        explain_solver_failure(ops, [&] { return solve_poisson(ops, mesh.positions, *analytic, *solver, c); });
    g = r.g;
    residual = r.residual;
    // The analytic solution is known on the unit sphere only (docs/math.md §10.2).
    const auto& shape = surface.shape;
    if (shape && std::abs(shape->sphere_radius() - 1.0) < 1e-12) err = r.errors;
  } else {
    if (!std::filesystem::exists(a.rhs)) {
      std::string names;
      for (const auto& t : test_functions()) names += (names.empty() ? "" : ", ") + t.name;
      throw InputError("--rhs '" + a.rhs + "': neither a test function (" + names + ") nor an existing file");
    }
    const Eigen::VectorXd b = read_scalars(a.rhs);
    if (b.size() != n)
      throw InputError("right-hand side file '" + a.rhs + "' has " + std::to_string(b.size()) +
                       " values, the mesh has " + std::to_string(n) + " vertices");
    g = explain_solver_failure(ops, [&] { return solve_neumann_poisson(ops.L, ops.M, b, *solver, 0.0, 0); });
    residual = neumann_residual(ops.L, ops.M, b, g, 0);
  }
  const SolverReport report = solver->info();
  if (!a.out.empty()) write_scalars(a.out, g);

  if (a.json) {
    nlohmann::json j;
    j["solver"] = solver_name;
    j["method"] = a.method;
    j["surface"] = a.source.describe();
    j["normals"] = kind;
    j["rhs"] = a.rhs;
    j["boundary"] = boundary.label();
    j["n"] = n;
    j["assemble_s"] = assemble_s;
    j["analyze_s"] = report.analyze_seconds;
    j["factorize_s"] = report.factorize_seconds;
    j["solve_s"] = report.solve_seconds;
    j["iterations"] = report.iterations;
    j["residual"] = residual;
    j["status"] = to_string(report.status);
    j["error_linf"] = err ? nlohmann::json(err->linf) : nlohmann::json(nullptr);
    j["error_l2"] = err ? nlohmann::json(err->l2) : nlohmann::json(nullptr);
    std::cout << j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) << "\n";
  } else {
    std::cout << "surface     " << a.source.describe() << " (" << n << " vertices)\n"
              << "method      " << a.method << " (normals " << kind << ")\n"
              << "solver      " << solver_name << "\n"
              << "assemble    " << assemble_s << " s\n"
              << "analyze     " << report.analyze_seconds << " s\n"
              << "factorize   " << report.factorize_seconds << " s\n"
              << "solve       " << report.solve_seconds << " s";
    if (report.iterations > 0) std::cout << " (" << report.iterations << " iterations)";
    std::cout << "\nresidual    " << residual << "\n";
    if (err)
      std::cout << "error Linf  " << err->linf << "\nerror L2    " << err->l2 << " (M-weighted, docs/math.md §10.4)\n";
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
      "solve", "Poisson problem L g = M b on a closed surface (docs/math.md §10.4) with any method and backend");
  args->source.add_options(*cmd);
  cmd->add_option("--method", args->method, "discretization (registry name)")->capture_default_str();
  args->normals.add_options(*cmd);
  cmd->add_option("--param", args->params, "method parameter key=value (repeatable)");
  cmd->add_option("--orientation", args->orientation,
                  "normals with u.n <= 0: clamp (default: raise u.n to 0.05) | warn (use as given) | error")
      ->check(CLI::IsMember({"error", "warn", "clamp"}));
  std::string names;
  for (const auto& t : test_functions()) names += (names.empty() ? "" : ", ") + t.name;
  cmd->add_option(
         "--rhs", args->rhs,
         names +
             " (docs/math.md §10.2: b = Laplacian of f at the projected vertices) or a file of one value per vertex")
      ->capture_default_str();
  cmd->add_option("--solver", args->solver,
                  std::string("linear solver backend (see `corrlap backends`; default ") + kDefaultLinearSolver + ")");
  cmd->add_option("--config", args->config_file,
                  "JSON file of backend options, e.g. {\"solver\": \"cg\", \"tolerance\": 1e-10}");
  cmd->add_option("options", args->options, "backend options key=value (override --config)");
  cmd->add_option("--out", args->out, "write the solution g (one value per vertex)");
  cmd->add_flag("--json", args->json, "print one JSON object");
  cmd->callback([args] { run(*args); });
});

}  // namespace
}  // namespace corrlap::cli
