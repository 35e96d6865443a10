#pragma once
// Fast per-face terms of the interpolated corrected calculus (spec §3.2-§3.5) for the assembly
// hot loop. Internal header. Same quantities as interpolated_local() (the readable reference
// implementation, kept for the tests and the extras path), computed with scalar fixed-size
// arithmetic: no Eigen temporaries, no 4x4 products with the constant D, and only the three
// matrices the assembly reads.
#include <cmath>

#include <corrlap/discretizations/assembly/detail/face_kernel_isa.hpp>

namespace corrlap::detail {

/// Layout of the per-face records written by interpolated_face_terms: `terms` (16 doubles) for
/// the column pass and `pd` (16 doubles, P_f D) for the edge rows, kept apart so that each pass
/// streams only what it reads.
///  [0, 4)   u_k^z (frame normal component of corner k) and [4] q = h^2 / 144: M_{0,f} (spec §3.2)
///           is q times integer combinations of the u_k^z (interpolated_mass_row);
///  [5, 15)  K1 = D^T (S^T S / ubar^z) D, the sharp part of -L_f (spec §3.5), packed symmetric
///           (index kSym[i][j]);
///  pd: P_f D (row-major 4x4), whose rows give the edge rows of P D0 (spec §3.6a).
inline constexpr int kTermsStride = 16, kTermsK1 = 5;
inline constexpr int kSym[4][4] = {{0, 1, 2, 3}, {1, 4, 5, 6}, {2, 5, 7, 8}, {3, 6, 8, 9}};

/// Row g of M_{0,f} from the record: 144 int phi_g phi_l phi_k is 9, 3 or 1 (spec §3.2 matrix).
inline void interpolated_mass_row(const double* t, int g, double* row) {
  static constexpr double W[4][4][4] = {
      {{9, 3, 1, 3}, {3, 3, 1, 1}, {1, 1, 1, 1}, {3, 1, 1, 3}},
      {{3, 3, 1, 1}, {3, 9, 3, 1}, {1, 3, 3, 1}, {1, 1, 1, 1}},
      {{1, 1, 1, 1}, {1, 3, 3, 1}, {1, 3, 9, 3}, {1, 1, 3, 3}},
      {{3, 1, 1, 3}, {1, 1, 1, 1}, {1, 1, 3, 3}, {3, 1, 3, 9}}};
  for (int l = 0; l < 4; ++l)
    row[l] = t[4] * (W[g][l][0] * t[0] + W[g][l][1] * t[1] + W[g][l][2] * t[2] + W[g][l][3] * t[3]);
}

/// x[k], u[k]: corner k position and vertex normal (world, 3 values each). Returns false (and
/// writes nothing) when the face is not a square to 1e-6, the test of the assembly.
inline bool interpolated_face_terms(const double* const x[4], const double* const u[4], double kappa, double* terms,
                                    double* pd) {
  double e[4][3];  // edge vectors delta_i = x_{i+1} - x_i (spec §3.4)
  for (int i = 0; i < 4; ++i)
    for (int c = 0; c < 3; ++c) e[i][c] = x[(i + 1) & 3][c] - x[i][c];
  auto dot = [](const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
  const double l0 = std::sqrt(dot(e[0], e[0])), l1 = std::sqrt(dot(e[1], e[1]));
  const double s02[3] = {e[0][0] + e[2][0], e[0][1] + e[2][1], e[0][2] + e[2][2]};
  if (!(std::abs(l1 - l0) <= 1e-6 * l0 && std::abs(dot(e[0], e[1])) <= 1e-6 * l0 * l0 &&
        std::sqrt(dot(s02, s02)) <= 1e-6 * l0))
    return false;
  // Frame of spec §0: t1 = (x1-x0)/h, t2 = (x2-x1)/|x2-x1|, n = t1 x t2.
  const double h = l0;
  const double ih = 1.0 / h, il1 = 1.0 / l1;
  const double t1[3] = {e[0][0] * ih, e[0][1] * ih, e[0][2] * ih};
  const double t2[3] = {e[1][0] * il1, e[1][1] * il1, e[1][2] * il1};
  const double n[3] = {t1[1] * t2[2] - t1[2] * t2[1], t1[2] * t2[0] - t1[0] * t2[2], t1[0] * t2[1] - t1[1] * t2[0]};
  // Corner normals in frame components (spec §3.1).
  double ul[4][3];
  for (int k = 0; k < 4; ++k) {
    ul[k][0] = dot(u[k], t1);
    ul[k][1] = dot(u[k], t2);
    ul[k][2] = dot(u[k], n);
  }
  double ue[4][3], ub[3];
  for (int c = 0; c < 3; ++c) {
    for (int i = 0; i < 4; ++i) ue[i][c] = 0.5 * (ul[i][c] + ul[(i + 1) & 3][c]);
    ub[c] = 0.25 * (ul[0][c] + ul[1][c] + ul[2][c] + ul[3][c]);
  }
  const double uz = ub[2];
  // S of spec §3.3 (closed form: first matrix / 3 + second matrix / 6 = (2 first + second) / 6).
  constexpr double s6 = 1.0 / 6.0;
  const double S[3][4] = {
      {(2.0 * uz + ue[0][2]) * s6, 0.0, -(2.0 * uz + ue[2][2]) * s6, 0.0},
      {0.0, (2.0 * uz + ue[1][2]) * s6, 0.0, -(2.0 * uz + ue[3][2]) * s6},
      {-(2.0 * ub[0] + ue[0][0]) * s6, -(2.0 * ub[1] + ue[1][1]) * s6, (2.0 * ub[0] + ue[2][0]) * s6,
       (2.0 * ub[1] + ue[3][1]) * s6}};
  // G = S D (D of spec §0: (S D)[c][j] = S[c][j-1] - S[c][j]).
  double G[3][4];
  for (int c = 0; c < 3; ++c)
    for (int j = 0; j < 4; ++j) G[c][j] = S[c][(j + 3) & 3] - S[c][j];
  // k1 = G^T G / ubar^z (spec §3.5: a_f U^T U = S^T S / ubar^z).
  const double iuz = 1.0 / uz;
  double* k1 = terms + kTermsK1;
  for (int i = 0; i < 4; ++i)
    for (int j = i; j < 4; ++j) k1[kSym[i][j]] = (G[0][i] * G[0][j] + G[1][i] * G[1][j] + G[2][i] * G[2][j]) * iuz;
  // Flat rows (spec §3.4): V_i = delta_i - kappa/6 ((2 d_a + d_b) u_a + (d_a + 2 d_b) u_b), in world
  // coordinates, then in frame components (V R) so that V U = (V R) S / (h ubar^z).
  const double w = ih * iuz, kk = kappa * s6;
  for (int i = 0; i < 4; ++i) {
    const double* ua = u[i];
    const double* ubv = u[(i + 1) & 3];
    const double da = dot(e[i], ua), db = dot(e[i], ubv);
    const double ca = kk * (2.0 * da + db), cb = kk * (da + 2.0 * db);
    const double v[3] = {e[i][0] - ca * ua[0] - cb * ubv[0], e[i][1] - ca * ua[1] - cb * ubv[1],
                         e[i][2] - ca * ua[2] - cb * ubv[2]};
    const double vr0 = dot(v, t1) * w, vr1 = dot(v, t2) * w, vr2 = dot(v, n) * w;
    // P D = D - V U D = D - (V R) G / (h ubar^z).
    for (int j = 0; j < 4; ++j) pd[4 * i + j] = -(vr0 * G[0][j] + vr1 * G[1][j] + vr2 * G[2][j]);
    pd[4 * i + i] -= 1.0;
    pd[4 * i + ((i + 1) & 3)] += 1.0;
  }
  for (int k = 0; k < 4; ++k) terms[k] = ul[k][2];  // M_{0,f} (spec §3.2), see interpolated_mass_row
  terms[4] = h * h / 144.0;
  return true;
}

/// The records of interpolated_face_terms for faces [b, e) of a quad mesh (`faces`: 4 vertex ids
/// per face; positions and vertex normals as one array per component), written at
/// terms + f kTermsStride and pd + 16 f. The vector paths compute several faces per register with
/// exactly the scalar operations, so every ISA gives the same bits. Returns the first face of the
/// range that is not a square, or -1 (faces after it may not be written).
int interpolated_face_range(const int* faces, int b, int e, const double* const position[3],
                            const double* const normal[3], double kappa, double* terms, double* pd,
                            FaceKernelIsa isa = FaceKernelIsa::Best);

}  // namespace corrlap::detail
