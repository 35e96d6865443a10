// corrlap normals: face or vertex normals of a digital surface (trivial, true, integral invariant).
#include <chrono>
#include <corrlap/io/output_folder.hpp>
#include <corrlap/io/text_io.hpp>
#include <iostream>

#include "command.hpp"
#include "deprecated.hpp"
#include "normal_options.hpp"
#include "surface_source.hpp"
#include "validators.hpp"

namespace corrlap::cli {

namespace {

struct NormalsArgs {
  SurfaceSource source;
  NormalOptions normals;
  std::string at = "faces", out;
  OutputOptions output;
};

void run(const NormalsArgs& a) {
  const auto t0 = std::chrono::steady_clock::now();
  StagedFile out(a.out);  // checked before the computation
  const LoadedSurface surface = a.source.load();
  const OutputUnits units = a.output.parse(surface);
  // Vertices: the normalized sum of the incident face normals (docs/math.md §1.5), as every command uses.
  const bool at_vertices = a.at == "vertices";
  const NormalFields fields =
      a.normals.resolve(surface, at_vertices ? NormalKind::Vertex : NormalKind::Face, "corrlap normals");
  const Eigen::MatrixX3d n = units.normals(at_vertices ? fields.vertex : fields.face);
  write_normals(out.path(), n);
  out.commit();
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::cerr << a.normals.describe(surface) << " normals of " << surface.description << ": " << n.rows() << " " << a.at
            << " -> " << a.out << " (" << units.name() << " coordinates"
            << (units.space_name().empty() ? "" : ", " + units.space_name()) << ", " << secs << " s)\n";
}

RegisterCommand reg(30, "normals", [](CLI::App& app) {
  auto args = std::make_shared<NormalsArgs>();
  auto* cmd = app.add_subcommand("normals", "estimate normals: one 'nx ny nz' per face (digitize order) or per vertex");
  args->source.add_options(*cmd, /*with_mesh=*/true);
  args->normals.source = "ii";  // what this command is for: the estimate of the voxels
  args->normals.add_options(*cmd);
  // The spellings of this command before --normals/--ii-radius/--ii-alpha were shared by all.
  add_deprecated_alias(*cmd, "--estimator", "--normals", args->normals.source);
  add_deprecated_alias(*cmd, "--radius", "--ii-radius", args->normals.ii_k)->check(positive_number());
  add_deprecated_alias(*cmd, "--alpha", "--ii-alpha", args->normals.ii_alpha);
  cmd->add_option("--at", args->at, "faces (default) or vertices (normalized sum of incident face normals)")
      ->check(CLI::IsMember({"faces", "vertices"}));
  cmd->add_option("--out", args->out, "output text file")->required();
  args->output.add_options(*cmd);
  cmd->callback([args] { run(*args); });
});

}  // namespace
}  // namespace corrlap::cli
