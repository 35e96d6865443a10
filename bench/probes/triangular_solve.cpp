// A probe (not part of the build): is CHOLMOD's supernodal solve with three columns the floor, or
// would a hand-written solve over the same factor, in double or with the factor in float, be
// faster? Reads L.mtx and M.mtx of `corrlap operators`, factorizes B = sqrt(alpha) M_l - L (AMD)
// and times both on the same right-hand sides.
//
//   g++ -O3 -march=native -std=c++20 -isystem /usr/include/eigen3 -I/usr/include/suitesparse
//       bench/probes/triangular_solve.cpp -lcholmod -o triangular_solve     (one line)
//   ./triangular_solve OPS_DIR ALPHA
#include <cholmod.h>

#include <Eigen/Sparse>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <unsupported/Eigen/SparseExtra>
#include <vector>

namespace {

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

// CHOLMOD's supernodal factor (int indices) with its values in T.
template <class T>
struct Supernodal {
  int n = 0, count = 0;
  std::vector<int> first_column, row_start, rows, perm;
  std::vector<long> value_start;
  std::vector<T> values;
};

template <class T>
Supernodal<T> copy_factor(const cholmod_factor* F) {
  Supernodal<T> S;
  S.n = int(F->n);
  S.count = int(F->nsuper);
  const auto* super = static_cast<const int*>(F->super);
  const auto* pi = static_cast<const int*>(F->pi);
  const auto* px = static_cast<const int*>(F->px);
  const auto* s = static_cast<const int*>(F->s);
  const auto* x = static_cast<const double*>(F->x);
  const auto* perm = static_cast<const int*>(F->Perm);
  S.first_column.assign(super, super + S.count + 1);
  S.row_start.assign(pi, pi + S.count + 1);
  S.value_start.assign(px, px + S.count + 1);
  S.rows.assign(s, s + pi[S.count]);
  S.values.assign(x, x + px[S.count]);
  S.perm.assign(perm, perm + S.n);
  return S;
}

// Solves L L^T y = y in place; y holds three interleaved columns (y[3 k + c]) in the factor's order.
template <class T>
void solve(const Supernodal<T>& S, double* y) {
  for (int sn = 0; sn < S.count; ++sn) {
    const int k1 = S.first_column[sn], columns = S.first_column[sn + 1] - k1;
    const int height = S.row_start[sn + 1] - S.row_start[sn];
    const int* rows = &S.rows[S.row_start[sn]];
    const T* L = &S.values[S.value_start[sn]];
    for (int j = 0; j < columns; ++j) {
      const T* column = L + long(j) * height;
      double* yj = y + 3 * (k1 + j);
      for (int c = 0; c < 3; ++c) yj[c] /= column[j];
      for (int i = j + 1; i < height; ++i) {
        double* yi = y + 3 * rows[i];
        for (int c = 0; c < 3; ++c) yi[c] -= column[i] * yj[c];
      }
    }
  }
  for (int sn = S.count - 1; sn >= 0; --sn) {
    const int k1 = S.first_column[sn], columns = S.first_column[sn + 1] - k1;
    const int height = S.row_start[sn + 1] - S.row_start[sn];
    const int* rows = &S.rows[S.row_start[sn]];
    const T* L = &S.values[S.value_start[sn]];
    for (int j = columns - 1; j >= 0; --j) {
      const T* column = L + long(j) * height;
      double sum[3] = {0.0, 0.0, 0.0};
      for (int i = j + 1; i < height; ++i)
        for (int c = 0; c < 3; ++c) sum[c] += column[i] * y[3 * rows[i] + c];
      double* yj = y + 3 * (k1 + j);
      for (int c = 0; c < 3; ++c) yj[c] = (yj[c] - sum[c]) / column[j];
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: triangular_solve OPS_DIR ALPHA\n");
    return 2;
  }
  Eigen::SparseMatrix<double> L, M;
  Eigen::loadMarket(L, std::string(argv[1]) + "/L.mtx");
  Eigen::loadMarket(M, std::string(argv[1]) + "/M.mtx");
  const double alpha = std::atof(argv[2]);
  const int n = int(L.rows());
  const Eigen::VectorXd mass = M * Eigen::VectorXd::Ones(n);
  Eigen::SparseMatrix<double> B = -L;
  for (int i = 0; i < n; ++i) B.coeffRef(i, i) += std::sqrt(alpha) * mass[i];
  Eigen::SparseMatrix<double> lower = B.triangularView<Eigen::Lower>();
  lower.makeCompressed();
  cholmod_common common;
  cholmod_start(&common);
  common.nmethods = 1;
  common.method[0].ordering = CHOLMOD_AMD;
  common.supernodal = CHOLMOD_SUPERNODAL;
  cholmod_sparse s{};
  s.nrow = s.ncol = std::size_t(n);
  s.nzmax = std::size_t(lower.nonZeros());
  s.p = lower.outerIndexPtr();
  s.i = lower.innerIndexPtr();
  s.x = lower.valuePtr();
  s.stype = -1;
  s.itype = CHOLMOD_INT;
  s.xtype = CHOLMOD_REAL;
  s.dtype = CHOLMOD_DOUBLE;
  s.sorted = s.packed = 1;
  cholmod_factor* F = cholmod_analyze(&s, &common);
  double t = now();
  cholmod_factorize(&s, F, &common);
  std::printf("n %d, factor entries %.3g, flops %.3g, factorize %.2f s\n", n, common.lnz, common.fl, now() - t);
  Eigen::MatrixXd R = Eigen::MatrixXd::Random(n, 3);
  cholmod_dense b{};
  b.nrow = b.d = std::size_t(n);
  b.ncol = 3;
  b.nzmax = std::size_t(3 * n);
  b.x = R.data();
  b.xtype = CHOLMOD_REAL;
  b.dtype = CHOLMOD_DOUBLE;
  cholmod_dense* x = nullptr;
  for (int rep = 0; rep < 3; ++rep) {
    if (x) cholmod_free_dense(&x, &common);
    t = now();
    x = cholmod_solve(CHOLMOD_A, F, &b, &common);
    std::printf("cholmod_solve, 3 columns: %.3f s\n", now() - t);
  }
  const Eigen::Map<const Eigen::MatrixXd> X(static_cast<const double*>(x->x), n, 3);
  const auto in_double = copy_factor<double>(F);
  const auto in_float = copy_factor<float>(F);
  std::vector<double> y(std::size_t(3 * n));
  const auto run = [&](const auto& S, const char* name) {
    for (int k = 0; k < n; ++k)
      for (int c = 0; c < 3; ++c) y[std::size_t(3 * k + c)] = R(S.perm[std::size_t(k)], c);
    const double start = now();
    solve(S, y.data());
    const double seconds = now() - start;
    double difference = 0.0;
    for (int k = 0; k < n; ++k)
      for (int c = 0; c < 3; ++c)
        difference = std::max(difference, std::abs(y[std::size_t(3 * k + c)] - X(S.perm[std::size_t(k)], c)));
    std::printf("%s: %.3f s, largest difference from cholmod_solve %.3g (largest |x| %.3g)\n", name, seconds,
                difference, X.cwiseAbs().maxCoeff());
  };
  for (int rep = 0; rep < 3; ++rep) {
    run(in_double, "hand-written, double factor");
    run(in_float, "hand-written, float factor");
  }
  cholmod_free_dense(&x, &common);
  cholmod_free_factor(&F, &common);
  cholmod_finish(&common);
  return 0;
}
