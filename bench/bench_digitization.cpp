// Digitization + surface extraction throughput (surfels/s) on sphere1, box -1.5..1.5.
// Goal (issue 2): h = 0.0025 (~3M surfels) under 2 s on 2 cores.
#include <benchmark/benchmark.h>

#include <corrlap/core/implicit_shape.hpp>
#include <corrlap/core/surfel_mesh.hpp>

#include "support.hpp"

using namespace corrlap;

static void BM_digitize_and_extract(benchmark::State& state) {
  const double h = 1.0 / double(state.range(0));
  DigitizationParams p;
  p.h = h;
  p.min_aabb = -1.5;
  p.max_aabb = 1.5;
  const ImplicitShape sphere = make_implicit_shape("sphere1");
  bench::reset_peak_rss();
  std::size_t surfels = 0;
  for (auto _ : state) {
    const SurfelMesh m = extract_surface(digitize(sphere, p));
    surfels = std::size_t(m.num_faces());
    benchmark::DoNotOptimize(m.positions.data());
  }
  state.counters["h"] = h;
  state.counters["surfels"] = double(surfels);
  state.counters["surfels_per_s"] = benchmark::Counter(double(surfels), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["peak_rss_MiB"] = bench::peak_rss_mib();
}
// h = 1/50, 1/100, 1/200, 1/400
BENCHMARK(BM_digitize_and_extract)->Arg(50)->Arg(100)->Arg(200)->Arg(400)->Unit(benchmark::kMillisecond)->UseRealTime();

BENCHMARK_MAIN();
