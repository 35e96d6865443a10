// corrlap curvature: corrected curvature measures (docs/math.md §8) -> H, G, k1, k2, directions per face/vertex.
#include <chrono>
#include <corrlap/core/error.hpp>
#include <corrlap/estimators/corrected_curvature.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/io/output_folder.hpp>
#include <corrlap/io/text_io.hpp>
#include <corrlap/pipeline/surface_defaults.hpp>
#include <iostream>
#include <optional>

#include "command.hpp"
#include "normal_options.hpp"
#include "surface_source.hpp"
#include "validators.hpp"

namespace corrlap::cli {

namespace {

struct CurvatureArgs {
  SurfaceSource source;
  NormalOptions normals;
  std::string out;
  OutputOptions output;
  std::optional<double> radius;  // unset: default_curvature_radius of the surface
  bool constant = false;
};

// The estimates in the output units: H, k1, k2 in 1 / length, G in 1 / length^2, the principal
// directions mapped with the positions.
CurvatureEstimates in_units(CurvatureEstimates e, const OutputUnits& units) {
  e.H = units.curvatures(e.H);
  e.k1 = units.curvatures(e.k1);
  e.k2 = units.curvatures(e.k2);
  e.G = units.inverse_areas(e.G);
  e.d1 = units.directions(e.d1);
  e.d2 = units.directions(e.d2);
  return e;
}

void write_set(const std::string& dir, const std::string& suffix, const CurvatureEstimates& e,
               const OutputUnits& units) {
  const std::string at = " at " + suffix;
  write_scalars(dir + "/H_" + suffix + ".txt", e.H, units.scalar_comments("H: mean curvature" + at, 1));
  write_scalars(dir + "/G_" + suffix + ".txt", e.G, units.scalar_comments("G: Gaussian curvature" + at, 2));
  write_scalars(dir + "/k1_" + suffix + ".txt", e.k1, units.scalar_comments("k1: least principal curvature" + at, 1));
  write_scalars(dir + "/k2_" + suffix + ".txt", e.k2, units.scalar_comments("k2: largest principal curvature" + at, 1));
  write_normals(dir + "/d1_" + suffix + ".txt", e.d1);
  write_normals(dir + "/d2_" + suffix + ".txt", e.d2);
}

void run(const CurvatureArgs& a) {
  const auto t0 = std::chrono::steady_clock::now();
  const bool from_mesh = !a.source.mesh.empty();
  const NormalOptions& opt = a.normals;
  NormalKind need = a.constant ? NormalKind::Face : NormalKind::Vertex;
  if (from_mesh) {
    if (opt.face_file.empty() == opt.vertex_file.empty())
      throw InputError("--mesh needs exactly one of --face-normals F or --vertex-normals F");
    if (opt.source_option->count() > 0)
      throw InputError("--normals applies to --shape/--volume; with --mesh give a normals file");
    // A face file: constant normals per face; a vertex file: interpolated normals.
    need = opt.face_file.empty() ? NormalKind::Vertex : NormalKind::Face;
  } else if (!opt.face_file.empty() || !opt.vertex_file.empty()) {
    throw InputError("--face-normals/--vertex-normals go with --mesh; with a shape or volume use --normals true|ii");
  }
  OutputFolder out(a.out);  // checked before the computation
  const LoadedSurface surface = a.source.load();
  const SurfelMesh& mesh = surface.mesh;
  // The normals of `corrlap operators` for the same source (docs/math.md §1.5, resolve_normals);
  // auto: true for shapes, ii for volumes.
  const NormalFields n = opt.resolve(surface, need, "curvature");
  const CorrectedCurvature cc = need == NormalKind::Vertex ? CorrectedCurvature::interpolated(mesh, n.vertex)
                                                           : CorrectedCurvature::constant(mesh, n.face);
  const double radius = a.radius ? *a.radius : default_curvature_radius(surface);
  const OutputUnits units = a.output.parse(surface);
  const CurvatureEstimates ef = in_units(cc.at_faces(radius), units);
  const CurvatureEstimates ev = in_units(cc.at_vertices(radius), units);
  write_set(out.path(), "faces", ef, units);
  write_set(out.path(), "vertices", ev, units);
  MeshAttributes attr;
  attr.face_scalars = {{"H", ef.H}, {"G", ef.G}, {"k1", ef.k1}, {"k2", ef.k2}};
  attr.vertex_scalars = {{"H", ev.H}, {"G", ev.G}, {"k1", ev.k1}, {"k2", ev.k2}};
  attr.comments = units.comments();
  try {
    write_mesh(out.file("curvature.ply"), units.mesh(mesh), attr);
  } catch (const Error& e) {
    // The text files above are the contract; the PLY is a convenience for viewers.
    std::cerr << "warning: curvature.ply not written: " << e.what() << "\n";
  }
  out.commit();
  const Eigen::Vector3d t = cc.totals();
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::cerr << "curvature (" << (cc.interpolated_normals() ? "interpolated vertex normals" : "constant face normals")
            << ", r=" << radius << "): " << mesh.num_faces() << " faces, totals mu0=" << t[0] << " mu1=" << t[1]
            << " mu2=" << t[2] << " (world units), mean H (faces) " << ef.H.mean() << " (" << units.name()
            << " units) -> " << a.out << " (" << secs << " s)\n";
}

RegisterCommand reg(31, "curvature", [](CLI::App& app) {
  auto args = std::make_shared<CurvatureArgs>();
  auto* cmd =
      app.add_subcommand("curvature", "corrected curvature measures: H, G, k1, k2 and directions (docs/math.md §8)");
  args->source.add_options(*cmd, /*with_mesh=*/true);
  // --face-normals/--vertex-normals with --mesh (a face file: constant normals per face; a vertex
  // file: interpolated); --normals with a shape or volume.
  args->normals.add_options(*cmd);
  cmd->add_flag("--constant", args->constant, "with --normals: use the face normals as constant per face");
  cmd->add_option("--radius", args->radius,
                  "ball radius in world units, the computation's (default " + number_text(kCurvatureRadiusFraction) +
                      " s, s = half the longest side of the surface's bounding box; for volumes and mesh files at "
                      "least " +
                      number_text(kVoxelMinCurvatureRadius) + " voxels)")
      ->check(non_negative_number());
  args->output.add_options(*cmd);
  cmd->add_option("--out", args->out,
                  "output directory (H_faces.txt, G_, k1_, k2_, d1_, d2_ per faces/vertices, curvature.ply)")
      ->required();
  cmd->callback([args] { run(*args); });
});

}  // namespace
}  // namespace corrlap::cli
