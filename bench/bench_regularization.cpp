// The two slow stages of `corrlap regularize` on large surfaces (goal: a 256^3 model in under 10 s,
// 512^3 in under 60 s), each against the readable function it equals:
//  - curvature: CorrectedCurvature::at_vertices (every measure, principal directions) against
//    mean_curvature_at_vertices (H alone, the faster walk), ball radius 0.1 size;
//  - solve: regularize_positions (Cholesky of L M_l^{-1} L + alpha M_l) against
//    regularize_positions_preconditioned (CG preconditioned by a factorization of sqrt(alpha) M_l - L).
// Surface: goursat (it spans [-9.7, 9.7]) digitized at h = range(0) / 1000, II normals, corrected
// FEM, alpha0 = 10: h = 0.105 gives ~210 K vertices (the bunny at 256^3), h = 0.0525 ~850 K (512^3).
//
//   ./build/bench/bench_regularization --benchmark_filter='solve.*/105'
#include <benchmark/benchmark.h>

#include <corrlap/corrlap.hpp>
#include <map>
#include <memory>

#include "support.hpp"

using namespace corrlap;

namespace {
struct Case {
  SurfelMesh mesh;
  NormalFields normals;
  Operators ops;
  double size = 1.0, h = 1.0;
  Eigen::VectorXd H;
};

const Case& regularization_case(int h_thousandths) {
  static std::map<int, std::unique_ptr<Case>> cache;
  auto& slot = cache[h_thousandths];
  if (slot) return *slot;
  slot = std::make_unique<Case>();
  Case& c = *slot;
  const ImplicitShape shape = make_implicit_shape("goursat");
  const double h = h_thousandths / 1000.0;
  const VoxelGrid grid = digitize(shape, {.h = h, .min_aabb = -10.0, .max_aabb = 10.0});
  c.mesh = extract_surface(grid);
  NormalRequest request;
  request.source = NormalSource::II;
  c.normals = resolve_normals(c.mesh, NormalKind::Vertex, request, &shape, &grid);
  c.ops = make_discretization("fem")->assemble(c.mesh, c.normals, Config());
  c.size = regularization_size(c.mesh);
  c.h = c.mesh.grid_step();
  c.H = CorrectedCurvature::interpolated(c.mesh, c.normals.vertex).mean_curvature_at_vertices(0.1 * c.size).H;
  return c;
}
}  // namespace

static void BM_curvature_full(benchmark::State& state) {
  const Case& c = regularization_case(int(state.range(0)));
  const CorrectedCurvature cc = CorrectedCurvature::interpolated(c.mesh, c.normals.vertex);
  for (auto _ : state) benchmark::DoNotOptimize(cc.at_vertices(0.1 * c.size).H.sum());
  state.counters["vertices"] = double(c.mesh.num_vertices());
}
BENCHMARK(BM_curvature_full)->Name("curvature/at_vertices")->Arg(105)->Arg(52)->Unit(benchmark::kSecond);

static void BM_curvature_mean(benchmark::State& state) {
  const Case& c = regularization_case(int(state.range(0)));
  const CorrectedCurvature cc = CorrectedCurvature::interpolated(c.mesh, c.normals.vertex);
  for (auto _ : state) benchmark::DoNotOptimize(cc.mean_curvature_at_vertices(0.1 * c.size).H.sum());
  state.counters["vertices"] = double(c.mesh.num_vertices());
}
BENCHMARK(BM_curvature_mean)->Name("curvature/mean_curvature_at_vertices")->Arg(105)->Arg(52)->Unit(benchmark::kSecond);

static void BM_solve_direct(benchmark::State& state) {
  const Case& c = regularization_case(int(state.range(0)));
  const double alpha = regularization_alpha(c.h * c.size, 10.0);
  bench::reset_peak_rss();
  for (auto _ : state) {
    auto solver = make_linear_solver("cholmod");
    benchmark::DoNotOptimize(
        regularize_positions(c.ops.L, c.ops.M, c.mesh.positions, c.normals.vertex, c.H, alpha, *solver).sum());
  }
  state.counters["vertices"] = double(c.mesh.num_vertices());
  state.counters["peak_rss_MiB"] = bench::peak_rss_mib();
}
BENCHMARK(BM_solve_direct)->Name("solve/direct")->Arg(105)->Arg(52)->Unit(benchmark::kSecond);

static void BM_solve_preconditioned(benchmark::State& state) {
  const Case& c = regularization_case(int(state.range(0)));
  const double alpha = regularization_alpha(c.h * c.size, 10.0);
  bench::reset_peak_rss();
  SolverReport report;
  for (auto _ : state) {
    auto solver = make_linear_solver("cholmod");
    benchmark::DoNotOptimize(regularize_positions_preconditioned(c.ops.L, c.ops.M, c.mesh.positions, c.normals.vertex,
                                                                 c.H, alpha, *solver, &report)
                                 .sum());
  }
  state.counters["vertices"] = double(c.mesh.num_vertices());
  state.counters["iterations"] = report.iterations;
  state.counters["peak_rss_MiB"] = bench::peak_rss_mib();
}
BENCHMARK(BM_solve_preconditioned)->Name("solve/preconditioned")->Arg(105)->Arg(52)->Unit(benchmark::kSecond);

BENCHMARK_MAIN();
