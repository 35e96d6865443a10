// Stress test (ctest label "stress"): 12 concurrent TBB tasks, 60 rounds each, every round
// assembling an operator with the parallel assembly plan and refactorizing/solving it with every
// backend. Direct solvers must reproduce the serial results bitwise, CG to its tolerance.
// Run it under ThreadSanitizer with `make test-tsan` (docs/backends.md; tests/stress/concurrently.hpp).
#define DOCTEST_CONFIG_IMPLEMENT_WITH_MAIN
#include <doctest/doctest.h>

#include <atomic>
#include <cmath>
#include <corrlap/backends/registry.hpp>
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/discretizations/assembly/parallel_assembly.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <corrlap/surface/implicit_shape.hpp>
#include <mutex>
#include <string>
#include <vector>

#include "stress/concurrently.hpp"

using namespace corrlap;
using SpMat = Eigen::SparseMatrix<double>;

namespace {

constexpr int kTasks = 12;
constexpr int kRounds = 60;
constexpr int kSystems = 7;  // distinct systems (same pattern), cycled through by the tasks

// OpenBLAS's results depend on its thread count in the last bits: CHOLMOD runs pin it to one
// thread so that the serial references and the concurrent runs use the same BLAS.
const std::vector<std::vector<std::string>> kBackends = {
    {"solver=eigen-ldlt"},
    {"solver=eigen-llt"},
    {"solver=cholmod", "blas_threads=1"},
    {"solver=cholmod", "supernodal=simplicial", "ordering=metis", "blas_threads=1"},
    {"solver=cholmod", "openmp_threads=1", "ordering=nesdis", "blas_threads=1"},
    {"solver=cg", "preconditioner=ichol", "tolerance=1e-12"},
};
bool is_cg(std::size_t b) { return b + 1 == kBackends.size(); }

struct Fixture {
  SurfelMesh mesh;
  AssemblyPlan plan;
  Fixture() {
    DigitizationParams p;
    p.h = 0.15;
    p.min_aabb = -2;
    p.max_aabb = 2;
    mesh = extract_surface(digitize(make_implicit_shape("sphere1"), p));
    plan = AssemblyPlan(mesh.faces.data(), std::size_t(mesh.num_faces()), 4, mesh.num_vertices());
  }
  /// System s: sum_f w_f(s) K_f + c(s) M_f (docs/math.md §4.5 flat stiffness, §4.4 mass), SPD, same pattern
  /// for every s; the face weights make the systems genuinely different.
  SpMat system(int s) const {
    const double K[16] = {4, -1, -2, -1, -1, 4, -1, -2, -2, -1, 4, -1, -1, -2, -1, 4};
    const double Mm[16] = {4, 2, 1, 2, 2, 4, 2, 1, 1, 2, 4, 2, 2, 1, 2, 4};
    const double h2 = mesh.h * mesh.h, c = 0.05 + 0.3 * s;
    return assemble(plan, [&](std::size_t begin, std::size_t end, double* locals) {
      for (std::size_t f = begin; f < end; ++f) {
        const double w = 1.0 + 0.5 * std::sin(0.37 * double(f) + s);
        for (int k = 0; k < 16; ++k) locals[16 * (f - begin) + k] = w * K[k] / 6.0 + c * h2 * Mm[k] / 36.0;
      }
    });
  }
  Eigen::VectorXd rhs(int s) const {
    return (mesh.positions.col(0).array() * (1.0 + s) + mesh.positions.col(2).array().square()).matrix();
  }
};

std::unique_ptr<LinearSolver> make(std::size_t b) { return make_linear_solver(Config::from_key_values(kBackends[b])); }

}  // namespace

TEST_CASE("concurrent assembly + factorization + solves equal the serial results") {
  const Fixture fx;
  const Eigen::Index n = fx.mesh.num_vertices();
  REQUIRE(n > 700);

  // Serial references.
  std::vector<std::vector<Eigen::VectorXd>> ref(kBackends.size(), std::vector<Eigen::VectorXd>(kSystems));
  std::vector<SpMat> systems;
  for (int s = 0; s < kSystems; ++s) systems.push_back(fx.system(s));
  for (std::size_t b = 0; b < kBackends.size(); ++b)
    for (int s = 0; s < kSystems; ++s) {
      auto solver = make(b);
      solver->compute(systems[std::size_t(s)]);
      ref[b][std::size_t(s)] = solver->solve(fx.rhs(s));
    }

  std::atomic<int> solves{0}, assembly_mismatch{0}, direct_mismatch{0}, cg_off{0}, errors{0};
  std::mutex message_mutex;
  std::string first_error;
  // kTasks really at once (TBB's default cap is the core count; concurrently() lifts it).
  std::atomic<int> running{0}, max_running{0};
  {
    test::concurrently(kTasks, kTasks, [&](int t) {
      const int now = ++running;
      for (int m = max_running.load(); now > m && !max_running.compare_exchange_weak(m, now);) {
      }
      try {
        // Each task keeps one solver per backend and refactorizes it (same pattern) every round;
        // every 10th round the solvers are recreated (construction/destruction under load).
        std::vector<std::unique_ptr<LinearSolver>> solvers(kBackends.size());
        for (int r = 0; r < kRounds; ++r) {
          const int s = (t + r) % kSystems;
          const SpMat A = fx.system(s);  // nested TBB assembly inside the task
          if (A.nonZeros() != systems[std::size_t(s)].nonZeros() ||
              !std::equal(A.valuePtr(), A.valuePtr() + A.nonZeros(), systems[std::size_t(s)].valuePtr()))
            ++assembly_mismatch;
          const Eigen::VectorXd b = fx.rhs(s);
          for (std::size_t k = 0; k < kBackends.size(); ++k) {
            if (!solvers[k] || r % 10 == 0) {
              solvers[k] = make(k);
              solvers[k]->analyze(A);
            }
            solvers[k]->factorize(A);
            const Eigen::VectorXd x = solvers[k]->solve(b);
            ++solves;
            const Eigen::VectorXd& xr = ref[k][std::size_t(s)];
            if (is_cg(k)) {
              if ((x - xr).norm() > 1e-8 * xr.norm()) ++cg_off;
            } else if (!std::equal(x.data(), x.data() + n, xr.data())) {
              ++direct_mismatch;
            }
          }
        }
      } catch (const std::exception& e) {
        ++errors;
        std::lock_guard<std::mutex> lock(message_mutex);
        if (first_error.empty()) first_error = e.what();
      }
      --running;
    });
  }
  INFO("first error: " << first_error);
  MESSAGE("tasks running at once (max): " << max_running.load());
  CHECK(max_running.load() >= 8);
  CHECK(errors.load() == 0);
  CHECK(solves.load() == kTasks * kRounds * int(kBackends.size()));
  CHECK(assembly_mismatch.load() == 0);
  CHECK(direct_mismatch.load() == 0);
  CHECK(cg_off.load() == 0);
}
