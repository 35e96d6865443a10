// corrlap normals: face or vertex normals of a digital surface (trivial, true, integral invariant).
#include <atomic>
#include <chrono>
#include <iostream>
#include <mutex>

#include <corrlap/surface/extract_surface.hpp>
#include <corrlap/core/error.hpp>
#include <corrlap/core/normal_fields.hpp>
#include <corrlap/estimators/normal_estimation.hpp>
#include <corrlap/io/text_io.hpp>

#include "command.hpp"
#include "surface_source.hpp"

namespace corrlap::cli {

/// Progress on stderr in steps of 10 % (II on fine grids runs for seconds to minutes).
ProgressFn stderr_progress(const std::string& what);

ProgressFn stderr_progress(const std::string& what) {
  auto last = std::make_shared<std::atomic<int>>(0);
  auto mutex = std::make_shared<std::mutex>();
  return [what, last, mutex](std::int64_t done, std::int64_t total) {
    if (total < 20000) return;  // short runs: stay quiet
    const int decile = int(10 * done / total);
    int prev = last->load();
    while (decile > prev) {
      if (last->compare_exchange_weak(prev, decile)) {
        std::lock_guard<std::mutex> lock(*mutex);
        std::cerr << what << ": " << 10 * decile << "%\n";
        break;
      }
    }
  };
}

namespace {

struct NormalsArgs {
  SurfaceSource source;
  std::string estimator = "ii", at = "faces", out;
  double radius = 3.0, alpha = 0.33;
};

void run(const NormalsArgs& a) {
  const NormalEstimator est = parse_normal_estimator(a.estimator);
  const auto t0 = std::chrono::steady_clock::now();
  SurfelMesh mesh;
  VoxelGrid grid;
  const bool need_voxels = a.source.mesh.empty();
  if (need_voxels) {
    grid = a.source.voxels();
    if (grid.count() == 0) throw InputError("the volume is empty: no voxel is inside (" + a.source.describe() + ")");
    mesh = extract_surface(grid);
  } else {
    mesh = a.source.surface();
  }
  const auto shape = a.source.implicit_shape();
  IIParams ii;
  ii.k = a.radius;
  ii.alpha = a.alpha;
  Eigen::MatrixX3d n = estimate_face_normals(est, mesh, need_voxels ? &grid : nullptr, shape ? &*shape : nullptr,
                                             ii, stderr_progress("ii normals"));
  if (a.at == "vertices") n = vertex_normals_from_face_normals(n, mesh.faces, mesh.num_vertices());
  write_normals(a.out, n);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::cerr << a.estimator << " normals of " << a.source.describe() << ": " << n.rows() << " " << a.at << " -> "
            << a.out << " (" << secs << " s)\n";
}

RegisterCommand reg(30, "normals", [](CLI::App& app) {
  auto args = std::make_shared<NormalsArgs>();
  auto* cmd = app.add_subcommand("normals", "estimate normals: one 'nx ny nz' per face (digitize order) or per vertex");
  args->source.add_options(*cmd, /*with_mesh=*/true);
  cmd->add_option("--estimator", args->estimator, "ii (integral invariant, spec 7), true (implicit shapes), trivial")
      ->check(CLI::IsMember({"ii", "true", "trivial"}));
  cmd->add_option("--radius", args->radius, "II: r-radius k, Euclidean radius k*h^alpha (default 3)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--alpha", args->alpha, "II: exponent alpha (default 0.33 as the reference; the paper uses 1/3)");
  cmd->add_option("--at", args->at, "faces (default) or vertices (normalized sum of incident face normals)")
      ->check(CLI::IsMember({"faces", "vertices"}));
  cmd->add_option("--out", args->out, "output text file")->required();
  cmd->callback([args] { run(*args); });
});

}  // namespace
}  // namespace corrlap::cli
