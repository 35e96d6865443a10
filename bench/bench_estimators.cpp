// Estimators: II normals (docs/math.md §7) time and peak memory on sphere1, box -1.5..1.5, and corrected
// curvature measures (docs/math.md §8) time. Goals (2 cores): II h = 0.025 < 1.5 s,
// h = 0.0125 < 15 s, h = 0.008 < 60 s, h = 0.004 < 10 min and < 16 GiB.
// The grid and the mesh are built outside the timed loop; only the estimator is timed.
// Run one size: ./bench_estimators --benchmark_filter='BM_ii_normals/125'
#include <benchmark/benchmark.h>

#include <corrlap/core/normal_fields.hpp>
#include <corrlap/estimators/corrected_curvature.hpp>
#include <corrlap/estimators/integral_invariant.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <corrlap/surface/implicit_shape.hpp>

#include "support.hpp"

using namespace corrlap;

namespace {
struct Digital {
  VoxelGrid grid;
  SurfelMesh mesh;
};
Digital sphere(double h) {
  DigitizationParams p;
  p.h = h;
  p.min_aabb = -1.5;
  p.max_aabb = 1.5;
  Digital d;
  d.grid = digitize(make_implicit_shape("sphere1"), p);
  d.mesh = extract_surface(d.grid);
  return d;
}
}  // namespace

// Argument: 1/h (h = 0.05, 0.025, 0.0125, 0.008, 0.004).
static void BM_ii_normals(benchmark::State& state) {
  const double h = 1.0 / double(state.range(0));
  const Digital d = sphere(h);
  bench::reset_peak_rss();
  for (auto _ : state) {
    const Eigen::MatrixX3d n = ii_face_normals(d.grid, d.mesh);
    benchmark::DoNotOptimize(n.data());
  }
  state.counters["h"] = h;
  state.counters["faces"] = double(d.mesh.num_faces());
  state.counters["r_digital"] = ii_digital_radius(h, {});
  state.counters["peak_rss_MiB"] = bench::peak_rss_mib();
}
BENCHMARK(BM_ii_normals)
    ->Arg(20)
    ->Arg(40)
    ->Arg(80)
    ->Arg(125)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
// h = 0.004 is long (minutes): run it explicitly with --benchmark_filter='BM_ii_normals_finest'.
static void BM_ii_normals_finest(benchmark::State& state) { BM_ii_normals(state); }
BENCHMARK(BM_ii_normals_finest)->Arg(250)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

// Corrected curvature measures with radial vertex normals: per-face measures + balls of radius
// 0.1 at every face centroid (H, G, k1, k2, directions).
static void BM_curvature_faces_r01(benchmark::State& state) {
  const double h = 1.0 / double(state.range(0));
  const Digital d = sphere(h);
  const Eigen::MatrixX3d vn = d.mesh.positions.rowwise().normalized();
  for (auto _ : state) {
    const CorrectedCurvature cc = CorrectedCurvature::interpolated(d.mesh, vn);
    const CurvatureEstimates e = cc.at_faces(0.1);
    benchmark::DoNotOptimize(e.H.data());
  }
  state.counters["h"] = h;
  state.counters["faces"] = double(d.mesh.num_faces());
  state.counters["peak_rss_MiB"] = bench::peak_rss_mib();
}
BENCHMARK(BM_curvature_faces_r01)->Arg(20)->Arg(40)->Arg(80)->Unit(benchmark::kMillisecond)->UseRealTime();

BENCHMARK_MAIN();
