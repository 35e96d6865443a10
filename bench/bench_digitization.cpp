// Digitization + surface extraction throughput (surfels/s) on sphere1, box -1.5..1.5.
// Goal: h = 0.0025 (~3M surfels) under 2 s on 2 cores.
//
//   ./build/bench/bench_digitization                       # all benchmarks
//   ./build/bench/bench_digitization --benchmark_filter=BM_digitize_and_extract
//   ./build/bench/bench_digitization --phases              # per-phase breakdown table only
//
// BM_digitize_and_extract is the goal metric (digitize + extract_surface, exact DGtal numbering).
// BM_digitize, BM_extract and BM_build_edges time the single steps; the phase counters of
// BM_extract (ms) split extract_surface into its internal phases.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <corrlap/core/mesh_topology.hpp>
#include <corrlap/core/stopwatch.hpp>
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <corrlap/surface/implicit_shape.hpp>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "support.hpp"

using namespace corrlap;

namespace {
DigitizationParams sphere_params(double h) {
  DigitizationParams p;
  p.h = h;
  p.min_aabb = -1.5;
  p.max_aabb = 1.5;
  return p;
}
const ImplicitShape& sphere() {
  static const ImplicitShape s = make_implicit_shape("sphere1");
  return s;
}
// CPU seconds of all threads of the process: on a shared machine this shows the work done even
// when wall-clock time is inflated by other processes.
double process_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}
}  // namespace

static void BM_digitize_and_extract(benchmark::State& state) {
  const DigitizationParams p = sphere_params(1.0 / double(state.range(0)));
  bench::reset_peak_rss();
  std::size_t surfels = 0;
  for (auto _ : state) {
    const SurfelMesh m = extract_surface(digitize(sphere(), p));
    surfels = std::size_t(m.num_faces());
    benchmark::DoNotOptimize(m.positions.data());
  }
  state.counters["h"] = p.h;
  state.counters["surfels"] = double(surfels);
  state.counters["surfels_per_s"] = benchmark::Counter(double(surfels), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["peak_rss_MiB"] = bench::peak_rss_mib();
}
// h = 1/50, 1/100, 1/200, 1/400
BENCHMARK(BM_digitize_and_extract)->Arg(50)->Arg(100)->Arg(200)->Arg(400)->Unit(benchmark::kMillisecond)->UseRealTime();

static void BM_digitize(benchmark::State& state) {
  const DigitizationParams p = sphere_params(1.0 / double(state.range(0)));
  for (auto _ : state) {
    const VoxelGrid g = digitize(sphere(), p);
    benchmark::DoNotOptimize(g.row(g.lower().y(), g.lower().z()));
  }
}
BENCHMARK(BM_digitize)->Arg(100)->Arg(400)->Unit(benchmark::kMillisecond)->UseRealTime();

static void BM_extract(benchmark::State& state) {
  const VoxelGrid g = digitize(sphere(), sphere_params(1.0 / double(state.range(0))));
  std::map<std::string, double> total;
  for (auto _ : state) {
    PhaseTimings t;
    const SurfelMesh m = extract_surface(g, &t);
    benchmark::DoNotOptimize(m.positions.data());
    for (const auto& ph : t.phases) total[ph.name] += ph.wall_seconds;
  }
  for (const auto& [name, s] : total)
    state.counters[name + "_ms"] = benchmark::Counter(1e3 * s / double(state.iterations()));
}
BENCHMARK(BM_extract)->Arg(100)->Arg(400)->Unit(benchmark::kMillisecond)->UseRealTime();

static void BM_build_edges(benchmark::State& state) {
  const SurfelMesh m = extract_surface(digitize(sphere(), sphere_params(1.0 / double(state.range(0)))));
  for (auto _ : state) {
    const EdgeTopology t = build_edges(m);
    benchmark::DoNotOptimize(t.edges.data());
  }
  state.counters["faces"] = double(m.num_faces());
}
BENCHMARK(BM_build_edges)->Arg(100)->Arg(400)->Unit(benchmark::kMillisecond)->UseRealTime();

// --phases [REPS]: per h, every step and every phase of extract_surface in execution order, the
// minimum over REPS runs (default 3) of wall and process CPU milliseconds, plus peak memory.
static int print_phases(int reps) {
  std::printf("%-8s %-20s %10s %10s   (min of %d runs)\n", "h", "phase", "wall ms", "cpu ms", reps);
  for (int inv : {50, 100, 200, 400}) {
    const DigitizationParams p = sphere_params(1.0 / inv);
    std::vector<std::pair<std::string, std::pair<double, double>>> rows;  // name -> (wall, cpu)
    auto record = [&](std::size_t& slot, const std::string& name, double wall, double cpu) {
      if (slot == rows.size()) rows.push_back({name, {wall, cpu}});
      auto& r = rows[slot++].second;
      r.first = std::min(r.first, wall);
      r.second = std::min(r.second, cpu);
    };
    int faces = 0, edges = 0;
    for (int rep = 0; rep < reps; ++rep) {
      std::size_t slot = 0;
      Stopwatch wall;
      const Stopwatch total;
      double c0 = process_cpu_seconds();
      const double total_c0 = c0;
      auto step = [&](const std::string& name) {
        record(slot, name, 1e3 * wall.lap(), 1e3 * (process_cpu_seconds() - c0));
        c0 = process_cpu_seconds();
      };
      const VoxelGrid g = digitize(sphere(), p);
      step("digitize");
      PhaseTimings t;
      const SurfelMesh m = extract_surface(g, &t);
      const double wall_extract = 1e3 * wall.elapsed();
      for (const auto& ph : t.phases) record(slot, "  " + ph.name, 1e3 * ph.wall_seconds, 1e3 * ph.cpu_seconds);
      record(slot, "extract_surface", wall_extract, 1e3 * (process_cpu_seconds() - c0));
      record(slot, "= digitize+extract", 1e3 * total.elapsed(), 1e3 * (process_cpu_seconds() - total_c0));
      wall.restart();
      c0 = process_cpu_seconds();
      const EdgeTopology e = build_edges(m);
      step("build_edges");
      faces = m.num_faces();
      edges = e.num_edges();
    }
    for (const auto& [name, wc] : rows) {
      std::printf("%-8g %-20s %10.1f %10.1f\n", p.h, name.c_str(), wc.first, wc.second);
    }
    std::printf("%-8g %d faces, %d edges, peak RSS so far %.0f MiB\n", p.h, faces, edges, bench::peak_rss_mib());
  }
  return 0;
}

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i)
    if (std::strcmp(argv[i], "--phases") == 0)
      return print_phases(i + 1 < argc ? std::max(1, std::atoi(argv[i + 1])) : 3);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
