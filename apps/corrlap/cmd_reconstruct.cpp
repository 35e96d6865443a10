// corrlap reconstruct: the paper's reconstruction from a normal map (§4.2, Fig. 16). A fine
// triangle mesh is the normal map of a coarse voxelization of itself: the surfels are subdivided,
// the fine normals sampled at the subdivided surface by closest-point projection, the mean
// curvature estimated from them (clamped), and the geometry regularized (docs/regularization.md).
#include <corrlap/backends/registry.hpp>
#include <corrlap/core/error.hpp>
#include <corrlap/core/stopwatch.hpp>
#include <corrlap/discretizations/registry.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/io/output_folder.hpp>
#include <corrlap/regularization/normal_map_reconstruction.hpp>
#include <corrlap/regularization/regularize_surface.hpp>
#include <corrlap/render/image.hpp>
#include <corrlap/render/render_mesh.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <corrlap/surface/mesh_voxelization.hpp>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "command.hpp"
#include "method_options.hpp"
#include "render_output.hpp"
#include "solver_options.hpp"
#include "surface_source.hpp"
#include "validators.hpp"

namespace corrlap::cli {
namespace {

struct ReconstructArgs {
  std::string mesh_file, out;
  SolverOptions solver;
  MethodOptions method_params;  // applied to each method of --methods that declares them
  int resolution = 64, subdivide = 3;
  std::string methods = "fem,polydec";
  std::optional<double> curvature_radius, h_clamp;
  double alpha0 = 10.0;
  bool no_render = false, no_view = false;
  bool allow_nonmanifold = false;  // accepted and ignored (kAllowNonmanifoldNote)
};

void run(const ReconstructArgs& a) {
  const std::vector<std::string> methods = split_list(a.methods);
  if (methods.empty()) throw InputError("reconstruct: no method (--methods)");
  const Config solver_config = a.solver.config();
  RegularizationOptions o;
  o.alpha0 = a.alpha0;
  // The bias test of the automatic alpha0 is calibrated on staircases at the surfel scale, not on
  // a subdivided coarse one (docs/math.md §9.4): the paper's fixed alpha0 here.
  o.alpha0_auto = false;
  o.solver = solver_config;
  // Every method and option before any computation; what the surface allows once it is known.
  const auto check_methods = [&](const SurfelMesh* surface) {
    for (const std::string& method : methods) {
      o.method = method;
      o.method_params = a.method_params.config(method, /*only_declared=*/true);
      surface ? check_regularization_options(*surface, o) : check_regularization_options(o);
    }
  };
  check_methods(nullptr);

  // Checked before the computation; written whole at the end or not at all.
  OutputFolder out(a.out);
  nlohmann::json stages, m;
  Stopwatch t;
  const PolygonMesh fine = read_mesh(a.mesh_file);
  const TriangleIndices triangles = triangulate(fine);
  const TriangleLocator locator(fine.positions, triangles);
  const Eigen::MatrixX3d fine_normals = triangle_mesh_vertex_normals(fine.positions, triangles);
  // The coarse voxelization, its surfels subdivided 2^n times along each side.
  MeshVoxelizationParams params;
  params.resolution = a.resolution;
  MeshVoxelizationReport report;
  const VoxelGrid grid = voxelize_mesh(fine, params, &report);
  for (const std::string& w : report.warnings()) std::cerr << "warning: " << a.mesh_file << ": " << w << "\n";
  const SurfelMesh coarse = extract_surface(grid);
  if (coarse.num_faces() == 0) throw InputError("reconstruct: the voxelization of '" + a.mesh_file + "' is empty");
  check_regularizable(coarse, "reconstruct");
  const SurfelMesh mesh = subdivide_quads(coarse, a.subdivide);
  stages["voxelize_s"] = t.lap();
  // The normal map at the subdivided surface: the fine mesh's normals at the closest points.
  const NormalFields normals = sample_normal_map(mesh, locator, fine_normals);
  stages["normal_map_s"] = t.lap();
  const double size = regularization_size(mesh);
  std::cerr << "reconstruct: " << a.mesh_file << " (" << fine.positions.rows() << " vertices), voxelized at "
            << a.resolution << " (h = " << report.h << ", " << coarse.num_faces() << " surfels), subdivided "
            << a.subdivide << " times: " << mesh.num_vertices() << " vertices, " << mesh.num_faces() << " faces\n";

  o.size = size;
  // Paper Fig. 16: |H| <= 10 for a unit-sized model. The radius in coarse voxels (the staircase's),
  // not the paper's 0.2 size: kReconstructionCurvatureRadiusVoxels says why.
  o.curvature_radius = a.curvature_radius ? *a.curvature_radius : kReconstructionCurvatureRadiusVoxels * report.h;
  o.h_clamp = a.h_clamp ? *a.h_clamp : 10.0 / size;
  // The positions are wrong by up to a coarse voxel, not a subdivided one: alpha from the coarse h.
  o.alpha_step = report.h;
  check_methods(&mesh);
  const DistanceToMesh before = distance_to_mesh(mesh, locator);
  const double angle_before = normal_angle_to_map(mesh, locator, fine_normals);
  MeshAttributes input_attr;
  input_attr.vertex_normals = normals.vertex;
  write_mesh(out.file("input.ply"), mesh, input_attr);
  m["mesh_file"] = a.mesh_file;
  m["fine_vertices"] = fine.positions.rows();
  m["resolution"] = a.resolution;
  m["h"] = report.h;
  m["subdivide"] = a.subdivide;
  m["vertices"] = mesh.num_vertices();
  m["faces"] = mesh.num_faces();
  m["size"] = size;
  m["curvature_radius"] = *o.curvature_radius;
  m["h_clamp"] = *o.h_clamp;
  m["alpha0"] = a.alpha0;
  m["distance_mean_before"] = before.mean;
  m["distance_max_before"] = before.max;
  m["normal_angle_before_deg"] = angle_before;
  RenderOptions view;
  if (!a.no_render) {
    write_png(out.file("fine.png"), render_mesh(fine, nullptr, view));
    write_png(out.file("before.png"), render_mesh(to_polygon_mesh(mesh), nullptr, view));
  }
  // The curvature does not depend on the method: once for all of them.
  t.restart();
  const RegularizationCurvature curvature = regularization_curvature(mesh, normals, o);
  stages["curvature_s"] = t.lap();
  for (const std::string& method : methods) {
    o.method = method;
    o.method_params = a.method_params.config(method, /*only_declared=*/true);
    const RegularizedSurface r = regularize_surface(mesh, normals, o, &curvature);
    for (const auto& w : r.warnings) std::cerr << "warning: " << method << ": " << w << "\n";
    const double seconds = t.lap();
    const DistanceToMesh after = distance_to_mesh(r.mesh, locator);
    const double angle_after = normal_angle_to_map(r.mesh, locator, fine_normals);
    MeshAttributes attr;
    attr.vertex_scalars = {{"H", r.H}};
    write_mesh(out.file("reconstructed_" + method + ".ply"), r.mesh, attr);
    if (!a.no_render)
      write_png(out.file("after_" + method + ".png"), render_mesh(to_polygon_mesh(r.mesh), nullptr, view));
    nlohmann::json entry;
    entry["distance_mean_after"] = after.mean;
    entry["distance_max_after"] = after.max;
    entry["normal_angle_after_deg"] = angle_after;
    entry["time_s"] = seconds;
    entry["alpha"] = r.alpha;
    m["methods"][method] = entry;
    std::cerr << "  " << method << ": mean distance to the fine mesh " << before.mean << " -> " << after.mean
              << " (max " << before.max << " -> " << after.max << "), normal angle to the map " << angle_before
              << " -> " << angle_after << " deg, " << seconds << " s\n";
  }
  // The page: the first method's result shown, the others, the staircase and the fine mesh a
  // click away.
  if (!a.no_view && can_write_view(out.file("view.html"))) {
    Stopwatch view_time;
    std::vector<ViewSurface> surfaces;
    for (std::size_t i = 0; i < methods.size(); ++i) {
      surfaces.push_back(read_view_surface(out.file("reconstructed_" + methods[i] + ".ply"), methods[i]));
      surfaces.back().visible = i == 0;
    }
    surfaces.push_back(read_view_surface(out.file("input.ply"), "staircase"));
    surfaces.back().visible = false;
    surfaces.push_back({"fine mesh", fine, {}, false});
    ViewOptions view_options;
    view_options.title = "reconstruct: " + a.mesh_file;
    write_view_beside(out.file("view.html"), surfaces, view_options);
    stages["view_s"] = view_time.lap();
  }
  m["time_s"] = stages;
  std::ofstream(out.file("metrics.json")) << m.dump(2) << "\n";
  out.commit();
  std::cerr << "  wrote " << a.out << "/input.ply, reconstructed_<method>.ply, metrics.json"
            << (a.no_render ? "" : ", fine.png, before.png, after_<method>.png") << (a.no_view ? "" : ", view.html")
            << "\n";
}

RegisterCommand reg(42, "reconstruct", [](CLI::App& app) {
  auto args = std::make_shared<ReconstructArgs>();
  auto* cmd = app.add_subcommand(
      "reconstruct",
      "recover a surface from a normal map (paper §4.2): voxelize a fine mesh coarsely, subdivide the surfels, sample "
      "the fine normals, regularize (docs/regularization.md)");
  cmd->add_option("--mesh-file", args->mesh_file, "the fine triangle mesh, which gives the normal map")->required();
  cmd->add_option("--resolution", args->resolution, "voxels along the mesh's longest side")
      ->check(CLI::Range(4, 1024))
      ->capture_default_str();
  cmd->add_option("--subdivide", args->subdivide, "subdivide each surfel into 2^n x 2^n quads")
      ->check(CLI::Range(0, 6))
      ->capture_default_str();
  cmd->add_option("--methods", args->methods,
                  "vertex discretizations to compare (a corrected one and polydec, the uncorrected one)")
      ->capture_default_str();
  cmd->add_option("--curvature-radius", args->curvature_radius,
                  "ball radius of the mean curvature (default " + number_text(kReconstructionCurvatureRadiusVoxels) +
                      " coarse voxels; the paper's Fig. 16 uses 0.2 s, s = half the longest side)")
      ->check(positive_number());
  cmd->add_option("--h-clamp", args->h_clamp, "clamp H to [-MAX, MAX] (default 10 / s, paper Fig. 16)")
      ->check(positive_number());
  cmd->add_option("--alpha0", args->alpha0, "attachment weight alpha = alpha0 / (h s)^2, h the coarse voxel")
      ->check(positive_number())
      ->capture_default_str();
  args->method_params.add_options(*cmd, /*method_flag=*/false);
  args->solver.add_options(*cmd, std::string("linear solver backend (default ") + kDefaultLinearSolver + ")");
  cmd->add_flag("--allow-nonmanifold", args->allow_nonmanifold, kAllowNonmanifoldNote);
  cmd->add_flag("--no-render", args->no_render, "do not draw the pictures");
  cmd->add_flag("--no-view", args->no_view,
                "do not write view.html (the page to turn the surfaces around in a browser)");
  cmd->add_option("--out", args->out, "output directory")->required();
  cmd->callback([args] { run(*args); });
});

}  // namespace
}  // namespace corrlap::cli
