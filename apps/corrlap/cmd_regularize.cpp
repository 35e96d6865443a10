// corrlap regularize: the paper's Laplacian regularization (paper §4.1, docs/math.md §9.2). From a
// staircased digital surface, new vertex positions whose corrected Laplacian matches -2 H n, with
// n the estimated (II) normals and H the corrected mean curvature.
#include <cmath>
#include <corrlap/backends/parallel.hpp>
#include <corrlap/backends/registry.hpp>
#include <corrlap/core/error.hpp>
#include <corrlap/core/mesh_topology.hpp>
#include <corrlap/core/stopwatch.hpp>
#include <corrlap/discretizations/registry.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/io/output_folder.hpp>
#include <corrlap/io/volume_io.hpp>
#include <corrlap/pipeline/front_end.hpp>
#include <corrlap/pipeline/surface_defaults.hpp>
#include <corrlap/regularization/alignment_regularization.hpp>
#include <corrlap/regularization/regularize_surface.hpp>
#include <corrlap/regularization/surface_quality.hpp>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#if defined(CORRLAP_WITH_PETSC)
#include <corrlap/backends/petsc.hpp>
#include <corrlap/distributed/collectives.hpp>
#include <corrlap/distributed/distributed_halo.hpp>
#include <corrlap/distributed/distributed_mesh_output.hpp>
#include <corrlap/distributed/distributed_problem.hpp>
#include <corrlap/distributed/distributed_quality.hpp>
#include <corrlap/distributed/distributed_regularize_surface.hpp>
#include <corrlap/distributed/distributed_render.hpp>
#include <corrlap/render/image.hpp>
#include <corrlap/render/render_mesh.hpp>
#include <variant>
#endif

#include "command.hpp"
#include "front_end_request.hpp"
#include "library_errors.hpp"
#include "method_options.hpp"
#include "normal_options.hpp"
#include "render_output.hpp"
#include "solver_options.hpp"
#include "surface_source.hpp"
#include "validators.hpp"

namespace corrlap::cli {
namespace {

// Surfaces from this many vertices take seconds per stage: regularize then prints a line before
// the curvature and each solve (RegularizationOptions::report_stage).
constexpr Eigen::Index kStageReportVertices = 100000;

struct RegularizeArgs {
  SurfaceSource source;
  MethodOptions method;
  NormalOptions normals;
  std::optional<double> size, curvature_radius;
  double curvature_spacing = kCurvatureSiteSpacing;
  std::string alpha0 = RegularizationOptions{}.alpha0_auto ? "auto" : number_text(RegularizationOptions{}.alpha0);
  double h_scale = 1.0;
  std::optional<double> h_clamp;
  std::string k1_edit, k2_edit;  // principal-curvature edits (paper §4.3), parsed by PrincipalCurvatureEdit
  double normal_attachment = 1.0;
  double solve_accuracy = kRegularizationSolveAccuracy;
  SolverOptions solver;
  std::string out;
  OutputOptions output;
  std::string baseline;  // "alignment": docs/math.md §9.1 instead of §9.2
  bool clamp = false;
  bool allow_nonmanifold = false;  // accepted and ignored (kAllowNonmanifoldNote)
  bool no_render = false;          // before.png / after.png are drawn unless --no-render
  bool no_view = false;            // view.html is written unless --no-view
  // Options of the paper's regularization only: given with --baseline they would be ignored.
  std::vector<CLI::Option*> laplacian_only;
  CLI::Option* clamp_option = nullptr;
};

// The geometry part of metrics.json, the same for both regularizations and both front ends: the
// largest move, the areas and, for implicit shapes, the quality before and after
// (docs/regularization.md). Lengths in the computation's world units.
struct GeometryMetrics {
  int components = 0;
  double displacement_max = 0.0, area_before = 0.0, area_after = 0.0;
  std::optional<SurfaceQuality> before, after;  // against the implicit shape
};

GeometryMetrics geometry_metrics(const LoadedSurface& surface, const SurfelMesh& result, double curvature_radius) {
  const SurfelMesh& mesh = surface.mesh;
  GeometryMetrics g;
  g.components = surface.components;
  g.displacement_max = (result.positions - mesh.positions).rowwise().norm().maxCoeff();
  g.area_before = surface_area(mesh);
  g.area_after = surface_area(result);
  if (surface.shape) {
    g.before = measure_against_shape(mesh, *surface.shape, curvature_radius);
    g.after = measure_against_shape(result, *surface.shape, curvature_radius);
  }
  return g;
}

// The displacement and areas describe the meshes written: in their units; the quality is measured
// in the computation's world units against the shape.
void add_geometry_metrics(nlohmann::json& m, const GeometryMetrics& g, const OutputUnits& units) {
  const double scale = units.length_scale();
  m["components"] = g.components;
  m["displacement_max"] = g.displacement_max * scale;
  m["area_before"] = g.area_before * scale * scale;
  m["area_after"] = g.area_after * scale * scale;
  if (!g.before || !g.after) return;
  m["distance_l1_before"] = g.before->distance_l1;
  m["distance_l1_after"] = g.after->distance_l1;
  m["normal_angle_deg_before"] = g.before->normal_angle_deg;
  m["normal_angle_deg_after"] = g.after->normal_angle_deg;
  m["mean_curvature_error_before"] = g.before->mean_curvature_error;
  m["mean_curvature_error_after"] = g.after->mean_curvature_error;
}

// DIR/input.ply, regularized.ply (its geometric normals, the displacement and `scalars`),
// regularized.obj; the input's own attributes in `input_attr`.
// The meshes in the chosen units; `curvatures` (H) and the displacement scale with them.
void write_surfaces(const std::string& dir, const SurfelMesh& input, MeshAttributes input_attr,
                    const SurfelMesh& result, std::map<std::string, Eigen::VectorXd> curvatures,
                    const OutputUnits& units) {
  for (auto& [name, v] : input_attr.vertex_scalars) v = units.curvatures(v);
  if (input_attr.vertex_normals.rows() > 0) input_attr.vertex_normals = units.normals(input_attr.vertex_normals);
  if (input_attr.face_normals.rows() > 0) input_attr.face_normals = units.normals(input_attr.face_normals);
  input_attr.comments = units.comments();
  write_mesh(dir + "/input.ply", units.mesh(input), input_attr);
  MeshAttributes result_attr;
  result_attr.comments = units.comments();
  for (auto& [name, v] : curvatures) v = units.curvatures(v);
  curvatures["displacement"] = units.lengths((result.positions - input.positions).rowwise().norm());
  result_attr.vertex_scalars = std::move(curvatures);
  const SurfelMesh out = units.mesh(result);
  result_attr.vertex_normals = geometric_vertex_normals(out);
  write_mesh(dir + "/regularized.ply", out, result_attr);
  MeshAttributes obj_attr;  // OBJ writes the comments only
  obj_attr.comments = units.comments();
  write_mesh(dir + "/regularized.obj", out, obj_attr);
}

// The space of the coordinates written ("RAS", "LPS", "unknown"); null for world and voxel units.
nlohmann::json output_space_json(const OutputUnits& units) {
  const std::string space = units.space_name();
  return space.empty() ? nlohmann::json(nullptr) : nlohmann::json(space);
}

void write_metrics(const std::string& dir, const nlohmann::json& m) {
  std::ofstream(dir + "/metrics.json") << m.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) << "\n";
}

// DIR/view.html: the staircase and the result as written (input.ply, regularized.ply), H in the
// range of the pictures (H after). Returns the seconds spent.
double write_regularization_view(const std::string& dir, const std::string& description) {
  Stopwatch t;
  if (!can_write_view(dir + "/view.html")) return 0.0;
  const std::vector<ViewSurface> surfaces{read_view_surface(dir + "/input.ply", "staircase"),
                                          read_view_surface(dir + "/regularized.ply", "regularized")};
  ViewOptions o;
  o.title = "regularize: " + description;
  for (const ScalarField& f : surfaces[1].fields)
    if (f.name == "H" && f.values.allFinite()) o.scales["H"] = colour_scale(f, RenderOptions{});
  write_view_beside(dir + "/view.html", surfaces, o);
  return t.lap();
}

// docs/math.md §9.1: the reference's alignment regularization (the paper's baseline [17]) with the
// face normals of --normals (the reference's test uses --normals convolved).
void run_alignment_baseline(const RegularizeArgs& a, const LoadedSurface& surface, const std::string& dir,
                            const std::string& shown, const std::string& description, nlohmann::json& stages,
                            Stopwatch& t) {
  const SurfelMesh& mesh = surface.mesh;
  const NormalFields normals = a.normals.resolve(surface, NormalKind::Face, "regularize --baseline alignment");
  stages["normals_s"] = t.lap();
  AlignmentParams params;
  params.clamp = a.clamp;
  const bool direct = a.baseline == "alignment-direct";
  if (direct && a.clamp)
    throw InputError("--clamp applies to --baseline alignment (the descent), not alignment-direct");
  const Config solver_config = a.solver.config();
  auto solver = make_linear_solver(solver_config, kDefaultLinearSolver);
  const AlignmentResult r = direct ? alignment_minimizer(mesh, normals.face, *solver, params)
                                   : alignment_regularization(mesh, normals.face, params);
  stages["solve_s"] = t.lap();
  if (!is_output_rank()) return;  // under mpirun rank 0 writes (every rank computed the same result)
  SurfelMesh result = mesh;
  result.positions = r.positions;
  MeshAttributes input_attr;
  input_attr.face_normals = normals.face;
  const OutputUnits units = a.output.parse(surface);
  write_surfaces(dir, mesh, input_attr, result, {}, units);
  stages["write_s"] = t.lap();
  if (!a.no_render) stages["render_s"] = render_before_after(dir, mesh, result, "", {}, {});
  if (!a.no_view) stages["view_s"] = write_regularization_view(dir, description);
  t.restart();
  nlohmann::json m;
  m["surface"] = description;
  m["output_units"] = units.name();
  m["output_space"] = output_space_json(units);
  m["vertices"] = mesh.num_vertices();
  m["faces"] = mesh.num_faces();
  m["h"] = mesh.grid_step();
  m["method"] = a.baseline;
  m["normals"] = a.normals.describe(surface);
  m["alpha"] = params.alpha;
  m["beta"] = params.beta;
  m["gamma"] = params.gamma;
  m["clamp"] = params.clamp;
  m["iterations"] = r.iterations;
  m["energy_initial"] = r.energy_initial;
  m["energy_final"] = r.energy_final;
  m["time_s"] = stages;
  // Measured with the default curvature radius of the paper's regularization.
  add_geometry_metrics(m, geometry_metrics(surface, result, default_curvature_radius(surface)), units);
  write_metrics(dir, m);
  std::cerr << "regularize --baseline " << a.baseline << ": energy " << r.energy_initial << " -> " << r.energy_final
            << " in " << r.iterations << " iterations\n  wrote " << shown
            << "/regularized.ply, regularized.obj, input.ply, metrics.json"
            << (a.no_render ? "" : ", before.png, after.png") << (a.no_view ? "" : ", view.html") << "\n";
}

void write_regularization(const RegularizeArgs& a, const RegularizationOptions& o, const LoadedSurface& surface,
                          const Eigen::MatrixX3d& input_normals, const RegularizedSurface& r,
                          const std::string& description, const std::string& dir, const std::string& shown,
                          nlohmann::json& stages, Stopwatch& t);

// One surface regularized into `dir` (`shown`: the folder as the user names it).
void regularize_one(const RegularizeArgs& a, RegularizationOptions o, const LoadedSurface& surface,
                    const std::string& description, const std::string& dir, const std::string& shown, Stopwatch& t) {
  nlohmann::json stages;
  const SurfelMesh& mesh = surface.mesh;
  check_regularizable(mesh, "regularize");
  if (a.baseline.empty()) check_regularization_options(mesh, o);
  stages["surface_s"] = t.lap();
  if (is_output_rank())
    std::cerr << "regularize: " << description << ": " << mesh.num_vertices() << " vertices, " << mesh.num_faces()
              << " faces, " << surface.components << " component" << (surface.components == 1 ? "" : "s")
              << ", h = " << mesh.grid_step() << "\n";
  if (!a.baseline.empty()) {
    run_alignment_baseline(a, surface, dir, shown, description, stages, t);
    return;
  }
  // docs/math.md §9.2: vertex normals n (II by default: normalized sums of the face normals).
  const NormalFields normals = a.normals.resolve(surface, NormalKind::Vertex, "regularize");
  stages["normals_s"] = t.lap();
  // Long runs say what they are doing (the curvature and each solve take seconds to minutes).
  if (mesh.num_vertices() >= kStageReportVertices && is_output_rank())
    o.report_stage = [](const std::string& stage) { std::cerr << "regularize: " << stage << "\n"; };
  const RegularizedSurface r = regularize_surface(surface, normals, o);
  for (const auto& w : r.warnings) std::cerr << "warning: " << w << "\n";
  stages["curvature_s"] = r.curvature_seconds;
  stages["operators_s"] = r.operators_seconds;
  stages["solve_s"] = r.solve_seconds;
  t.restart();
  if (!is_output_rank()) return;  // under mpirun rank 0 writes (every rank computed the same result)
  write_regularization(a, o, surface, normals.vertex, r, description, dir, shown, stages, t);
}

// metrics.json of the paper's regularization but its geometry part, the same for both front ends.
nlohmann::json regularization_metrics(const RegularizeArgs& a, const RegularizationOptions& o,
                                      const RegularizedSurface& r, std::int64_t vertices, std::int64_t faces,
                                      const std::string& description, const std::string& normals,
                                      const OutputUnits& units, FrontEnd front_end, const nlohmann::json& stages) {
  nlohmann::json m;
  m["surface"] = description;
  m["front_end"] = to_string(front_end);
  m["vertices"] = vertices;
  m["faces"] = faces;
  m["h"] = r.h;
  m["method"] = a.method.method;
  m["normals"] = normals;
  m["size"] = r.size;
  m["curvature_radius"] = r.curvature_radius;
  m["alpha0"] = r.alpha0;
  m["alpha"] = r.alpha;
  if (o.alpha0_auto) {
    nlohmann::json trials = nlohmann::json::array();
    for (const Alpha0Trial& t : r.alpha0_trials) {
      trials.push_back({{"alpha0", t.alpha0}, {"bias", t.bias}});
      if (t.estimated) trials.back()["estimated"] = true;
    }
    m["alpha0_auto"] = {{"bias_limit", kAttachmentBiasLimit}, {"trials", trials}};
  }
  m["h_scale"] = a.h_scale;
  m["h_clamp"] = a.h_clamp ? nlohmann::json(*a.h_clamp) : nlohmann::json(nullptr);
  m["output_units"] = units.name();
  m["output_space"] = output_space_json(units);
  m["k1_edit"] = o.k1_edit.describe();
  m["k2_edit"] = o.k2_edit.describe();
  if (o.k1_edit.active() || o.k2_edit.active()) {
    m["normal_attachment"] = o.normal_attachment;
    m["normal_angle_change_deg"] = r.normal_angle_change_deg;
  }
  m["solver"] = r.solver;
  m["solve_scheme"] = r.solve_scheme;
  if (r.solve_scheme == "preconditioned-cg") {
    m["solve_iterations"] = r.solve_iterations;
    m["solve_accuracy"] = o.solve_accuracy;
    m["solve_error_bound"] = r.solve_error_bound;
  }
  if (r.factor_nonzeros > 0.0) {
    m["solve_factorize_s"] = r.factorize_seconds;
    m["factor_nonzeros"] = r.factor_nonzeros;
    m["factor_flops"] = r.factor_flops;
  }
  m["solve_residual"] = r.solve_residual;
  m["area_ratio"] = r.check.area_ratio;
  m["extent_ratio"] = r.check.extent_ratio;
  m["time_s"] = stages;
  m["energy_initial"] = r.energy_before.laplacian;  // the attachment term is 0 at the input
  m["energy_final"] = r.energy_after.laplacian + r.alpha * r.energy_after.attachment;
  return m;
}

// The summary on stderr, the same for both front ends.
void report_regularization(const RegularizeArgs& a, const RegularizedSurface& r, const nlohmann::json& m,
                           const std::string& shown) {
  std::cerr << "regularize: " << a.method.method << ", alpha = " << r.alpha0 << " / (h size)^2 = " << r.alpha << ", "
            << r.solver << ": max displacement " << m["displacement_max"].get<double>();
  if (m.contains("distance_l1_before"))
    std::cerr << ", mean distance to the surface " << m["distance_l1_before"].get<double>() << " -> "
              << m["distance_l1_after"].get<double>();
  std::cerr << "\n  wrote " << shown << "/regularized.ply, regularized.obj, input.ply, metrics.json"
            << (a.no_render ? "" : ", before.png, after.png") << (a.no_view ? "" : ", view.html") << "\n";
}

// The outputs of the paper's regularization in `dir`: the surfaces, pictures and metrics.json.
void write_regularization(const RegularizeArgs& a, const RegularizationOptions& o, const LoadedSurface& surface,
                          const Eigen::MatrixX3d& input_normals, const RegularizedSurface& r,
                          const std::string& description, const std::string& dir, const std::string& shown,
                          nlohmann::json& stages, Stopwatch& t) {
  const SurfelMesh& mesh = surface.mesh;
  MeshAttributes input_attr;
  input_attr.vertex_normals = input_normals;
  input_attr.vertex_scalars = {{"H", r.H}};
  const OutputUnits units = a.output.parse(surface);
  write_surfaces(dir, mesh, input_attr, r.mesh, {{"H", r.H}}, units);
  stages["write_s"] = t.lap();
  if (!a.no_render) stages["render_s"] = render_before_after(dir, mesh, r.mesh, "H", r.H, r.H);
  if (!a.no_view) stages["view_s"] = write_regularization_view(dir, description);
  t.restart();
  nlohmann::json m = regularization_metrics(a, o, r, mesh.num_vertices(), mesh.num_faces(), description,
                                            a.normals.describe(surface), units, FrontEnd::Serial, stages);
  add_geometry_metrics(m, geometry_metrics(surface, r.mesh, r.curvature_radius), units);
  write_metrics(dir, m);
  report_regularization(a, r, m, shown);
}

// "3" for an integer label, else its shortest exact decimal.
std::string label_name(double label) {
  if (label == std::floor(label) && std::abs(label) < 1e15) return std::to_string(std::int64_t(label));
  std::ostringstream os;
  os.precision(17);
  os << label;
  return os.str();
}

#if defined(CORRLAP_WITH_PETSC)
// The command in the terms of choose_front_end (pipeline/front_end.hpp), which decides.
FrontEndRequest front_end_request(const RegularizeArgs& a, const RegularizationOptions& o) {
  FrontEndRequest r =
      cli::front_end_request(FrontEndRequest::Task::Regularize, a.source, a.normals, a.method, a.solver);
  r.serial_only_regularization = !a.baseline.empty() || a.source.all_labels() || o.k1_edit.active() ||
                                 o.k2_edit.active() || (!o.alpha0_auto && o.alpha0 == 0.0);
  return r;
}

// Positions in the output units (faces keep the caller's orientation: OutputUnits::mirrors).
Eigen::MatrixX3d positions_in(const OutputUnits& units, const Eigen::MatrixX3d& positions, double h) {
  SurfelMesh m;
  m.positions = positions;
  m.h = h;
  return units.mesh(m).positions;
}

// False when the distributed front end refused the input (distributed_problem.hpp): its refusals
// are collective, so every rank then takes the serial front end. The ranks regularize their
// slabs and write the outputs together: each its own vertices and faces of the meshes and samples
// of the pictures, and the measures summed over the ranks; no rank gathers the surface
// (docs/distributed.md, "Writing the outputs").
bool run_distributed(const RegularizeArgs& a, const RegularizationOptions& o) {
  PetscLinearSolver solver;
  solver.configure(a.solver.config());  // a bad option fails before the surface, on every rank
  Stopwatch t;
  std::optional<OutputFolder> out;
  if (is_output_rank()) out.emplace(a.out);
  const SurfaceInput input = a.source.input();
  const bool shape = std::holds_alternative<ImplicitShapeInput>(input);
  std::string refused;
  const auto problem = make_distributed_problem(input, a.normals.request(shape), refused);
  if (!problem) {
    if (is_output_rank()) std::cerr << "note: " << refused << "; using the serial front end\n";
    return false;
  }
  const DistributedSurface& s = problem->surface();
  nlohmann::json stages;
  stages["surface_s"] = t.lap();  // with the normals and the operators
  if (is_output_rank())
    std::cerr << "regularize: " << a.source.describe() << ": " << s.num_vertices << " vertices, " << s.num_faces
              << " faces, h = " << s.mesh.h << ", distributed over " << s.ranks << " ranks\n";
  const DistributedRegularizedSurface d = distributed_regularize_surface(*problem, o, !shape, solver);
  stages["curvature_s"] = d.curvature_seconds;
  stages["solve_s"] = d.solve_seconds;
  t.restart();

  const Eigen::MatrixX3d before = s.mesh.positions.topRows(s.num_owned);
  RegularizedSurface r;  // what metrics.json reports (no mesh: the ranks hold it)
  r.h = s.mesh.h;
  r.size = d.size;
  r.curvature_radius = d.curvature_radius;
  r.alpha0 = d.alpha0;
  r.alpha = d.alpha;
  r.alpha0_trials = d.alpha0_trials;
  r.solver = "petsc";
  r.solve_scheme = "preconditioned-cg";
  r.solve_iterations = d.solve_iterations;
  r.solve_error_bound = d.solve_error_bound;
  r.solve_residual = d.solve_residual;
  r.curvature_seconds = d.curvature_seconds;
  r.solve_seconds = d.solve_seconds;
  r.energy_before = d.energy_before;
  r.energy_after = d.energy_after;
  // As regularize_surface: a solve stopped at a proven accuracy is checked without its residual.
  r.check = distributed_check_solution(s, before, d.positions,
                                       o.solve_accuracy > 0.0 ? std::nullopt : std::optional<double>(d.solve_residual),
                                       "regularization (fem)");

  // The surfaces, every rank writing its part into rank 0's folder.
  const std::string dir = text_of_rank0(out ? out->path() : std::string());
  const OutputUnits units = a.output.parse(problem->frame());
  const bool mirrors = units.mirrors();
  MeshAttributes input_attr;
  input_attr.vertex_normals = units.normals(problem->vertex_normals());
  input_attr.vertex_scalars = {{"H", units.curvatures(d.H)}};
  input_attr.comments = units.comments();
  write_distributed_mesh(dir + "/input.ply", s, positions_in(units, before, r.h), input_attr, mirrors);
  const Eigen::MatrixX3d after = positions_in(units, d.positions, r.h);
  MeshAttributes result_attr;
  result_attr.comments = units.comments();
  result_attr.vertex_scalars = {{"H", units.curvatures(d.H)},
                                {"displacement", units.lengths((d.positions - before).rowwise().norm())}};
  // The normals of the faces as written: reversed faces turn them.
  result_attr.vertex_normals = distributed_geometric_vertex_normals(s, after) * (mirrors ? -1.0 : 1.0);
  write_distributed_mesh(dir + "/regularized.ply", s, after, result_attr, mirrors);
  MeshAttributes obj_attr;  // OBJ writes the comments only
  obj_attr.comments = units.comments();
  write_distributed_mesh(dir + "/regularized.obj", s, after, obj_attr, mirrors);
  stages["write_s"] = t.lap();
  if (!a.no_render) {
    // As render_before_after: both pictures in the range of H after.
    const RenderOptions options;
    const ColourScale scale = colour_scale(distributed_field_percentiles(s, "H", d.H), options);
    const Image picture_before = distributed_render(s, before, "H", d.H, scale, options);
    const Image picture_after = distributed_render(s, d.positions, "H", d.H, scale, options);
    if (is_output_rank()) {
      write_png(dir + "/before.png", picture_before);
      write_png(dir + "/after.png", picture_after);
    }
    stages["render_s"] = t.lap();
  }
  t.restart();

  GeometryMetrics g;
  g.components = distributed_components(s);
  double displacement = s.num_owned > 0 ? (d.positions - before).rowwise().norm().maxCoeff() : 0.0;
  displacement = max_over_ranks(displacement);
  g.displacement_max = displacement;
  g.area_before = distributed_surface_area(s, before);
  g.area_after = distributed_surface_area(s, d.positions);
  if (const ImplicitShape* shape_of = problem->shape()) {
    const DistributedHalo halo =
        distributed_halo(problem->source(), s, quality_halo_columns(r.curvature_radius, displacement, r.h));
    g.before = distributed_measure_against_shape(s, halo, before, 0.0, *shape_of, r.curvature_radius);
    g.after = distributed_measure_against_shape(s, halo, d.positions, displacement, *shape_of, r.curvature_radius);
  }
  nlohmann::json m = regularization_metrics(a, o, r, s.num_vertices, s.num_faces, a.source.describe(),
                                            to_string(problem->normals()), units, FrontEnd::Distributed, stages);
  add_geometry_metrics(m, g, units);
  if (!is_output_rank()) return true;
  write_metrics(dir, m);
  // The page holds the whole surface in one process, which the ranks never gather.
  RegularizeArgs reported = a;
  reported.no_view = true;
  report_regularization(reported, r, m, a.out);
  if (!a.no_view)
    std::cerr << "note: view.html is not written under mpirun (it would hold the whole surface in one process); "
                 "write it with: corrlap view "
              << a.out << "/input.ply " << a.out << "/regularized.ply --out " << a.out << "/view.html\n";
  out->commit();
  return true;
}
#endif

void run(const RegularizeArgs& a) {
  if (!a.baseline.empty())
    for (const CLI::Option* opt : a.laplacian_only)
      if (opt->count() > 0)
        throw InputError(opt->get_name() + " applies to the paper's regularization, not to --baseline " + a.baseline);
  if (!a.baseline.empty() && a.method.any_given())
    throw InputError("--method and its parameters apply to the paper's regularization, not to --baseline " +
                     a.baseline);
  if (a.baseline.empty() && a.clamp_option->count() > 0) throw InputError("--clamp applies to --baseline alignment");
  RegularizationOptions o;
  o.method = a.method.method;
  o.method_params = a.method.config();
  o.size = a.size;
  o.curvature_radius = a.curvature_radius;
  o.curvature_spacing = a.curvature_spacing;
  o.alpha0_auto = a.alpha0 == "auto";
  o.alpha0 = o.alpha0_auto ? RegularizationOptions{}.alpha0 : std::stod(a.alpha0);  // checked by the option
  o.h_scale = a.h_scale;
  o.h_clamp = a.h_clamp;
  if (!a.k1_edit.empty()) o.k1_edit = PrincipalCurvatureEdit::parse(a.k1_edit);
  if (!a.k2_edit.empty()) o.k2_edit = PrincipalCurvatureEdit::parse(a.k2_edit);
  o.normal_attachment = a.normal_attachment;
  o.solver = a.solver.config();
  o.solve_accuracy = a.solve_accuracy;
  // The options first: a bad name or value fails before the (possibly long) normals.
  check_regularization_options(o);

  // Checked before the (possibly long) computation; written whole at the end or not at all. Under
  // mpirun only rank 0 writes: the other ranks compute alongside (the PETSc backends solve together).
#if defined(CORRLAP_WITH_PETSC)
  if (choose_front_end(front_end_request(a, o)) == FrontEnd::Distributed && run_distributed(a, o)) return;
#endif
  std::optional<OutputFolder> out;
  if (is_output_rank()) out.emplace(a.out);
  const auto folder = [&](const std::string& name) { return out ? out->file(name) : std::string(); };
  if (!a.source.all_labels()) {
    Stopwatch t;
    const LoadedSurface surface = a.source.load();
    regularize_one(a, o, surface, a.source.describe(), out ? out->path() : std::string(), a.out, t);
    if (out) out->commit();
    return;
  }
  // --labels all: the file read once, one surface per label in OUT/label-N/ (docs/io.md).
  Stopwatch t;
  VolumeReadOptions read;
  if (a.source.raw_dimensions.size() == 3)
    read.raw_dimensions =
        Eigen::Vector3i(a.source.raw_dimensions[0], a.source.raw_dimensions[1], a.source.raw_dimensions[2]);
  const VolumeData data = in_cli_terms([&] { return read_volume_data(a.source.volume, read); });
  const std::vector<double> labels = in_cli_terms([&] { return volume_labels(data); });
  if (out)
    std::cerr << "regularize: " << a.source.volume << ": " << labels.size() << " label"
              << (labels.size() == 1 ? "" : "s") << "\n";
  std::optional<double> h;
  if (a.source.h_option && a.source.h_option->count() > 0) h = a.source.h;
  // One label that cannot be regularized (a speck of a voxel or two, a part the options do not
  // suit) does not cost the others: its error is reported and recorded in labels.json, the other
  // labels are written, and the command still fails at the end so that scripts see it.
  nlohmann::json index = nlohmann::json::array();
  std::vector<std::string> failures;
  bool numerical = false;
  for (const double label : labels) {
    const std::string name = "label-" + label_name(label);
    const std::string description = a.source.volume + ", label " + label_name(label);
    const std::string dir = folder(name);
    if (out) std::filesystem::create_directories(dir);
    try {
      const LoadedSurface surface =
          in_cli_terms([&] { return load_surface(volume_array(data, InsideRule::label(label), h)); }, description);
      regularize_one(a, o, surface, description, dir, a.out + "/" + name, t);
      index.push_back({{"label", label}, {"folder", name}});
    } catch (const Error& e) {
      numerical = numerical || dynamic_cast<const InputError*>(&e) == nullptr;
      if (out) {
        std::filesystem::remove_all(dir);
        std::cerr << "regularize: label " << label_name(label) << " not written: " << e.what() << "\n";
      }
      index.push_back({{"label", label}, {"error", e.what()}});
      failures.push_back(label_name(label));
    }
  }
  std::string failed;
  for (const std::string& f : failures) failed += (failed.empty() ? "" : ", ") + f;
  const std::string summary = std::to_string(failures.size()) + " of " + std::to_string(labels.size()) +
                              " labels could not be regularized (" + failed + "; their errors above and in " + a.out +
                              "/labels.json)";
  if (failures.size() == labels.size()) {
    if (numerical) throw NumericalError("regularize: " + summary);
    throw InputError("regularize: " + summary);
  }
  if (out) {
    std::ofstream(out->file("labels.json")) << index.dump(2) << "\n";
    // Every label's result on one page, where they lie in the volume.
    if (!a.no_view && can_write_view(out->file("view.html"))) {
      std::vector<ViewSurface> surfaces;
      for (const auto& entry : index)
        if (entry.contains("folder")) {
          const std::string folder = entry["folder"];
          surfaces.push_back(read_view_surface(out->file(folder + "/regularized.ply"), folder));
        }
      ViewOptions view;
      view.title = "regularize: " + a.source.volume + ", every label";
      view.layout = "overlay";
      write_view_beside(out->file("view.html"), surfaces, view);
    }
    out->commit();
  }
  if (failures.empty()) return;
  const std::string message = "regularize: " + summary + "; the other labels are written";
  if (numerical) throw NumericalError(message);
  throw InputError(message);
}

RegisterCommand reg(42, "regularize", [](CLI::App& app) {
  auto args = std::make_shared<RegularizeArgs>();
  auto* cmd = app.add_subcommand(
      "regularize", "smooth a digital surface: (L M^-1 L + alpha M) p' = alpha M p - 2 L (H n) (docs/math.md §9.2)");
  args->source.add_options(*cmd);
  auto& only = args->laplacian_only;
  args->method.add_options(*cmd, /*method_flag=*/true, "fem");
  args->normals.source = "ii";  // the paper's normals (alpha = 1/3), for shapes as for volumes
  args->normals.add_options(*cmd);
  only.push_back(
      cmd->add_option("--size", args->size,
                      "object size s: the paper's defaults are for unit-sized shapes and apply to the shape scaled by "
                      "1/s (default: half the longest side of the bounding box; 1 for sphere1)")
          ->check(positive_number()));
  only.push_back(cmd->add_option("--curvature-radius", args->curvature_radius,
                                 "ball radius of the corrected mean curvature H, world units (default " +
                                     number_text(kCurvatureRadiusFraction) +
                                     " s; for volumes and mesh files at least " +
                                     number_text(kVoxelMinCurvatureRadius) + " voxels)")
                     ->check(positive_number()));
  only.push_back(cmd->add_option("--curvature-spacing", args->curvature_spacing,
                                 "spacing of the vertices where the curvature ball is walked, a fraction of the "
                                 "curvature radius; the others interpolate them (0: every vertex)")
                     ->check(non_negative_number())
                     ->capture_default_str());
  only.push_back(cmd->add_option("--alpha0", args->alpha0,
                                 "attachment weight: alpha = alpha0 / (h s)^2 (0: no attachment, the shape from the "
                                 "curvature alone, placed at the input's centroid; auto: from " +
                                     number_text(RegularizationOptions{}.alpha0) +
                                     " up while the result keeps away from the input's local mean and a larger "
                                     "alpha0 brings it back: detail a few voxels wide; docs/regularization.md)")
                     ->check(non_negative_number_or("auto"))
                     ->capture_default_str()
                     ->capture_default_str());
  only.push_back(
      cmd->add_option("--h-scale", args->h_scale, "curvature editing: H <- S H (paper §4.3)")->capture_default_str());
  only.push_back(
      cmd->add_option("--h-clamp", args->h_clamp, "curvature editing: clamp H to [-MAX, MAX] (after --h-scale)")
          ->check(positive_number()));
  only.push_back(cmd->add_option("--k1", args->k1_edit,
                                 "principal-curvature editing (paper §4.3) of the smaller principal curvature k1: "
                                 "scale:S, set:V or clamp:V; the normals are re-integrated from the edited shape "
                                 "operator S' and H = tr(S')/2 (docs/regularization.md)"));
  only.push_back(cmd->add_option("--k2", args->k2_edit, "the same for the larger principal curvature k2"));
  only.push_back(cmd->add_option("--normal-attachment", args->normal_attachment,
                                 "with --k1/--k2: weight of the new normals' attachment to the old ones, relative to "
                                 "the object size")
                     ->check(positive_number())
                     ->capture_default_str());
  only.push_back(cmd->add_option("--solve-accuracy", args->solve_accuracy,
                                 "the solve stops when the RMS error of the positions is provably below this many "
                                 "voxels (0: to rounding; docs/regularization.md)")
                     ->check(non_negative_number())
                     ->capture_default_str());
  args->solver.add_options(
      *cmd, std::string("linear solver backend (see `corrlap backends`; default ") + kDefaultLinearSolver + ")",
      /*positional_alias=*/true);
  cmd->add_option("--baseline", args->baseline,
                  "alignment: the paper's baseline [17] (the reference's DigitalSurfaceRegularization, docs/math.md "
                  "§9.1) with the face normals of --normals (its test: --normals convolved); alignment-direct: the "
                  "exact minimizer of the same energy by one sparse solve")
      ->check(CLI::IsMember({"alignment", "alignment-direct"}));
  cmd->add_flag("--allow-nonmanifold", args->allow_nonmanifold, kAllowNonmanifoldNote);
  args->clamp_option =
      cmd->add_flag("--clamp", args->clamp, "with --baseline alignment: keep every pointel within 0.5 voxel");
  cmd->add_flag("--no-render", args->no_render, "do not draw before.png and after.png");
  cmd->add_flag("--no-view", args->no_view,
                "do not write view.html (the page to turn the surfaces around in a browser)");
  args->output.add_options(*cmd);
  cmd->add_option("--out", args->out,
                  "output directory (regularized.ply/.obj, input.ply, metrics.json, before.png, after.png, view.html)")
      ->required();
  cmd->callback([args] { run(*args); });
});

}  // namespace
}  // namespace corrlap::cli
