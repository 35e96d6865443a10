#pragma once
// Interpolated corrected calculus (paper §2.1 + appendix; docs/math.md §3; registry name "interpolated"):
// bilinearly interpolated vertex normals correct area, sharp and flat of every surfel.
#include <Eigen/Core>
#include <corrlap/core/discretization.hpp>
#include <memory>

#include "quad_assembly.hpp"

namespace corrlap {

/// Per-face operators of docs/math.md §3.2-§3.5 for a square quad (a surfel) with corner normals u_k
/// (rows of `normals`, world coordinates, not renormalized).
struct InterpolatedLocal {
  double area = 0.0;                     ///< a_f = h^2 ubar^z (docs/math.md §3.2)
  double ubar_z = 0.0;                   ///< ubar . n, mean normal component along the trivial normal
  Eigen::Matrix4d mass;                  ///< M_{0,f}
  Eigen::Matrix<double, 3, 4> S;         ///< integrated gradient matrix S (frame components, docs/math.md §3.3)
  QuadSharp sharp;                       ///< U_f = R S / (h ubar^z)
  QuadFlat flat;                         ///< V_f[i,:] = delta_i^T (I - kappa Q_i) (docs/math.md §3.4)
  Eigen::Matrix4d projection;            ///< P_f = I - V_f U_f
  Eigen::Matrix4d projected_difference;  ///< P_f D, rows of the global P D0 (docs/math.md §3.6a)
  Eigen::Matrix4d sharp_stiffness;       ///< D^T (S^T S / ubar^z) D = (S D)^T (S D) / ubar^z (docs/math.md §3.5)
  Eigen::Matrix4d inner_product;         ///< M_{1,f} = S^T S / ubar^z + lambda P_f^T P_f (docs/math.md §3.5)
  Eigen::Matrix4d laplacian;             ///< L_f = -D^T M_{1,f} D = -(sharp_stiffness + lambda (P_f D)^T (P_f D))
};
InterpolatedLocal interpolated_local(const QuadCorners& corners, const QuadCorners& normals, double lambda,
                                     double kappa = 2.0);

/// Corrected bilinear mass M_{0,f} of docs/math.md §3.2 (surfel form): (h^2/144) sum_k w_{glk} u_k^z.
Eigen::Matrix4d interpolated_local_mass(double h, const Eigen::Vector4d& uz);

/// The "interpolated" discretization. Parameters: lambda (0.1), kappa (2), assembly = global
/// (docs/math.md §3.6a, DGtal L0(), default) | local (§3.6b), extras, and the normal policy keys.
std::unique_ptr<Discretization> make_interpolated_corrected();

}  // namespace corrlap
