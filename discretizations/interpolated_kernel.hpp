#pragma once
// Fast per-face terms of the interpolated corrected calculus (spec §3.2-§3.5) for the assembly
// hot loop. Internal header. Same quantities as interpolated_local() (the readable reference
// implementation, kept for the tests and the extras path), computed with scalar fixed-size
// arithmetic: no Eigen temporaries, no 4x4 products with the constant D, and only the three
// matrices the assembly reads.
#include <cmath>

namespace corrlap::detail {

/// Terms of one surfel written by interpolated_face_terms (row-major 4x4 each).
///  m0: M_{0,f} (spec §3.2); k1: D^T (S^T S / ubar^z) D, the sharp part of -L_f (spec §3.5);
///  pd: P_f D, whose rows give the edge rows of P D0 in the global variant (spec §3.6a).
struct InterpolatedFaceTerms {
  double m0[16];
  double k1[16];
  double pd[16];
};

/// x[k], u[k]: corner k position and vertex normal (world, 3 values each). Returns false (and
/// writes nothing) when the face is not a square to 1e-6, the test of the assembly.
inline bool interpolated_face_terms(const double* const x[4], const double* const u[4], double kappa, double* m0,
                                    double* k1, double* pd) {
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
  const double t1[3] = {e[0][0] / h, e[0][1] / h, e[0][2] / h};
  const double t2[3] = {e[1][0] / l1, e[1][1] / l1, e[1][2] / l1};
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
  // S of spec §3.3 (closed form: first matrix / 3 + second matrix / 6).
  const double S[3][4] = {
      {uz / 3.0 + ue[0][2] / 6.0, 0.0, -uz / 3.0 - ue[2][2] / 6.0, 0.0},
      {0.0, uz / 3.0 + ue[1][2] / 6.0, 0.0, -uz / 3.0 - ue[3][2] / 6.0},
      {-ub[0] / 3.0 - ue[0][0] / 6.0, -ub[1] / 3.0 - ue[1][1] / 6.0, ub[0] / 3.0 + ue[2][0] / 6.0,
       ub[1] / 3.0 + ue[3][1] / 6.0}};
  // G = S D (D of spec §0: (S D)[c][j] = S[c][j-1] - S[c][j]).
  double G[3][4];
  for (int c = 0; c < 3; ++c)
    for (int j = 0; j < 4; ++j) G[c][j] = S[c][(j + 3) & 3] - S[c][j];
  // k1 = G^T G / ubar^z (spec §3.5: a_f U^T U = S^T S / ubar^z).
  for (int i = 0; i < 4; ++i)
    for (int j = i; j < 4; ++j) k1[4 * i + j] = k1[4 * j + i] = (G[0][i] * G[0][j] + G[1][i] * G[1][j] + G[2][i] * G[2][j]) / uz;
  // Flat rows (spec §3.4): V_i = delta_i - kappa/6 ((2 d_a + d_b) u_a + (d_a + 2 d_b) u_b), in world
  // coordinates, then in frame components (V R) so that V U = (V R) S / (h ubar^z).
  const double w = 1.0 / (h * uz);
  for (int i = 0; i < 4; ++i) {
    const double* ua = u[i];
    const double* ubv = u[(i + 1) & 3];
    const double da = dot(e[i], ua), db = dot(e[i], ubv);
    const double ca = kappa * (2.0 * da + db) / 6.0, cb = kappa * (da + 2.0 * db) / 6.0;
    const double v[3] = {e[i][0] - ca * ua[0] - cb * ubv[0], e[i][1] - ca * ua[1] - cb * ubv[1],
                         e[i][2] - ca * ua[2] - cb * ubv[2]};
    const double vr0 = dot(v, t1) * w, vr1 = dot(v, t2) * w, vr2 = dot(v, n) * w;
    // P D = D - V U D = D - (V R) G / (h ubar^z).
    for (int j = 0; j < 4; ++j) pd[4 * i + j] = -(vr0 * G[0][j] + vr1 * G[1][j] + vr2 * G[2][j]);
    pd[4 * i + i] -= 1.0;
    pd[4 * i + ((i + 1) & 3)] += 1.0;
  }
  // M_{0,f} (spec §3.2): h^2/144 sum_k w_{glk} u_k^z with w = 9, 3 or 1 per corner pair/triple.
  const double q = h * h / 144.0;
  const double z0 = ul[0][2], z1 = ul[1][2], z2 = ul[2][2], z3 = ul[3][2];
  const double all = z0 + z1 + z2 + z3;
  m0[0] = q * (9.0 * z0 + 3.0 * z1 + z2 + 3.0 * z3);
  m0[5] = q * (3.0 * z0 + 9.0 * z1 + 3.0 * z2 + z3);
  m0[10] = q * (z0 + 3.0 * z1 + 9.0 * z2 + 3.0 * z3);
  m0[15] = q * (3.0 * z0 + z1 + 3.0 * z2 + 9.0 * z3);
  m0[1] = m0[4] = q * (3.0 * z0 + 3.0 * z1 + z2 + z3);
  m0[6] = m0[9] = q * (z0 + 3.0 * z1 + 3.0 * z2 + z3);
  m0[11] = m0[14] = q * (z0 + z1 + 3.0 * z2 + 3.0 * z3);
  m0[3] = m0[12] = q * (3.0 * z0 + z1 + z2 + 3.0 * z3);
  m0[2] = m0[8] = m0[7] = m0[13] = q * all;
  return true;
}

}  // namespace corrlap::detail
