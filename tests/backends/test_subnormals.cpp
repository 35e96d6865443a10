// Subnormal numbers flushed to zero (core/threads.hpp flush_subnormals_in_process, and the CHOLMOD
// factorization's own scope): the flags are set where they should be and only there, and BLAS
// still computes the same solutions after its worker threads restart.
#include <doctest/doctest.h>

#include <corrlap/backends/registry.hpp>
#include <corrlap/core/threads.hpp>
#include <vector>
#if defined(__x86_64__) || defined(__SSE2__)
#include <xmmintrin.h>
#endif

using namespace corrlap;

namespace {

// The shifted 2D grid Laplacian shift I - L on k x k points: SPD, with a supernodal factor whose
// dense blocks go through BLAS.
Eigen::SparseMatrix<double> shifted_grid(int k, double shift) {
  std::vector<Eigen::Triplet<double>> t;
  const auto id = [k](int i, int j) { return i * k + j; };
  for (int i = 0; i < k; ++i)
    for (int j = 0; j < k; ++j) {
      double diagonal = shift;
      for (const auto& [di, dj] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
        const int a = i + di, b = j + dj;
        if (a < 0 || b < 0 || a >= k || b >= k) continue;
        t.emplace_back(id(i, j), id(a, b), -1.0);
        diagonal += 1.0;
      }
      t.emplace_back(id(i, j), id(i, j), diagonal);
    }
  Eigen::SparseMatrix<double> A(k * k, k * k);
  A.setFromTriplets(t.begin(), t.end());
  return A;
}

// |A x - b| / |b| for a CHOLMOD solve of A x = b, b all ones.
double cholmod_residual(const Eigen::SparseMatrix<double>& A) {
  auto solver = make_linear_solver("cholmod");
  solver->analyze(A);
  solver->factorize(A);
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(A.rows());
  const Eigen::VectorXd x = solver->solve(b);
  return (A * x - b).norm() / b.norm();
}

}  // namespace

#if defined(__x86_64__) || defined(__SSE2__)
TEST_CASE("a CHOLMOD factorization leaves the caller's floating-point flags as it found them") {
  // The control bits (rounding, masks, FTZ, DAZ); the low 6 are sticky exception flags that
  // arithmetic raises.
  constexpr unsigned kControl = ~0x3Fu;
  const unsigned before = _mm_getcsr() & kControl;
  // A large shift: the factor's entries far from the diagonal decay far below 1e-308.
  const double residual = cholmod_residual(shifted_grid(120, 1e6));
  CHECK((_mm_getcsr() & kControl) == before);
  CHECK(residual < 1e-14);
}

TEST_CASE("flush_subnormals_in_process sets FTZ and DAZ, and BLAS solves as before") {
  // This doctest case runs in a process of its own (ctest), so the process-wide flags stay here.
  const Eigen::SparseMatrix<double> A = shifted_grid(120, 1e-3);
  const double before = cholmod_residual(A);
  REQUIRE(flush_subnormals_in_process());
  CHECK((_mm_getcsr() & 0x8040u) == 0x8040u);
  // DAZ: a subnormal operand counts as 0; FTZ: a subnormal result becomes 0.
  volatile double tiny = 1e-310, small = 1e-200;
  CHECK(tiny * 1.0 == 0.0);
  CHECK(small * small == 0.0);
  // OpenBLAS's workers were stopped; the next factorization starts them again and solves alike.
  set_thread_count(2);
  const double after = cholmod_residual(A);
  CHECK(after < 1e-10);
  CHECK(before < 1e-10);
  CHECK(flush_subnormals_in_process());  // again: harmless
  CHECK(cholmod_residual(A) < 1e-10);
}
#endif
