// corrlap normals: face or vertex normals of a digital surface (trivial, true, integral invariant).
#include <chrono>
#include <corrlap/io/text_io.hpp>
#include <iostream>

#include "command.hpp"
#include "normal_options.hpp"
#include "surface_source.hpp"
#include "validators.hpp"

namespace corrlap::cli {

namespace {

struct NormalsArgs {
  SurfaceSource source;
  std::string estimator = "ii", at = "faces", out;
  double radius = 3.0, alpha = 0.33;
};

void run(const NormalsArgs& a) {
  NormalOptions opt;
  opt.source = a.estimator;
  opt.ii.k = a.radius;
  opt.ii.alpha = a.alpha;
  const auto t0 = std::chrono::steady_clock::now();
  const LoadedSurface surface = a.source.load();
  // Vertices: the normalized sum of the incident face normals (docs/math.md §1.5), as every command uses.
  const bool at_vertices = a.at == "vertices";
  const NormalFields fields =
      opt.resolve(surface, at_vertices ? NormalKind::Vertex : NormalKind::Face, "corrlap normals");
  const Eigen::MatrixX3d& n = at_vertices ? fields.vertex : fields.face;
  write_normals(a.out, n);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::cerr << a.estimator << " normals of " << a.source.describe() << ": " << n.rows() << " " << a.at << " -> "
            << a.out << " (" << secs << " s)\n";
}

RegisterCommand reg(30, "normals", [](CLI::App& app) {
  auto args = std::make_shared<NormalsArgs>();
  auto* cmd = app.add_subcommand("normals", "estimate normals: one 'nx ny nz' per face (digitize order) or per vertex");
  args->source.add_options(*cmd, /*with_mesh=*/true);
  cmd->add_option("--estimator", args->estimator,
                  "ii (integral invariant, docs/math.md §7), true (implicit shapes), trivial")
      ->check(CLI::IsMember({"ii", "true", "trivial", "convolved"}));
  cmd->add_option("--radius", args->radius, "II: r-radius k, Euclidean radius k*h^alpha (default 3)")
      ->check(positive_number());
  cmd->add_option("--alpha", args->alpha, "II: exponent alpha (default 0.33 as the reference; the paper uses 1/3)");
  cmd->add_option("--at", args->at, "faces (default) or vertices (normalized sum of incident face normals)")
      ->check(CLI::IsMember({"faces", "vertices"}));
  cmd->add_option("--out", args->out, "output text file")->required();
  cmd->callback([args] { run(*args); });
});

}  // namespace
}  // namespace corrlap::cli
