#include "regularize_surface.hpp"

#include <algorithm>
#include <cmath>
#include <corrlap/backends/registry.hpp>
#include <corrlap/core/error.hpp>
#include <corrlap/core/mesh_topology.hpp>
#include <corrlap/core/stopwatch.hpp>
#include <corrlap/discretizations/registry.hpp>
#include <corrlap/estimators/corrected_curvature.hpp>
#include <corrlap/regularization/attachment_bias.hpp>
#include <corrlap/regularization/patch_bias.hpp>
#include <corrlap/regularization/surface_quality.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <numbers>
#include <optional>
#include <sstream>

namespace corrlap {

namespace {
// Below this bounding-box diagonal, in voxels, an object is a speck: two or three voxels, whose
// curvature exceeds 1/h for real.
constexpr double kSpeckVoxels = 4.0;
}  // namespace

double default_curvature_radius(double size, double voxel, bool voxels_from_file, double fraction) {
  const double radius = fraction * size;
  return voxels_from_file ? std::max(radius, kVoxelMinCurvatureRadius * voxel) : radius;
}

double regularization_size(const SurfelMesh& mesh) {
  if (mesh.num_vertices() == 0) return 0.0;
  return 0.5 * (mesh.positions.colwise().maxCoeff() - mesh.positions.colwise().minCoeff()).maxCoeff();
}

namespace {
// A number as a user wrote it (1e+300, 0.01), not std::to_string's fixed point.
std::string number_text(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

double object_size(const SurfelMesh& mesh, const RegularizationOptions& o) {
  const double size = o.size ? *o.size : regularization_size(mesh);
  if (!(size > 0.0) || !std::isfinite(size))
    throw InputError("regularization: the object size must be a positive number, got " + number_text(size) +
                         (o.size ? "" : " (the surface's half bounding box)"),
                     "size");
  return size;
}

// A real option: finite and above `min` (or at least `min` when `open` is false).
void check_real(double value, const char* parameter, const char* what, double min, bool open = true) {
  if (std::isfinite(value) && (open ? value > min : value >= min)) return;
  throw InputError("regularization: " + std::string(parameter) + " = " + number_text(value) + ": " + what +
                       " must be a finite number " + (open ? "> " : ">= ") + number_text(min),
                   parameter);
}

void check_edit(const PrincipalCurvatureEdit& e, const char* parameter) {
  if (!std::isfinite(e.value) || (e.kind == PrincipalCurvatureEdit::Kind::Clamp && e.value < 0.0))
    throw InputError(
        "regularization: the principal curvature edit " + e.describe() + " needs a finite value (>= 0 for clamp)",
        parameter);
}

// The h that alpha = alpha0 / (h size)^2 uses.
double alpha_h(const SurfelMesh& mesh, const RegularizationOptions& o) {
  return o.alpha_step ? *o.alpha_step : mesh.grid_step();
}

// Whether `method` with `params` defines its operators on vertices, asked of the method itself on
// the smallest closed surface (one voxel's six surfels, microseconds): the interface does not
// declare it, and a method's parameters can change it (heat-kernel's variant). A probe that fails
// says nothing: the assembly on the real surface reports its own error.
bool on_vertices(const Discretization& method, const Config& params) {
  static const SurfelMesh cube = [] {
    VoxelGrid grid(Eigen::Vector3i(-1, -1, -1), Eigen::Vector3i(1, 1, 1), 1.0);
    grid.set(0, 0, 0, true);
    return extract_surface(grid);
  }();
  NormalFields normals;
  normals.face = cube.face_normals_from_positions();
  normals.vertex = vertex_normals_from_face_normals(normals.face, cube.faces, cube.num_vertices());
  try {
    return method.assemble(cube, normals, params).domain == Operators::Domain::Vertices;
  } catch (const Error&) {
    return true;
  }
}
// The error for a method whose operators live on faces, naming the methods (and the choices of
// this one's parameters) that define them on vertices.
[[noreturn]] void refuse_face_method(const std::string& method) {
  std::string able;
  for (const std::string& name : discretization_registry().names())
    if (on_vertices(*make_discretization(name), Config{})) able += (able.empty() ? "" : ", ") + name;
  const auto refused = make_discretization(method);
  for (const Parameter& p : refused->parameters().items())
    for (const std::string& value : p.choices) {
      Config variant;
      variant.set(p.name, value);
      if (on_vertices(*refused, variant)) able += ", or " + method + " with " + p.name + "=" + value;
    }
  throw InputError("regularization: method '" + method +
                       "' defines its operators on faces, and the positions live on vertices; use " + able,
                   "method");
}
}  // namespace

void check_regularization_options(const RegularizationOptions& o) {
  const auto method = make_discretization(o.method);
  (void)method->parameters().read(o.method_params, o.method);
  if (!on_vertices(*method, o.method_params)) refuse_face_method(o.method);
  (void)make_linear_solver(o.solver, kDefaultLinearSolver);
  if (o.size) check_real(*o.size, "size", "the object size", 0.0);
  if (o.curvature_radius) check_real(*o.curvature_radius, "curvature_radius", "the curvature radius", 0.0);
  check_real(o.curvature_spacing, "curvature_spacing", "the curvature site spacing", 0.0, /*open=*/false);
  check_real(o.alpha0, "alpha0", "alpha0", 0.0, /*open=*/false);  // 0: no attachment (docs/math.md §9.3)
  if (o.alpha_step) check_real(*o.alpha_step, "alpha_step", "the step of alpha", 0.0);
  if (!std::isfinite(o.h_scale))
    throw InputError("regularization: the mean curvature scale must be a finite number, got " + number_text(o.h_scale),
                     "h_scale");
  if (o.h_clamp) check_real(*o.h_clamp, "h_clamp", "the mean curvature clamp", 0.0, /*open=*/false);
  check_real(o.normal_attachment, "normal_attachment", "the normal attachment", 0.0);
  check_real(o.solve_accuracy, "solve_accuracy", "the solve accuracy", 0.0, /*open=*/false);
  check_edit(o.k1_edit, "k1");
  check_edit(o.k2_edit, "k2");
}

void check_regularization_options(const SurfelMesh& mesh, const RegularizationOptions& o) {
  check_regularization_options(o);
  if (mesh.num_vertices() == 0) throw InputError("regularization: the surface has no vertex");
  const double size = object_size(mesh, o), h = alpha_h(mesh, o);
  const double alpha = regularization_alpha(h * size, o.alpha0);
  // The staircase's area bounds the sum of every method's lumped mass (corrected areas project it).
  const double largest = max_regularization_alpha(surface_area(mesh), mesh.positions.cwiseAbs().maxCoeff());
  if (alpha > largest) {
    const double alpha0_max = largest * (h * size) * (h * size);
    throw InputError("regularization: alpha0 = " + number_text(o.alpha0) +
                         " gives alpha = alpha0 / (h size)^2 = " + number_text(alpha) +
                         ", beyond what the solve represents in double precision on this surface: the attachment "
                         "term alpha M p would overflow and the result would be garbage (all zeros); alpha0 up to " +
                         number_text(alpha0_max) +
                         " can be solved here, and the paper uses 0.01 to 1000 (a larger alpha0 keeps the result "
                         "closer to the input)",
                     "alpha0");
  }
}

void check_curvature_resolvable(std::int64_t absurd, std::int64_t total, double worst, double h, double across) {
  if (absurd == 0) return;
  // An object a few voxels across (a speck of a segmentation) really curves by more than 1/h: say
  // so rather than blame the normals.
  if (across < kSpeckVoxels)
    throw InputError("regularization: the object is " + std::to_string(across) +
                         " voxels across (its bounding box's diagonal), too small for a surface to be regularized: "
                         "its mean curvature exceeds 1/h at " +
                         std::to_string(absurd) + " of " + std::to_string(total) +
                         " vertices; leave it out (a speck of a segmentation), or give h_clamp to clamp H",
                     "h_clamp");
  throw InputError("regularization: the mean curvature exceeds 1/h = " + std::to_string(1.0 / h) + " at " +
                       std::to_string(absurd) + " of " + std::to_string(total) + " vertices (up to " +
                       std::to_string(worst) +
                       "): the normals are likely wrong there, e.g. II normals whose radius exceeds the shape's "
                       "features; give a smaller ii_radius, other normals, or h_clamp to clamp H",
                   "ii_radius");
}

RegularizationCurvature regularization_curvature(const SurfelMesh& mesh, const NormalFields& normals,
                                                 const RegularizationOptions& o) {
  check_regularization_options(mesh, o);
  if (!normals.has_vertex()) throw InputError("regularization: vertex normals are needed");
  RegularizationCurvature c;
  const double h = mesh.grid_step();
  c.size = object_size(mesh, o);
  c.curvature_radius = o.curvature_radius ? *o.curvature_radius : default_curvature_radius(c.size, h, false);
  Stopwatch watch;
  if (o.report_stage)
    o.report_stage("mean curvature in balls of radius " + number_text(c.curvature_radius) + " (" +
                   number_text(c.curvature_radius / h) + " voxels) at " + std::to_string(mesh.num_vertices()) +
                   " vertices");
  // docs/math.md §9.2: H from the corrected curvature measures with the same normals (§8).
  // Principal edits need k1, k2 and their directions at every vertex; H alone is walked at sites
  // (§8.4) and interpolated.
  const bool principal = o.k1_edit.active() || o.k2_edit.active();
  const CorrectedCurvature measures = CorrectedCurvature::interpolated(mesh, normals.vertex);
  CurvatureEstimates estimates;
  if (principal)
    estimates = measures.at_vertices(c.curvature_radius);
  else
    estimates.H = measures.mean_curvature_at_sites(c.curvature_radius, o.curvature_spacing * c.curvature_radius).H;
  c.H = estimates.H;
  for (Eigen::Index v = 0; v < c.H.size(); ++v)
    if (!std::isfinite(c.H[v]))
      throw NumericalError("regularization: the mean curvature of vertex " + std::to_string(v) +
                           " is not finite (is the curvature radius larger than the mesh?)");
  // A curvature radius below one voxel cannot be resolved: an estimate |H| > 1/h means the normals
  // are wrong there (II normals whose radius exceeds the shape's features). Solving with such H
  // moves the surface by many voxels, silently; refuse unless the user clamps H. (The check is on
  // the estimate, before the edits.)
  if (!o.h_clamp) {
    std::int64_t absurd = 0;
    double worst = 0.0;
    for (Eigen::Index v = 0; v < c.H.size(); ++v)
      if (std::abs(c.H[v]) > 1.0 / h) {
        ++absurd;
        worst = std::max(worst, std::abs(c.H[v]));
      }
    const double across = mesh.num_vertices() > 0
                              ? (mesh.positions.colwise().maxCoeff() - mesh.positions.colwise().minCoeff()).norm() / h
                              : 0.0;
    check_curvature_resolvable(absurd, c.H.size(), worst, h, across);
  }
  c.normals = normals.vertex;
  if (principal) {
    // Paper §4.3: edit k1, k2 in S, integrate dn = S' into n', H' = tr(S') / 2 (curvature_editing.hpp).
    const std::vector<Eigen::Matrix3d> S =
        edited_shape_operators(estimates.k1, estimates.k2, estimates.d1, estimates.d2, o.k1_edit, o.k2_edit);
    auto integration_solver = make_linear_solver(o.solver, kDefaultLinearSolver);
    c.normals = integrate_shape_operator(mesh, S, normals.vertex, c.size, o.normal_attachment, *integration_solver);
    double angles = 0.0;
    for (Eigen::Index v = 0; v < c.H.size(); ++v) {
      c.H[v] = 0.5 * S[std::size_t(v)].trace();
      angles += std::acos(std::clamp(c.normals.row(v).dot(normals.vertex.row(v)), -1.0, 1.0));
    }
    c.normal_angle_change_deg = c.H.size() > 0 ? angles / double(c.H.size()) * 180.0 / std::numbers::pi : 0.0;
  }
  c.H *= o.h_scale;  // curvature editing (paper §4.3): scale, then clamp
  if (o.h_clamp) c.H = c.H.cwiseMax(-*o.h_clamp).cwiseMin(*o.h_clamp);
  c.seconds = watch.lap();
  return c;
}

RegularizedSurface regularize_surface(const SurfelMesh& mesh, const NormalFields& normals,
                                      const RegularizationOptions& o, const RegularizationCurvature* curvature) {
  // Options first: a bad name or value fails before the curvature and the assembly.
  check_regularization_options(mesh, o);
  auto solver = make_linear_solver(o.solver, kDefaultLinearSolver);
  auto method = make_discretization(o.method);
  const int boundary_edges = compute_mesh_info(mesh).boundary_edges;
  if (boundary_edges > 0)
    throw InputError("regularization: the surface is open (" + std::to_string(boundary_edges) +
                     " boundary edges); it is defined for closed surfaces");
  if (!normals.has_vertex()) throw InputError("regularization: vertex normals are needed");
  if (curvature && (curvature->H.size() != mesh.num_vertices() || curvature->normals.rows() != mesh.num_vertices()))
    throw InputError("regularization: the given curvature has " + std::to_string(curvature->H.size()) + " values for " +
                     std::to_string(mesh.num_vertices()) + " vertices");

  RegularizedSurface r;
  r.h = mesh.grid_step();
  r.solver = o.solver.get_string("solver", kDefaultLinearSolver);
  std::optional<RegularizationCurvature> computed;
  if (!curvature) curvature = &computed.emplace(regularization_curvature(mesh, normals, o));
  r.size = curvature->size;
  r.curvature_radius = curvature->curvature_radius;
  const double alpha_step = alpha_h(mesh, o);
  r.alpha0 = o.alpha0;
  r.alpha = regularization_alpha(alpha_step * r.size, o.alpha0);
  r.H = curvature->H;
  r.normals = curvature->normals;
  r.normal_angle_change_deg = curvature->normal_angle_change_deg;
  r.curvature_seconds = computed ? curvature->seconds : 0.0;
  Stopwatch watch;

  Operators ops = method->assemble(mesh, normals, o.method_params);
  r.warnings = ops.warnings;
  if (ops.domain != Operators::Domain::Vertices) refuse_face_method(o.method);
  r.operators_seconds = watch.lap();

  r.mesh = mesh;
  double residual = 0.0;
  // One solve: the positions, and what the result reports of it.
  struct Solved {
    Eigen::MatrixX3d positions;
    std::string scheme;
    int iterations = 0;
    double error_bound = 0.0, residual = 0.0;
  };
  std::vector<Solved> solved;
  std::optional<PreconditionedRegularization> preconditioned;  // its analysis serves every trial
  const auto solve_at = [&](double alpha) -> Solved {
    Solved out;
    bool analyzed = true;  // whether this solve ran a symbolic analysis
    if (alpha == 0.0) {
      preconditioned.reset();  // the solver analyzes another pattern
      SolverReport unattached;
      out.positions =
          regularize_positions_unattached(ops.L, ops.M, mesh.positions, r.normals, r.H, *solver, &unattached);
      out.scheme = "unattached";
      out.residual = unattached.residual;
    }
    // With a direct backend, CG preconditioned by a factorization with L's pattern gives the normal
    // equations' solution at a fraction of the cost of factorizing L M_l^{-1} L (the header of
    // regularize_positions_preconditioned); it needs L negative semi-definite, else the direct solve.
    if (r.solver != "cg" && out.scheme.empty()) {
      try {
        SolverReport cg;
        const double step = mesh.grid_step();
        double bound = 0.0;
        analyzed = !preconditioned;
        if (!preconditioned) preconditioned.emplace(ops.L, ops.M, mesh.positions, r.normals, r.H, *solver);
        // A later trial starts from the last one's positions (a larger alpha0 moves them less), an
        // estimated one has none.
        const Eigen::MatrixX3d* start =
            solved.empty() || solved.back().positions.rows() == 0 ? nullptr : &solved.back().positions;
        out.positions = preconditioned->solve(alpha, o.solve_accuracy * step, &cg, &bound, start);
        out.scheme = "preconditioned-cg";
        out.iterations = cg.iterations;
        out.error_bound = bound / step;
        out.residual = cg.residual;
      } catch (const SolverError& e) {
        if (e.status() != SolverStatus::NotPositiveDefinite) throw;
        preconditioned.reset();  // the direct solve below analyzes another pattern with the same solver
        // Once, though every trial of the automatic alpha0 meets it.
        const std::string warning = "regularization: " + std::string(e.what()) +
                                    "; L is not negative semi-definite, solved the normal equations directly";
        if (std::find(r.warnings.begin(), r.warnings.end(), warning) == r.warnings.end()) r.warnings.push_back(warning);
      }
    }
    if (out.scheme.empty()) {
      SolverReport direct;
      analyzed = true;
      out.positions = regularize_positions(ops.L, ops.M, mesh.positions, r.normals, r.H, alpha, *solver, &direct);
      out.scheme = "direct";
      out.residual = direct.residual;
    }
    const SolverReport& backend = solver->info();
    r.factorize_seconds += (analyzed ? backend.analyze_seconds : 0.0) + backend.factorize_seconds;
    r.factor_nonzeros = backend.factor_nonzeros;
    r.factor_flops = backend.factor_flops;
    return out;
  };
  // Curvature edits move the surface away from the staircase on purpose: the bias test would undo them.
  const bool edited = o.h_scale != 1.0 || o.h_clamp || o.k1_edit.active() || o.k2_edit.active();
  const bool automatic = o.alpha0_auto && !edited && r.alpha0 > 0.0;
  // docs/math.md §9.5: on a large surface the first trial's bias is estimated from patches first;
  // far above the limit, its result would not be kept and its solve is skipped.
  // The patches are solved as the preconditioned scheme solves, which needs a direct backend.
  if (automatic && r.solver != "cg" && mesh.num_vertices() >= o.patch_bias_min_vertices) {
    PatchBiasOptions patch_options;
    patch_options.stop_below = 0.5 * kPatchBiasSkipFactor * kAttachmentBiasLimit;
    if (o.report_stage)
      o.report_stage("estimating the bias at alpha0 = " + number_text(r.alpha0) + " from " +
                     std::to_string(patch_options.patches) + " patches");
    try {
      const PatchBias estimate = patch_attachment_bias(mesh.faces, ops.L, ops.M, mesh.positions, r.normals, r.H,
                                                       r.alpha, alpha_step, patch_options);
      if (estimate.bias >= kPatchBiasSkipFactor * kAttachmentBiasLimit) {
        r.alpha0_trials.push_back({r.alpha0, estimate.bias, /*estimated=*/true});
        solved.emplace_back();  // no positions: solved below if it is the one kept
      }
    } catch (const SolverError&) {
      // L not negative semi-definite (the whole solve then falls back to the direct scheme): no estimate.
    }
  }
  if (solved.empty()) {
    if (o.report_stage) o.report_stage("solving with alpha0 = " + number_text(r.alpha0));
    solved.push_back(solve_at(r.alpha));
  }
  if (o.alpha0_auto && !edited) {
    // docs/math.md §9.4: raise alpha0 while the result keeps away from the staircase's local mean
    // and the raise buys the bias back.
    const Eigen::VectorXd mass = ops.M * Eigen::VectorXd::Ones(ops.M.cols());
    const auto bias_of = [&](const Eigen::MatrixX3d& q) {
      return attachment_bias(mesh.faces, mesh.positions, q, r.normals, mass, alpha_step);
    };
    if (r.alpha0_trials.empty()) r.alpha0_trials.push_back({r.alpha0, bias_of(solved.back().positions)});
    // The largest alpha0 the solve represents on this surface (check_regularization_options).
    const double scale = alpha_step * r.size;
    const double largest =
        std::min(alpha0_for_wavelength(kAutoAlpha0MinWavelength, r.size / alpha_step),
                 max_regularization_alpha(surface_area(mesh), mesh.positions.cwiseAbs().maxCoeff()) * scale * scale);
    for (double next = next_alpha0(r.alpha0_trials, kAttachmentBiasLimit, largest); next > 0.0;
         next = next_alpha0(r.alpha0_trials, kAttachmentBiasLimit, largest)) {
      if (o.report_stage)
        o.report_stage(std::string(r.alpha0_trials.back().estimated ? "the estimate" : "the result") +
                       " at alpha0 = " + number_text(r.alpha0_trials.back().alpha0) + " keeps " +
                       number_text(r.alpha0_trials.back().bias) + " voxels from the input's local mean (limit " +
                       number_text(kAttachmentBiasLimit) + "): solving with alpha0 = " + number_text(next));
      solved.push_back(solve_at(regularization_alpha(scale, next)));
      r.alpha0_trials.push_back({next, bias_of(solved.back().positions)});
    }
    const std::size_t kept = chosen_alpha0_trial(r.alpha0_trials);
    r.alpha0 = r.alpha0_trials[kept].alpha0;
    r.alpha = regularization_alpha(scale, r.alpha0);
    solved.resize(kept + 1);
    if (r.alpha0_trials[kept].estimated) {
      // The raise bought less than it should (the estimate was too high): the first trial is kept
      // after all, solved now.
      if (o.report_stage) o.report_stage("solving with alpha0 = " + number_text(r.alpha0));
      solved.back() = solve_at(r.alpha);
      r.alpha0_trials.push_back({r.alpha0, bias_of(solved.back().positions)});
    }
  }
  Solved& result = solved.back();
  r.mesh.positions = std::move(result.positions);
  r.solve_scheme = result.scheme;
  r.solve_iterations = result.iterations;
  r.solve_error_bound = result.error_bound;
  residual = result.residual;
  r.solve_seconds = watch.lap();
  r.solve_residual = residual;

  // A solve stopped at a proven accuracy has its error bound instead: its relative residual is
  // dominated by high frequencies of no consequence (1e-3 on small surfaces) and says nothing more.
  const bool proven = r.solve_scheme == "preconditioned-cg" && o.solve_accuracy > 0.0;
  r.check = check_solution(mesh, r.mesh.positions, proven ? std::nullopt : std::optional<double>(residual),
                           "regularization (" + o.method + ")");
  r.energy_before = regularization_energy(ops.L, ops.M, mesh.positions, r.normals, r.H, mesh.positions);
  r.energy_after = regularization_energy(ops.L, ops.M, mesh.positions, r.normals, r.H, r.mesh.positions);
  return r;
}

}  // namespace corrlap
