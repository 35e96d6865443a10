// corrlap demo: the main job on a built-in example (the unit sphere), running the whole data flow
// voxels -> digital surface -> normals and curvature -> operators -> solver -> results.
#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <corrlap/backends/registry.hpp>
#include <corrlap/core/mesh_topology.hpp>
#include <corrlap/discretizations/registry.hpp>
#include <corrlap/estimators/corrected_curvature.hpp>
#include <corrlap/estimators/implicit_normals.hpp>
#include <corrlap/estimators/normal_estimation.hpp>
#include <corrlap/estimators/normal_resolution.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/problems/problems.hpp>
#include <corrlap/problems/test_functions.hpp>
#include <corrlap/regularization/regularize_surface.hpp>
#include <corrlap/regularization/surface_quality.hpp>
#include <corrlap/render/render_mesh.hpp>
#include <corrlap/render/view_page.hpp>
#include <corrlap/studies/regularization_study.hpp>
#include <corrlap/studies/study.hpp>
#include <corrlap/studies/study_index.hpp>
#include <corrlap/studies/study_tables.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <corrlap/surface/implicit_shape.hpp>
#include <cstdio>
#include <filesystem>
#include <string>

#include "command.hpp"
#include "study_output.hpp"

namespace corrlap::cli {
namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

DigitizationParams sphere_params(double h) {
  DigitizationParams p;
  p.h = h;
  p.min_aabb = -2;
  p.max_aabb = 2;
  return p;
}

void digitization_table(const ImplicitShape& sphere) {
  std::printf("== 1. Digitization of the unit sphere (docs/math.md §1): the digital area does not converge to 4*pi\n");
  std::printf("%8s %10s %10s %10s %6s %12s %10s %10s\n", "h", "vertices", "edges", "faces", "euler", "area F*h^2",
              "area/4pi", "time_s");
  for (double h : {0.2, 0.1, 0.05, 0.01}) {
    const auto t0 = Clock::now();
    const SurfelMesh mesh = extract_surface(digitize(sphere, sphere_params(h)));
    const MeshInfo info = compute_mesh_info(mesh);
    std::printf("%8.3f %10d %10d %10d %6d %12.6f %10.6f %10.4f\n", h, info.vertices, info.edges, info.faces, info.euler,
                info.area, info.area / (4 * M_PI), since(t0));
  }
  std::printf("\n");
}

void normals_and_curvature(const ImplicitShape& sphere) {
  std::printf(
      "== 2. Normals (docs/math.md §7) and corrected curvature (docs/math.md §8, exact vertex normals) on the unit "
      "sphere\n");
  std::printf("%8s %16s %16s %12s %12s %10s\n", "h", "II mean angle", "II max angle", "mean H", "max|H-1|", "time_s");
  for (double h : {0.1, 0.05}) {
    const auto t0 = Clock::now();
    const VoxelGrid grid = digitize(sphere, sphere_params(h));
    const SurfelMesh mesh = extract_surface(grid);
    const Eigen::MatrixX3d ii = estimate_face_normals(NormalSource::II, mesh, &grid, &sphere);
    const Eigen::MatrixX3d exact = true_face_normals(sphere, mesh);
    double mean = 0, worst = 0;
    for (int f = 0; f < mesh.num_faces(); ++f) {
      const double a = std::atan2(ii.row(f).cross(exact.row(f)).norm(), ii.row(f).dot(exact.row(f)));
      mean += a;
      worst = std::max(worst, a);
    }
    mean /= mesh.num_faces();
    // Exact radial vertex normals, as in docs/math.md §12.4 (mean H 1.0026, max |H-1| 0.045 at h = 0.1), not
    // the "true" field of --normals true (normalized sum of face normals: max |H-1| 0.33 here).
    const Eigen::MatrixX3d vn = exact_vertex_normals(sphere, mesh);
    const CurvatureEstimates c = CorrectedCurvature::interpolated(mesh, vn).at_vertices(0.1);
    std::printf("%8.3f %14.4f deg %14.4f deg %12.6f %12.6f %10.3f\n", h, mean * 180 / M_PI, worst * 180 / M_PI,
                c.H.mean(), (c.H.array() - 1.0).abs().maxCoeff(), since(t0));
  }
  std::printf("\n");
}

void operators_table(const ImplicitShape& sphere) {
  std::printf("== 3. Operators (true normals) -> backward Poisson f = x^2 (docs/math.md §10.4, %s) and eigenvalues\n",
              kDefaultLinearSolver);
  std::printf("   area = 1^T M 1 (4*pi = %.5f); eigenvalues -lambda should be 0, 2 (x3), 6 (x5)\n", 4 * M_PI);
  std::printf("%18s %7s %10s %12s %12s %10s %10s %10s\n", "method", "h", "area", "Poisson L2", "order", "mu_1", "mu_4",
              "time_s");
  NormalRequest request;
  request.source = NormalSource::True;
  for (const char* method : {"polydec", "projected-polydec", "fem", "interpolated", "corrected-vrm"}) {
    double previous = 0;
    for (double h : {0.1, 0.05}) {
      const auto t0 = Clock::now();
      const SurfelMesh mesh = extract_surface(digitize(sphere, sphere_params(h)));
      auto disc = make_discretization(method);
      const NormalFields normals = resolve_normals(mesh, disc->required_normals(), request, &sphere, nullptr, method);
      const Operators ops = disc->assemble(mesh, normals, Config());
      auto solver = make_linear_solver(kDefaultLinearSolver);
      const PoissonErrors e = solve_poisson(ops, mesh.positions, test_function("x2"), *solver).errors;
      const EigenResult r = make_eigen_solver(kDefaultEigenSolver)->solve(ops.L, ops.M, 5);
      const double area =
          Eigen::VectorXd::Ones(mesh.num_vertices()).dot(ops.M * Eigen::VectorXd::Ones(mesh.num_vertices()));
      char order[32] = "";
      if (previous > 0) std::snprintf(order, sizeof order, "%.2f", std::log(previous / e.l2) / std::log(2.0));
      std::printf("%18s %7.3f %10.5f %12.3e %12s %10.5f %10.5f %10.3f\n", method, h, area, e.l2, order, r.values[1],
                  r.values[4], since(t0));
      previous = e.l2;
    }
  }
  std::printf(
      "\nUncorrected PolyDEC neither gets the area nor the spectrum right; the corrected methods do,\n"
      "and their Poisson error decreases about like h^1.7 (docs/math.md §12.5).\n");
}

void study_section() {
  const std::string dir = "corrlap-demo-study";
  std::printf(
      "\n== 4. A short study (corrlap study backward; docs/studies.md): fem and interpolated, x2,\n"
      "   h = 0.2, 0.1, 0.05, 2 centres each, fitted orders and a plot -> %s/\n",
      dir.c_str());
  std::fflush(stdout);
  StudyOptions o;
  o.kind = StudyKind::Backward;
  o.methods = {"fem", "interpolated"};
  o.h = {0.2, 0.1, 0.05};
  o.functions = {"x2"};
  o.centers = 2;
  o.min_aabb = -1.5;
  o.max_aabb = 1.5;
  std::filesystem::create_directories(dir);
  std::filesystem::remove(dir + "/results.csv");
  StudyCallbacks cb;
  cb.rows = [&](const std::vector<StudyRow>& rows) { write_results_csv(dir + "/results.csv", rows, true); };
  run_study(o, cb);
  finish_study(dir, dir, false, true);
  std::fflush(stdout);
}

void regularization_section(const ImplicitShape& sphere) {
  const std::string dir = "corrlap-demo-regularize";
  std::printf(
      "\n== 5. Regularization (corrlap regularize; docs/regularization.md): the staircase of the unit sphere\n"
      "   moved by (L M^-1 L + alpha M) p' = alpha M p - 2 L (H n), II normals, H from corrected curvature\n");
  std::filesystem::create_directories(dir);
  // The surface, its normals and its curvature do not depend on the method: once for both.
  const double h = 0.05;
  auto t0 = Clock::now();
  const VoxelGrid grid = digitize(sphere, sphere_params(h));
  const SurfelMesh mesh = extract_surface(grid);
  NormalRequest request;
  request.source = NormalSource::II;
  const NormalFields normals = resolve_normals(mesh, NormalKind::Vertex, request, &sphere, &grid, "demo");
  RegularizationOptions o;
  const RegularizationCurvature curvature = regularization_curvature(mesh, normals, o);
  const SurfaceQuality before = measure_against_shape(mesh, sphere, curvature.curvature_radius);
  std::printf("   surface, II normals and mean curvature (shared by the methods): %.3f s\n", since(t0));
  std::printf("%18s %7s %12s %12s %14s %14s %10s\n", "method", "h", "dist before", "dist after", "angle before",
              "angle after", "time_s");
  std::vector<ViewSurface> surfaces;  // the page: the staircase beside each result
  for (const char* method : {"fem", "polydec"}) {
    t0 = Clock::now();
    o.method = method;
    const RegularizedSurface r = regularize_surface(mesh, normals, o, &curvature);
    const SurfaceQuality after = measure_against_shape(r.mesh, sphere, r.curvature_radius);
    const std::string out = dir + "/regularized_" + method + ".ply";
    MeshAttributes attr;
    attr.vertex_normals = geometric_vertex_normals(r.mesh);
    attr.vertex_scalars = {{"H", r.H}};
    write_mesh(out, r.mesh, attr);
    // Pictures coloured by H on one range: the staircase once, each result.
    const ScalarField H{"H", r.H, false};
    RenderOptions view;
    view.range_min = 0.5;
    view.range_max = 1.5;
    if (std::string(method) == "fem") {
      write_png(dir + "/before.png", render_mesh(to_polygon_mesh(mesh), &H, view));
      surfaces.push_back({"staircase", to_polygon_mesh(mesh), {H}});
    }
    surfaces.push_back({method, to_polygon_mesh(r.mesh), {H}});
    write_png(dir + "/after_" + std::string(method) + ".png", render_mesh(to_polygon_mesh(r.mesh), &H, view));
    std::printf("%18s %7.3f %12.3e %12.3e %10.2f deg %10.2f deg %10.3f  -> %s\n", method, h, before.distance_l1,
                after.distance_l1, before.normal_angle_deg, after.normal_angle_deg, since(t0), out.c_str());
  }
  std::printf("   (mean distance of the vertices to the sphere, mean angle of the surface's own normals)\n");
  std::printf("   pictures: %s/before.png (the staircase), %s/after_fem.png, %s/after_polydec.png\n", dir.c_str(),
              dir.c_str(), dir.c_str());
  if (has_viewer()) {
    ViewOptions page;
    page.title = "corrlap demo: the unit sphere's staircase, regularized";
    page.scales["H"] = ColourScale{0.5, 1.5, Colormap::Sequential};  // the pictures' range
    write_view_page(dir + "/view.html", surfaces, page);
    std::printf("   to turn them around in a browser: %s/view.html\n", dir.c_str());
  }
  std::fflush(stdout);
}

void regularization_study_section() {
  const std::string dir = "corrlap-demo-regularization-study";
  std::printf(
      "\n== 6. The regularization study (corrlap study regularization; paper Fig. 15): sphere1 at\n"
      "   h = 0.2, 0.1, 0.05, corrected fem, uncorrected polydec and the baseline [17] -> %s/\n",
      dir.c_str());
  std::fflush(stdout);
  RegularizationStudyOptions o;
  o.shapes = {"sphere1"};
  o.h = {0.2, 0.1, 0.05};
  o.methods = {"fem", "polydec", "alignment"};
  o.min_aabb = -1.5;
  o.max_aabb = 1.5;
  std::filesystem::create_directories(dir);
  std::vector<RegularizationStudyRow> rows;
  run_regularization_study(o, [&](const RegularizationStudyRow& r) {
    rows.push_back(r);
    std::printf("%18s %7.3f  distance %10.3e -> %10.3e   |H - 1| %8.4f -> %8.4f\n", r.method.c_str(), r.h,
                r.distance_before, r.distance_after, r.curvature_error_before, r.curvature_error_after);
  });
  write_regularization_csv(dir + "/regularization.csv", rows);
  std::printf("   table: %s/regularization.csv\n", dir.c_str());
  std::fflush(stdout);
  run_plot_script(dir);
  write_study_index(dir, "corrlap demo: regularization");
  std::printf("   plots and table on one page: %s/index.html\n", dir.c_str());
}

void run_demo() {
  const auto t0 = Clock::now();
  const ImplicitShape sphere = make_implicit_shape("sphere1");
  digitization_table(sphere);
  normals_and_curvature(sphere);
  operators_table(sphere);
  study_section();
  regularization_section(sphere);
  regularization_study_section();
  std::printf("\ndemo finished in %.1f s\n", since(t0));
}

RegisterCommand reg(0, "demo", [](CLI::App& app) {
  auto* cmd = app.add_subcommand("demo", "run the whole pipeline on a built-in example (unit sphere)");
  cmd->callback([] { run_demo(); });
});

}  // namespace
}  // namespace corrlap::cli
