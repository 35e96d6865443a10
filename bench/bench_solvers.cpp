// Linear solver backends on sphere1 operators: analyze / factorize / solve per backend,
// refactorization (analysis reused) vs full factorization, CG iterations, and the 49 smallest
// eigenpairs by shift-invert. System: M - dt L with dt = 0.035 h (docs/math.md §10.3, SPD).
// Operators: corrected FEM (9-point stencil) and interpolated corrected calculus (21-point stencil),
// true normals. Goals: CHOLMOD >= 3x faster than eigen-ldlt in factorization at the largest size;
// refactorization >= 1.5x faster than analyze + factorize; our CHOLMOD wrapper within 10% of
// calling CHOLMOD directly ("cholmod-direct": the same settings through the C API).
//   bench_solvers                      all sizes up to h = 0.005
//   CORRLAP_BENCH_FINEST=1 bench_solvers --benchmark_filter='h=0.0025'   the 3M-unknown case
#include <benchmark/benchmark.h>
#include <cholmod.h>

#include <corrlap/backends/registry.hpp>
#include <corrlap/backends/spectra_eigs.hpp>
#include <corrlap/core/normal_fields.hpp>
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/discretizations/registry.hpp>
#include <corrlap/estimators/implicit_normals.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <corrlap/surface/implicit_shape.hpp>
#include <cstdlib>
#include <map>
#include <memory>
#include <mutex>

#include "support.hpp"

using namespace corrlap;
using SpMat = Eigen::SparseMatrix<double>;

namespace {

struct Problem {
  SpMat L, M, A;  // A = M - dt L
  double h = 0;
  std::string method;
};

const Problem& problem(const std::string& method, double h) {
  static std::map<std::pair<std::string, double>, std::unique_ptr<Problem>> cache;
  static std::mutex mutex;
  std::lock_guard<std::mutex> lock(mutex);
  auto& p = cache[{method, h}];
  if (p) return *p;
  p = std::make_unique<Problem>();
  DigitizationParams d;
  d.h = h;
  d.min_aabb = -2;
  d.max_aabb = 2;
  const ImplicitShape shape = make_implicit_shape("sphere1");
  const SurfelMesh mesh = extract_surface(digitize(shape, d));
  NormalFields normals;
  normals.face = true_face_normals(shape, mesh);
  normals.vertex = vertex_normals_from_face_normals(normals.face, mesh.faces, mesh.num_vertices());
  const Operators ops = make_discretization(method)->assemble(mesh, normals, Config{});
  p->L = ops.L;
  p->M = ops.M;
  p->method = method;
  p->A = p->M - 0.035 * h * p->L;
  p->A.makeCompressed();
  p->h = h;
  return *p;
}

const std::vector<std::pair<std::string, std::vector<std::string>>> kBackends = {
    {"eigen-ldlt", {"solver=eigen-ldlt"}},
    {"eigen-llt", {"solver=eigen-llt"}},
    {"cholmod-amd", {"solver=cholmod", "ordering=amd"}},
    {"cholmod-metis", {"solver=cholmod", "ordering=metis"}},
    // Same without the O(nnz) input checks (symmetry): the wrapper's own overhead.
    {"cholmod-metis-nocheck", {"solver=cholmod", "ordering=metis", "check_symmetry=false"}},
    {"cholmod-simplicial", {"solver=cholmod", "supernodal=simplicial"}},
    {"cholmod-serial-omp", {"solver=cholmod", "openmp_threads=1"}},
    {"cg-jacobi", {"solver=cg", "preconditioner=jacobi", "tolerance=1e-10"}},
    {"cg-ichol", {"solver=cg", "preconditioner=ichol", "tolerance=1e-10"}},
};

std::unique_ptr<LinearSolver> make(std::size_t b) {
  return make_linear_solver(Config::from_key_values(kBackends[b].second));
}

void counters(benchmark::State& state, const Problem& p) {
  state.counters["n"] = double(p.A.rows());
  state.counters["h"] = p.h;
  state.counters["peak_rss_MiB"] = bench::peak_rss_mib();
  // The CSV reporter needs the same counters in every run.
  for (const char* c : {"iterations", "restarts", "mu_1", "mu_48"})
    if (!state.counters.count(c)) state.counters[c] = 0;
}

void analyze(benchmark::State& state, std::size_t b, const std::string& method, double h) {
  const Problem& p = problem(method, h);
  auto s = make(b);
  for (auto _ : state) s->analyze(p.A);
  counters(state, p);
}

// Full factorization: symbolic analysis + numeric factorization.
void compute(benchmark::State& state, std::size_t b, const std::string& method, double h) {
  const Problem& p = problem(method, h);
  bench::reset_peak_rss();
  for (auto _ : state) {
    auto s = make(b);
    s->compute(p.A);
  }
  counters(state, p);
}

// Refactorization with new values on the analyzed pattern (e.g. a new dt).
void refactorize(benchmark::State& state, std::size_t b, const std::string& method, double h) {
  const Problem& p = problem(method, h);
  auto s = make(b);
  s->analyze(p.A);
  SpMat A2 = p.M - 0.07 * h * p.L;
  A2.makeCompressed();
  int i = 0;
  for (auto _ : state) s->factorize(++i % 2 ? A2 : p.A);
  counters(state, p);
}

void solve(benchmark::State& state, std::size_t b, const std::string& method, double h) {
  const Problem& p = problem(method, h);
  auto s = make(b);
  s->compute(p.A);
  // A smooth non-trivial right-hand side (A 1 = M 1 would make 1 the exact solution).
  const Eigen::VectorXd rhs = p.M * Eigen::VectorXd::LinSpaced(p.A.rows(), -1.0, 1.0).array().sin().matrix();
  for (auto _ : state) benchmark::DoNotOptimize(s->solve(rhs).data());
  state.counters["iterations"] = s->info().iterations;
  counters(state, p);
}

void eigs49(benchmark::State& state, const std::string& solver, const std::string& method, double h) {
  const Problem& p = problem(method, h);
  ShiftInvertEigenSolver e;
  e.configure(Config::from_key_values({"solver=" + solver}));
  EigenResult r;
  for (auto _ : state) r = e.solve(p.L, p.M, 49);
  state.counters["restarts"] = r.iterations;
  state.counters["mu_1"] = r.values[1];    // ~2 (l = 1) for corrected operators
  state.counters["mu_48"] = r.values[48];  // ~42 (l = 6) for corrected operators
  counters(state, p);
}

// The same full factorization as "cholmod-amd" (supernodal, AMD, postordered, lower triangle)
// through CHOLMOD's C API directly: the baseline for the wrapper's overhead.
void cholmod_direct(benchmark::State& state, const std::string& method, double h) {
  const Problem& p = problem(method, h);
  SpMat lower = p.A.triangularView<Eigen::Lower>();
  lower.makeCompressed();
  cholmod_common c;
  cholmod_start(&c);
  c.supernodal = CHOLMOD_SUPERNODAL;
  c.nmethods = 1;
  c.method[0].ordering = CHOLMOD_AMD;
  c.postorder = 1;
  cholmod_sparse a{};
  a.nrow = a.ncol = std::size_t(lower.rows());
  a.nzmax = std::size_t(lower.nonZeros());
  a.p = lower.outerIndexPtr();
  a.i = lower.innerIndexPtr();
  a.x = lower.valuePtr();
  a.stype = -1;
  a.itype = CHOLMOD_INT;
  a.xtype = CHOLMOD_REAL;
  a.dtype = CHOLMOD_DOUBLE;
  a.sorted = 1;
  a.packed = 1;
  for (auto _ : state) {
    cholmod_factor* L = cholmod_analyze(&a, &c);
    cholmod_factorize(&a, L, &c);
    if (c.status != CHOLMOD_OK) state.SkipWithError("cholmod_factorize failed");
    cholmod_free_factor(&L, &c);
  }
  cholmod_finish(&c);
  counters(state, p);
}

}  // namespace

int main(int argc, char** argv) {
  const bool finest = std::getenv("CORRLAP_BENCH_FINEST") != nullptr;
  std::vector<double> hs = {0.02, 0.01, 0.005};
  if (finest) hs = {0.0025};
  for (const std::string method : {"fem", "interpolated"})
    for (double h : hs) {
      const std::string htag = "h=" + std::to_string(h).substr(0, 6);
      for (std::size_t b = 0; b < kBackends.size(); ++b) {
        const std::string& name = kBackends[b].first;
        const bool slow =
            name == "eigen-llt" || name == "cholmod-simplicial" || name == "cholmod-serial-omp" || name == "cg-jacobi";
        if (h < 0.009 && slow) continue;  // keep the run short: one Eigen and the main CHOLMOD variants
        const std::string tag = method + "/" + name + "/" + htag;
        const bool iterative = name.rfind("cg", 0) == 0;
        if (!iterative) {
          benchmark::RegisterBenchmark(("analyze/" + tag).c_str(), analyze, b, method, h)
              ->Unit(benchmark::kMillisecond)
              ->UseRealTime();
          benchmark::RegisterBenchmark(("compute/" + tag).c_str(), compute, b, method, h)
              ->Unit(benchmark::kMillisecond)
              ->UseRealTime();
          benchmark::RegisterBenchmark(("refactorize/" + tag).c_str(), refactorize, b, method, h)
              ->Unit(benchmark::kMillisecond)
              ->UseRealTime();
        }
        benchmark::RegisterBenchmark(("solve/" + tag).c_str(), solve, b, method, h)
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime();
      }
      benchmark::RegisterBenchmark(("compute/" + method + "/cholmod-direct/" + htag).c_str(), cholmod_direct, method, h)
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime();
    }
  if (!finest)
    for (const std::string method : {"fem", "interpolated"})
      for (double h : {0.02, 0.01})
        benchmark::RegisterBenchmark(("eigs49/" + method + "/cholmod/h=" + std::to_string(h).substr(0, 6)).c_str(),
                                     eigs49, std::string("cholmod"), method, h)
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime()
            ->Iterations(1);
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
}
