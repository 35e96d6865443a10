// Bitwise equal to interpolated_local (mass, sharp_stiffness, projected_difference), checked by TEST_CASE("interpolated fast face terms are bitwise the readable interpolated_local").
//
// The per-face kernel of the interpolated corrected calculus (spec §3.2-§3.5) for the assembly hot
// loop: several faces per SIMD register (one face per lane), each lane doing the readable
// function's operations in its order (no FMA contraction: -ffp-contract=off), writing only what the
// assembly reads.
#include <cmath>

#include <corrlap/discretizations/detail/interpolated_kernel.hpp>

#include <corrlap/discretizations/assembly/detail/avx2_target.inc>

#include <cstddef>
#include <cstring>

namespace corrlap::detail {

namespace {

typedef double Lanes1 __attribute__((vector_size(8)));   // one face: the tail of a range
typedef double Lanes2 __attribute__((vector_size(16)));  // an SSE2 register of doubles
typedef double Lanes4 __attribute__((vector_size(32)));  // an AVX register of doubles

// a . b for 3-vectors of lanes, summed left to right as the scalar dot (a macro: a helper
// function returning an AVX vector would be compiled for the default target).
#define CORRLAP_DOT3(a, b) ((a)[0] * (b)[0] + (a)[1] * (b)[1] + (a)[2] * (b)[2])

// The records of N consecutive faces f0 .. f0 + N - 1 at once, one face per vector lane (GCC
// vector extensions: compiled as AVX2, SSE2 or scalar code by the caller's target); square roots
// and the square test (to 1e-6) per lane in scalar code.
// Corners come from `faces` (4 per face), positions px/py/pz and normals ux/uy/uz (one array per
// component). Returns false, having written nothing, when some face is not a square.

template <class vec>
__attribute__((always_inline)) inline bool interpolated_face_terms_batch(const int* faces, int f0, const double* px,
                                                                         const double* py, const double* pz,
                                                                         const double* ux, const double* uy,
                                                                         const double* uz_, double kappa,
                                                                         double* terms, double* pd) {
  constexpr int N = int(sizeof(vec) / sizeof(double));
  double xl[4][3][N], ulanes[4][3][N];  // gathered lane by lane, then loaded as vectors
  for (int k = 0; k < 4; ++k)
    for (int l = 0; l < N; ++l) {
      const int v = faces[4 * (f0 + l) + k];
      xl[k][0][l] = px[v];
      xl[k][1][l] = py[v];
      xl[k][2][l] = pz[v];
      ulanes[k][0][l] = ux[v];
      ulanes[k][1][l] = uy[v];
      ulanes[k][2][l] = uz_[v];
    }
  vec x[4][3], u[4][3];
  std::memcpy(x, xl, sizeof x);
  std::memcpy(u, ulanes, sizeof u);
  vec e[4][3];
  for (int i = 0; i < 4; ++i)
    for (int c = 0; c < 3; ++c) e[i][c] = x[(i + 1) & 3][c] - x[i][c];
  const vec q0 = CORRLAP_DOT3(e[0], e[0]), q1 = CORRLAP_DOT3(e[1], e[1]), d01 = CORRLAP_DOT3(e[0], e[1]);
  const vec s02[3] = {e[0][0] + e[2][0], e[0][1] + e[2][1], e[0][2] + e[2][2]};
  const vec q02 = CORRLAP_DOT3(s02, s02);
  vec l0, l1;
  for (int l = 0; l < N; ++l) {
    l0[l] = std::sqrt(q0[l]);
    l1[l] = std::sqrt(q1[l]);
    if (!(std::abs(l1[l] - l0[l]) <= 1e-6 * l0[l] && std::abs(d01[l]) <= 1e-6 * l0[l] * l0[l] &&
          std::sqrt(q02[l]) <= 1e-6 * l0[l]))
      return false;
  }
  const vec h = l0;
  const vec ih = 1.0 / h, il1 = 1.0 / l1;
  const vec t1[3] = {e[0][0] * ih, e[0][1] * ih, e[0][2] * ih};
  const vec t2[3] = {e[1][0] * il1, e[1][1] * il1, e[1][2] * il1};
  const vec n[3] = {t1[1] * t2[2] - t1[2] * t2[1], t1[2] * t2[0] - t1[0] * t2[2], t1[0] * t2[1] - t1[1] * t2[0]};
  vec ul[4][3];
  for (int k = 0; k < 4; ++k) {
    ul[k][0] = CORRLAP_DOT3(u[k], t1);
    ul[k][1] = CORRLAP_DOT3(u[k], t2);
    ul[k][2] = CORRLAP_DOT3(u[k], n);
  }
  vec ue[4][3], ub[3];
  for (int c = 0; c < 3; ++c) {
    for (int i = 0; i < 4; ++i) ue[i][c] = 0.5 * (ul[i][c] + ul[(i + 1) & 3][c]);
    ub[c] = 0.25 * (ul[0][c] + ul[1][c] + ul[2][c] + ul[3][c]);
  }
  const vec uz = ub[2];
  constexpr double s6 = 1.0 / 6.0;
  const vec zero = {};  // the literal zeros of the scalar S
  const vec S[3][4] = {
      {(2.0 * uz + ue[0][2]) * s6, zero, -(2.0 * uz + ue[2][2]) * s6, zero},
      {zero, (2.0 * uz + ue[1][2]) * s6, zero, -(2.0 * uz + ue[3][2]) * s6},
      {-(2.0 * ub[0] + ue[0][0]) * s6, -(2.0 * ub[1] + ue[1][1]) * s6, (2.0 * ub[0] + ue[2][0]) * s6,
       (2.0 * ub[1] + ue[3][1]) * s6}};
  vec G[3][4];
  for (int c = 0; c < 3; ++c)
    for (int j = 0; j < 4; ++j) G[c][j] = S[c][(j + 3) & 3] - S[c][j];
  const vec iuz = 1.0 / uz;
  vec k1[10];
  for (int i = 0; i < 4; ++i)
    for (int j = i; j < 4; ++j) k1[kSym[i][j]] = (G[0][i] * G[0][j] + G[1][i] * G[1][j] + G[2][i] * G[2][j]) * iuz;
  const vec w = ih * iuz;
  const double kk = kappa * s6;
  vec p[16];
  for (int i = 0; i < 4; ++i) {
    const vec* ua = u[i];
    const vec* ubv = u[(i + 1) & 3];
    const vec da = CORRLAP_DOT3(e[i], ua), db = CORRLAP_DOT3(e[i], ubv);
    const vec ca = kk * (2.0 * da + db), cb = kk * (da + 2.0 * db);
    const vec v[3] = {e[i][0] - ca * ua[0] - cb * ubv[0], e[i][1] - ca * ua[1] - cb * ubv[1],
                      e[i][2] - ca * ua[2] - cb * ubv[2]};
    const vec vr0 = CORRLAP_DOT3(v, t1) * w, vr1 = CORRLAP_DOT3(v, t2) * w, vr2 = CORRLAP_DOT3(v, n) * w;
    for (int j = 0; j < 4; ++j) p[4 * i + j] = -(vr0 * G[0][j] + vr1 * G[1][j] + vr2 * G[2][j]);
    p[4 * i + i] -= 1.0;
    p[4 * i + ((i + 1) & 3)] += 1.0;
  }
  const vec hh = h * h / 144.0;
  for (int l = 0; l < N; ++l) {
    double* t = terms + std::size_t(l) * kTermsStride;
    double* o = pd + std::size_t(l) * 16;
    for (int k = 0; k < 4; ++k) t[k] = ul[k][2][l];
    t[4] = hh[l];
    for (int m = 0; m < 10; ++m) t[kTermsK1 + m] = k1[m][l];
    for (int m = 0; m < 16; ++m) o[m] = p[m][l];
  }
  return true;
}


#undef CORRLAP_DOT3

template <class Lanes>
__attribute__((always_inline)) inline int face_range_body(const int* faces, int b, int e, const double* const x[3],
                                                          const double* const u[3], double kappa, double* terms,
                                                          double* pd) {
  constexpr int N = int(sizeof(Lanes) / sizeof(double));
  int f = b;
  if constexpr (N > 1)
    for (; f + N <= e; f += N)
      if (!interpolated_face_terms_batch<Lanes>(faces, f, x[0], x[1], x[2], u[0], u[1], u[2], kappa,
                                                terms + std::size_t(f) * kTermsStride, pd + std::size_t(f) * 16))
        break;  // some face of the batch is not a square: the one-face loop finds which
  for (; f < e; ++f)
    if (!interpolated_face_terms_batch<Lanes1>(faces, f, x[0], x[1], x[2], u[0], u[1], u[2], kappa,
                                               terms + std::size_t(f) * kTermsStride, pd + std::size_t(f) * 16))
      return f;
  return -1;
}

CORRLAP_AVX2_TARGET int face_range_avx2(const int* faces, int b, int e, const double* const x[3],
                                                    const double* const u[3], double kappa, double* terms,
                                                    double* pd) {
  return face_range_body<Lanes4>(faces, b, e, x, u, kappa, terms, pd);
}

int face_range_sse2(const int* faces, int b, int e, const double* const x[3], const double* const u[3], double kappa,
                    double* terms, double* pd) {
  return face_range_body<Lanes2>(faces, b, e, x, u, kappa, terms, pd);
}

int face_range_scalar(const int* faces, int b, int e, const double* const x[3], const double* const u[3],
                      double kappa, double* terms, double* pd) {
  return face_range_body<Lanes1>(faces, b, e, x, u, kappa, terms, pd);
}

}  // namespace

int interpolated_face_range(const int* faces, int b, int e, const double* const position[3],
                            const double* const normal[3], double kappa, double* terms, double* pd, FaceKernelIsa isa) {
  switch (resolve_face_kernel_isa(isa)) {
    case FaceKernelIsa::Avx2: return face_range_avx2(faces, b, e, position, normal, kappa, terms, pd);
    case FaceKernelIsa::Sse2: return face_range_sse2(faces, b, e, position, normal, kappa, terms, pd);
    default: return face_range_scalar(faces, b, e, position, normal, kappa, terms, pd);
  }
}

}  // namespace corrlap::detail
