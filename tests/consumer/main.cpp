// A program that embeds corrlap through its installed CMake package.
#include <corrlap/core/implicit_shape.hpp>
#include <corrlap/core/mesh_topology.hpp>

#include <cstdio>

int main() {
  corrlap::DigitizationParams p;
  p.h = 0.25;
  const auto mesh = corrlap::extract_surface(corrlap::digitize(corrlap::make_implicit_shape("sphere1"), p));
  const auto info = corrlap::compute_mesh_info(mesh);
  std::printf("V=%d F=%d E=%d\n", info.vertices, info.faces, info.edges);
  // spec §12.1: sphere1 at h = 0.25 has V = 296, F = 294, E = 588
  return (info.vertices == 296 && info.faces == 294 && info.edges == 588) ? 0 : 1;
}
