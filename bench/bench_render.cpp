// Rendering speed of render_mesh (goal: a million faces in about a second) on digitized
// sphere1 surfaces, 800 x 800 with 2 x 2 supersampling, grey and coloured by a vertex scalar.
//
//   ./build/bench/bench_render
#include <benchmark/benchmark.h>

#include <corrlap/core/polygon_mesh.hpp>
#include <corrlap/render/render_mesh.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <corrlap/surface/implicit_shape.hpp>
#include <map>

using namespace corrlap;

namespace {
const PolygonMesh& sphere_surface(double h) {
  static std::map<double, PolygonMesh> cache;
  auto it = cache.find(h);
  if (it != cache.end()) return it->second;
  DigitizationParams p;
  p.h = h;
  p.min_aabb = -1.5;
  p.max_aabb = 1.5;
  return cache[h] = to_polygon_mesh(extract_surface(digitize(make_implicit_shape("sphere1"), p)));
}
}  // namespace

// range(0): 1 / h; range(1): 1 = coloured by the height z.
static void BM_render_sphere(benchmark::State& state) {
  const PolygonMesh& mesh = sphere_surface(1.0 / double(state.range(0)));
  const ScalarField z{"z", mesh.positions.col(2), false};
  const bool coloured = state.range(1) != 0;
  for (auto _ : state) benchmark::DoNotOptimize(render_mesh(mesh, coloured ? &z : nullptr).rgb.data());
  state.counters["faces"] = double(mesh.faces.size());
  state.counters["Mfaces_per_s"] =
      benchmark::Counter(double(mesh.faces.size()) * 1e-6, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_render_sphere)->Args({50, 0})->Args({250, 0})->Args({250, 1})->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
