#pragma once
// Fast per-face terms of the interpolated corrected calculus (docs/math.md §3.2-§3.5) for the assembly
// hot loop (interpolated_corrected_fast.cpp), bitwise the matrices of the readable
// interpolated_local() (mass, sharp_stiffness, projected_difference), computed without Eigen
// temporaries and only for what the assembly reads. Internal header.
#include <Eigen/Core>
#include <cmath>
#include <corrlap/core/discretization.hpp>
#include <corrlap/discretizations/assembly/detail/face_kernel_isa.hpp>

namespace corrlap::detail {

/// Layout of the per-face records written by interpolated_face_range: `terms` (16 doubles) for
/// the column pass and `pd` (16 doubles, P_f D) for the edge rows, kept apart so that each pass
/// streams only what it reads.
///  [0, 4)   u_k^z (frame normal component of corner k) and [4] q = h^2 / 144: M_{0,f} (docs/math.md §3.2)
///           is q times integer combinations of the u_k^z (interpolated_mass_row);
///  [5, 15)  K1 = D^T (S^T S / ubar^z) D, the sharp part of -L_f (docs/math.md §3.5), packed symmetric
///           (index kSym[i][j]);
///  pd: P_f D (row-major 4x4), whose rows give the edge rows of P D0 (docs/math.md §3.6a).
inline constexpr int kTermsStride = 16, kTermsK1 = 5;
inline constexpr int kSym[4][4] = {{0, 1, 2, 3}, {1, 4, 5, 6}, {2, 5, 7, 8}, {3, 6, 8, 9}};

/// Row g of M_{0,f} from the record: 144 int phi_g phi_l phi_k is 9, 3 or 1 (docs/math.md §3.2 matrix).
inline void interpolated_mass_row(const double* t, int g, double* row) {
  static constexpr double W[4][4][4] = {{{9, 3, 1, 3}, {3, 3, 1, 1}, {1, 1, 1, 1}, {3, 1, 1, 3}},
                                        {{3, 3, 1, 1}, {3, 9, 3, 1}, {1, 3, 3, 1}, {1, 1, 1, 1}},
                                        {{1, 1, 1, 1}, {1, 3, 3, 1}, {1, 3, 9, 3}, {1, 1, 3, 3}},
                                        {{3, 1, 1, 3}, {1, 1, 1, 1}, {1, 1, 3, 3}, {3, 1, 3, 9}}};
  for (int l = 0; l < 4; ++l)
    row[l] = t[4] * (W[g][l][0] * t[0] + W[g][l][1] * t[1] + W[g][l][2] * t[2] + W[g][l][3] * t[3]);
}

/// The records for faces [b, e) of a quad mesh (`faces`: 4 vertex ids
/// per face; positions and vertex normals as one array per component), written at
/// terms + f kTermsStride and pd + 16 f. The vector paths compute several faces per register with
/// exactly the scalar operations, so every ISA gives the same bits. Returns the first face of the
/// range that is not a square, or -1 (faces after it may not be written).
int interpolated_face_range(const int* faces, int b, int e, const double* const position[3],
                            const double* const normal[3], double kappa, double* terms, double* pd,
                            FaceKernelIsa isa = FaceKernelIsa::Best);

/// ops.L and ops.M of the interpolated corrected calculus for vertex normals u (#V x 3): global
/// projection (docs/math.md §3.6a) or sum of the local L_f (§3.6b), through `pattern` when given. Throws
/// InputError naming the first face that is not a square.
void interpolated_fast_assembly(const SurfelMesh& mesh, const Eigen::MatrixX3d& u, const QuadPattern* pattern,
                                double lambda, double kappa, bool global, Operators& ops);

}  // namespace corrlap::detail
