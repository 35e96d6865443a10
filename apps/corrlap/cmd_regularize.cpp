// corrlap regularize: the paper's Laplacian regularization (paper §4.1, docs/math.md §9.2). From a
// staircased digital surface, new vertex positions whose corrected Laplacian matches -2 H n, with
// n the estimated (II) normals and H the corrected mean curvature.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <corrlap/backends/registry.hpp>
#include <corrlap/core/error.hpp>
#include <corrlap/discretizations/registry.hpp>
#include <corrlap/estimators/corrected_curvature.hpp>
#include <corrlap/estimators/implicit_normals.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/regularization/laplacian_regularization.hpp>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>

#include "command.hpp"
#include "normal_options.hpp"
#include "surface_source.hpp"
#include "validators.hpp"

namespace corrlap::cli {
namespace {

struct RegularizeArgs {
  SurfaceSource source;
  std::string method = "fem";
  NormalOptions normals;
  std::vector<std::string> params;
  double curvature_radius = 0.1;
  double alpha0 = 10.0;
  double h_scale = 1.0;
  std::optional<double> h_clamp;
  std::string solver;
  std::vector<std::string> options;
  std::string out;
};

double seconds_since(std::chrono::steady_clock::time_point& t0) {
  const auto now = std::chrono::steady_clock::now();
  const double s = std::chrono::duration<double>(now - t0).count();
  t0 = now;
  return s;
}

// Geometric vertex normals of a surface with these positions (docs/math.md §1.5: normalized sums
// of the face normals from the corners): what a viewer shades with, and what the metrics compare.
Eigen::MatrixX3d geometric_vertex_normals(const SurfelMesh& mesh) {
  return vertex_normals_from_face_normals(mesh.face_normals_from_positions(), mesh.faces, mesh.num_vertices());
}

// Mean angle in degrees between the rows of two unit-vector fields.
double mean_angle_deg(const Eigen::MatrixX3d& a, const Eigen::MatrixX3d& b) {
  double sum = 0.0;
  for (Eigen::Index i = 0; i < a.rows(); ++i) sum += std::acos(std::clamp(a.row(i).dot(b.row(i)), -1.0, 1.0));
  return a.rows() > 0 ? sum / double(a.rows()) * 180.0 / std::numbers::pi : 0.0;
}

// Quality of a surface against the implicit shape it digitizes: mean distance of the vertices,
// mean angle of the geometric vertex normals to the true normals, and mean |H - H_true| of the
// corrected curvature computed on the surface with its own geometric normals.
struct SurfaceQuality {
  double distance_l1 = 0.0, normal_angle_deg = 0.0, mean_curvature_error = 0.0;
};
SurfaceQuality measure(const SurfelMesh& mesh, const ImplicitShape& shape, double radius) {
  SurfaceQuality q;
  q.distance_l1 = distances_to_surface(shape, mesh.positions).mean();
  const Eigen::MatrixX3d n = geometric_vertex_normals(mesh);
  q.normal_angle_deg = mean_angle_deg(n, true_vertex_normals(shape, mesh));
  const Eigen::VectorXd H = CorrectedCurvature::interpolated(mesh, n).at_vertices(radius).H;
  q.mean_curvature_error = (H - true_mean_curvatures(shape, mesh.positions)).cwiseAbs().mean();
  return q;
}

void check_finite(const Eigen::MatrixXd& values, const std::string& what) {
  if (!values.allFinite()) throw NumericalError("regularize: " + what + " has a non-finite value; nothing was written");
}

void run(const RegularizeArgs& a) {
  // The backend first: a bad option fails before the (possibly long) normals and assembly.
  Config config = Config::from_key_values(a.options);
  if (!a.solver.empty()) config.set("solver", a.solver);
  const std::string solver_name = config.get_string("solver", kDefaultLinearSolver);
  auto solver = make_linear_solver(config, kDefaultLinearSolver);
  auto method = make_discretization(a.method);
  const Config params = Config::from_key_values(a.params);

  nlohmann::json stages;
  auto t = std::chrono::steady_clock::now();
  const LoadedSurface surface = a.source.load();
  const SurfelMesh& mesh = surface.mesh;
  const BoundaryCondition boundary = boundary_condition(mesh);
  if (!boundary.closed())
    throw InputError("regularize: the surface is open (" + std::to_string(boundary.boundary_edges) +
                     " boundary edges); the regularization is defined for closed surfaces");
  const double h = mesh.grid_step();
  stages["surface_s"] = seconds_since(t);
  std::cerr << "regularize: " << a.source.describe() << ": " << mesh.num_vertices() << " vertices, " << mesh.num_faces()
            << " faces, h = " << h << "\n";

  // docs/math.md §9.2: vertex normals n (II by default: the normalized sums of the face normals)
  // and the mean curvature H from the corrected curvature measures with the same normals.
  const NormalFields normals = a.normals.resolve(surface, NormalKind::Vertex, "regularize");
  stages["normals_s"] = seconds_since(t);
  Eigen::VectorXd H = CorrectedCurvature::interpolated(mesh, normals.vertex).at_vertices(a.curvature_radius).H;
  check_finite(H, "the mean curvature");
  // Curvature editing (paper §4.3): scale, then clamp to [-MAX, MAX].
  H *= a.h_scale;
  if (a.h_clamp) H = H.cwiseMax(-*a.h_clamp).cwiseMin(*a.h_clamp);
  stages["curvature_s"] = seconds_since(t);

  Operators ops = method->assemble(mesh, normals, params);
  for (const auto& w : ops.warnings) std::cerr << "warning: " << w << "\n";
  if (ops.domain != Operators::Domain::Vertices)
    throw InputError("regularize: method '" + a.method + "' defines operators on faces; positions live on vertices");
  stages["operators_s"] = seconds_since(t);

  const double alpha = regularization_alpha(h, a.alpha0);
  SurfelMesh result = mesh;
  result.positions = regularize_positions(ops.L, ops.M, mesh.positions, normals.vertex, H, alpha, *solver);
  check_finite(result.positions, "the regularized surface");
  stages["solve_s"] = seconds_since(t);

  std::filesystem::create_directories(a.out);
  MeshAttributes input_attr;
  input_attr.vertex_normals = normals.vertex;
  input_attr.vertex_scalars = {{"H", H}};
  write_mesh(a.out + "/input.ply", mesh, input_attr);
  MeshAttributes result_attr;
  result_attr.vertex_normals = geometric_vertex_normals(result);
  result_attr.vertex_scalars = {{"H", H}, {"displacement", (result.positions - mesh.positions).rowwise().norm()}};
  write_mesh(a.out + "/regularized.ply", result, result_attr);
  write_mesh(a.out + "/regularized.obj", result);
  stages["write_s"] = seconds_since(t);

  nlohmann::json m;
  m["surface"] = a.source.describe();
  m["vertices"] = mesh.num_vertices();
  m["faces"] = mesh.num_faces();
  m["h"] = h;
  m["method"] = a.method;
  m["normals"] = a.normals.describe(surface);
  m["curvature_radius"] = a.curvature_radius;
  m["alpha0"] = a.alpha0;
  m["alpha"] = alpha;
  m["h_scale"] = a.h_scale;
  m["h_clamp"] = a.h_clamp ? nlohmann::json(*a.h_clamp) : nlohmann::json(nullptr);
  m["solver"] = solver_name;
  m["time_s"] = stages;
  const RegularizationEnergy before =
      regularization_energy(ops.L, ops.M, mesh.positions, normals.vertex, H, mesh.positions);
  const RegularizationEnergy after =
      regularization_energy(ops.L, ops.M, mesh.positions, normals.vertex, H, result.positions);
  m["energy_initial"] = before.laplacian;  // the attachment term is 0 at the input
  m["energy_final"] = after.laplacian + alpha * after.attachment;
  m["displacement_max"] = (result.positions - mesh.positions).rowwise().norm().maxCoeff();
  if (surface.shape) {
    const SurfaceQuality qb = measure(mesh, *surface.shape, a.curvature_radius);
    const SurfaceQuality qa = measure(result, *surface.shape, a.curvature_radius);
    m["distance_l1_before"] = qb.distance_l1;
    m["distance_l1_after"] = qa.distance_l1;
    m["normal_angle_deg_before"] = qb.normal_angle_deg;
    m["normal_angle_deg_after"] = qa.normal_angle_deg;
    m["mean_curvature_error_before"] = qb.mean_curvature_error;
    m["mean_curvature_error_after"] = qa.mean_curvature_error;
  }
  std::ofstream(a.out + "/metrics.json") << m.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) << "\n";
  std::cerr << "regularize: " << a.method << ", alpha = " << a.alpha0 << " / h^2, " << solver_name
            << ": max displacement " << m["displacement_max"].get<double>();
  if (surface.shape)
    std::cerr << ", mean distance to the surface " << m["distance_l1_before"].get<double>() << " -> "
              << m["distance_l1_after"].get<double>();
  std::cerr << "\n  wrote " << a.out << "/regularized.ply, regularized.obj, input.ply, metrics.json\n";
}

RegisterCommand reg(42, "regularize", [](CLI::App& app) {
  auto args = std::make_shared<RegularizeArgs>();
  auto* cmd = app.add_subcommand(
      "regularize", "smooth a digital surface: (L M^-1 L + alpha M) p' = alpha M p - 2 L (H n) (docs/math.md §9.2)");
  args->source.add_options(*cmd);
  std::string names;
  for (const auto& n : discretization_registry().names()) names += (names.empty() ? "" : ", ") + n;
  cmd->add_option("--method", args->method, "discretization: " + names)->capture_default_str();
  args->normals.source = "ii";  // the paper's normals (alpha = 1/3), for shapes as for volumes
  args->normals.add_options(*cmd);
  cmd->add_option("--param", args->params, "method parameter key=value (repeatable)");
  cmd->add_option("--curvature-radius", args->curvature_radius,
                  "ball radius of the corrected mean curvature H, world units")
      ->check(positive_number())
      ->capture_default_str();
  cmd->add_option("--alpha0", args->alpha0, "attachment weight: alpha = alpha0 / h^2")
      ->check(positive_number())
      ->capture_default_str();
  cmd->add_option("--h-scale", args->h_scale, "curvature editing: H <- S H (paper §4.3)")->capture_default_str();
  cmd->add_option("--h-clamp", args->h_clamp, "curvature editing: clamp H to [-MAX, MAX] (after --h-scale)")
      ->check(positive_number());
  cmd->add_option("--solver", args->solver,
                  std::string("linear solver backend (see `corrlap backends`; default ") + kDefaultLinearSolver + ")");
  cmd->add_option("options", args->options, "backend options key=value");
  cmd->add_option("--out", args->out, "output directory (regularized.ply/.obj, input.ply, metrics.json)")->required();
  cmd->callback([args] { run(*args); });
});

}  // namespace
}  // namespace corrlap::cli
