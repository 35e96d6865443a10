// corrlap solve: pure-Neumann Poisson problem of spec §10.4 with any discretization and any
// linear solver backend; prints timings, the residual and the error vs the analytic solution.
#include <chrono>
#include <cmath>
#include <iostream>
#include <optional>

#include <nlohmann/json.hpp>

#include <corrlap/problems/problems.hpp>
#include <corrlap/backends/registry.hpp>
#include <corrlap/core/error.hpp>
#include <corrlap/core/normal_fields.hpp>
#include <corrlap/discretizations/registry.hpp>
#include <corrlap/estimators/implicit_normals.hpp>
#include <corrlap/io/text_io.hpp>

#include "command.hpp"
#include "surface_source.hpp"

namespace corrlap::cli {
namespace {

struct SolveArgs {
  SurfaceSource source;
  std::string method = "fem";
  std::string normals = "auto";
  std::vector<std::string> params;
  std::string rhs = "x2";
  std::string solver;
  std::string config_file;
  std::vector<std::string> options;
  std::string out;
  bool json = false;
};

/// Test functions of spec §10.2 on the unit sphere: value and Laplace-Beltrami at q (|q| = 1).
struct TestFunction {
  double (*f)(const Eigen::Vector3d&);
  double (*laplacian)(const Eigen::Vector3d&);
};

std::optional<TestFunction> test_function(const std::string& name) {
  if (name == "x2")
    return TestFunction{[](const Eigen::Vector3d& q) { return q.x() * q.x(); },
                        [](const Eigen::Vector3d& q) { return 2.0 - 6.0 * q.x() * q.x(); }};
  if (name == "expx")
    return TestFunction{[](const Eigen::Vector3d& q) { return std::exp(q.x()); },
                        [](const Eigen::Vector3d& q) { return std::exp(q.x()) * (1.0 - 2.0 * q.x() - q.x() * q.x()); }};
  if (name == "p6") {
    // P6(z) = (231 z^6 - 315 z^4 + 105 z^2 - 5) / 16, a degree-6 harmonic: Delta f = -42 f.
    auto p6 = [](const Eigen::Vector3d& q) {
      const double z2 = q.z() * q.z();
      return (((231.0 * z2 - 315.0) * z2 + 105.0) * z2 - 5.0) / 16.0;
    };
    return TestFunction{p6, [](const Eigen::Vector3d& q) {
                          const double z2 = q.z() * q.z();
                          return -42.0 * (((231.0 * z2 - 315.0) * z2 + 105.0) * z2 - 5.0) / 16.0;
                        }};
  }
  return std::nullopt;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void run(const SolveArgs& a) {
  // Backend configuration first: a bad key fails before the (possibly long) assembly.
  Config config;
  if (!a.config_file.empty()) config = Config::from_json_file(a.config_file);
  config.merge(Config::from_key_values(a.options));
  if (!a.solver.empty()) config.set("solver", a.solver);
  const std::string solver_name = config.get_string("solver", "cholmod");
  auto solver = make_linear_solver(config, "cholmod");

  auto method = make_discretization(a.method);
  const Config params = Config::from_key_values(a.params);
  const auto analytic = test_function(a.rhs);

  const auto t0 = std::chrono::steady_clock::now();
  const SurfelMesh mesh = a.source.surface();
  const auto shape = a.source.implicit_shape();

  // Normal fields (spec §1.5): true normals of the implicit shape, or trivial ones.
  std::string kind = a.normals;
  if (kind == "auto") kind = shape ? "true" : "trivial";
  if (kind == "true" && !shape) throw InputError("--normals true needs an implicit shape (--shape or --polynomial)");
  NormalFields normals;
  if (method->required_normals() != NormalKind::None) {
    if (kind == "true") {
      normals.face = true_face_normals(*shape, mesh);
      normals.vertex = true_vertex_normals(*shape, mesh);
    } else {
      normals.face = mesh.face_normals_from_positions();
      normals.vertex = vertex_normals_from_face_normals(normals.face, mesh.faces, mesh.num_vertices());
    }
  }
  const Operators ops = method->assemble(mesh, normals, params);
  for (const auto& w : ops.warnings) std::cerr << "warning: " << w << "\n";
  if (ops.domain != Operators::Domain::Vertices)
    throw InputError("corrlap solve: method '" + a.method + "' defines operators on faces; the Poisson problem is set on vertices");
  const double assemble_s = seconds_since(t0);
  const Eigen::Index n = ops.L.rows();

  // Right-hand side b = Delta f at q_v = (x_v - c) / |x_v - c| (spec §10.1), or from a file.
  const Eigen::Vector3d c(a.source.center[0], a.source.center[1], a.source.center[2]);
  Eigen::VectorXd b(n), f;
  if (analytic) {
    f.resize(n);
    for (Eigen::Index v = 0; v < n; ++v) {
      const Eigen::Vector3d x = mesh.positions.row(v).transpose() - c;
      const Eigen::Vector3d q = x / x.norm();
      f[v] = analytic->f(q);
      b[v] = analytic->laplacian(q);
    }
  } else {
    b = read_scalars(a.rhs);
    if (b.size() != n)
      throw InputError("right-hand side file '" + a.rhs + "' has " + std::to_string(b.size()) + " values, the mesh has " +
                       std::to_string(n) + " vertices");
  }
  // The analytic solution is known on the unit sphere only (spec §10.2).
  const bool known = analytic && shape && std::abs(shape->sphere_radius() - 1.0) < 1e-12;

  const double pin_value = analytic ? f[0] : 0.0;  // spec §10.4: g_0 = f(q_0)
  const Eigen::VectorXd g = solve_neumann_poisson(ops.L, ops.M, b, *solver, pin_value, 0);
  const SolverReport report = solver->info();

  // Residual of the solved system (free rows of L g = M b_compatible), the same for every backend.
  const Eigen::VectorXd bc = b.array() - mass_weighted_mean(ops.M, b);
  const Eigen::VectorXd Mb = ops.M * bc;
  Eigen::VectorXd r = ops.L * g - Mb;
  r[0] = 0.0;
  const double residual = r.norm() / std::max(Mb.norm(), 1e-300);
  std::optional<PoissonErrors> err;
  if (known) err = poisson_errors(ops.M, g, f);
  if (!a.out.empty()) write_scalars(a.out, g);

  if (a.json) {
    nlohmann::json j;
    j["solver"] = solver_name;
    j["method"] = a.method;
    j["surface"] = a.source.describe();
    j["normals"] = kind;
    j["rhs"] = a.rhs;
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
    std::cout << j.dump(2) << "\n";
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
      std::cout << "error Linf  " << err->linf << "\nerror L2    " << err->l2 << " (M-weighted, spec §10.4)\n";
    else
      std::cout << "error       n/a (analytic solution known for x2/expx/p6 on the unit sphere only)\n";
  }
  if (report.status != SolverStatus::Success) std::cerr << "warning: " << report.message << "\n";
}

RegisterCommand reg(40, "solve", [](CLI::App& app) {
  auto args = std::make_shared<SolveArgs>();
  auto* cmd = app.add_subcommand("solve", "Poisson problem L g = M b on a closed surface (spec §10.4) with any method and backend");
  args->source.add_options(*cmd);
  cmd->add_option("--method", args->method, "discretization (registry name)")->capture_default_str();
  cmd->add_option("--normals", args->normals, "normals for corrected methods: true (implicit shapes), trivial, auto")
      ->check(CLI::IsMember({"auto", "true", "trivial"}))
      ->capture_default_str();
  cmd->add_option("--param", args->params, "method parameter key=value (repeatable)");
  cmd->add_option("--rhs", args->rhs,
                  "x2, expx, p6 (spec §10.2: b = Laplacian of f at the projected vertices) or a file of one value per vertex")
      ->capture_default_str();
  cmd->add_option("--solver", args->solver, "linear solver backend (see `corrlap backends`; default cholmod)");
  cmd->add_option("--config", args->config_file, "JSON file of backend options, e.g. {\"solver\": \"cg\", \"tolerance\": 1e-10}");
  cmd->add_option("options", args->options, "backend options key=value (override --config)");
  cmd->add_option("--out", args->out, "write the solution g (one value per vertex)");
  cmd->add_flag("--json", args->json, "print one JSON object");
  cmd->callback([args] { run(*args); });
});

}  // namespace
}  // namespace corrlap::cli
