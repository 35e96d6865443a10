// corrlap demo: the main job on a built-in example. It grows with every capability.
#include <chrono>
#include <cmath>
#include <cstdio>

#include <corrlap/core/implicit_shape.hpp>
#include <corrlap/core/mesh_topology.hpp>

#include "command.hpp"

namespace corrlap::cli {
namespace {

void digitization_table() {
  std::printf("== 1. Digitization of the unit sphere (spec §1): the digital area does not converge to 4*pi\n");
  std::printf("%8s %10s %10s %10s %6s %12s %10s %10s\n", "h", "vertices", "edges", "faces", "euler", "area F*h^2",
              "area/4pi", "time_s");
  const ImplicitShape sphere = make_implicit_shape("sphere1");
  for (double h : {0.2, 0.1, 0.05}) {
    const auto t0 = std::chrono::steady_clock::now();
    DigitizationParams p;
    p.h = h;
    p.min_aabb = -2;
    p.max_aabb = 2;
    const SurfelMesh mesh = extract_surface(digitize(sphere, p));
    const MeshInfo info = compute_mesh_info(mesh);
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("%8.3f %10d %10d %10d %6d %12.6f %10.6f %10.4f\n", h, info.vertices, info.edges, info.faces,
                info.euler, info.area, info.area / (4 * M_PI), t);
  }
  std::printf("\n");
}

RegisterCommand reg(0, "demo", [](CLI::App& app) {
  auto* cmd = app.add_subcommand("demo", "run the main job on a built-in example (sphere1)");
  cmd->callback([] { digitization_table(); });
});

}  // namespace
}  // namespace corrlap::cli
