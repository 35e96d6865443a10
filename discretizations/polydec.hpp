#pragma once
// PolyDEC of de Goes et al. (docs/math.md §2.1-§2.4; registry name "polydec") and Projected PolyDEC of
// Coeurjolly & Lachaud (docs/math.md §2.5; "projected-polydec"), on quads.
#include <Eigen/Core>
#include <corrlap/core/discretization.hpp>
#include <memory>

#include "quad_assembly.hpp"

namespace corrlap {

/// Per-face operators of docs/math.md §2.2 built from the embedded corners.
struct PolyDecLocal {
  double area = 0.0;              ///< |a_f|
  Eigen::Vector3d normal;         ///< n_f = a_f / |a_f|
  QuadSharp sharp;                ///< U_f (3x4)
  QuadFlat flat;                  ///< V_f (4x3)
  Eigen::Matrix4d projection;     ///< P_f = I - V_f U_f
  Eigen::Matrix4d inner_product;  ///< M_{1,f} = |a_f| U_f^T U_f + lambda P_f^T P_f
  Eigen::Matrix4d laplacian;      ///< L_f = -D^T M_{1,f} D (negative semi-definite)
};
PolyDecLocal polydec_local(const QuadCorners& embedded, double lambda);

/// Projected PolyDEC embedder (docs/math.md §2.5): x - (u.x) u for every corner.
QuadCorners polydec_project_corners(const QuadCorners& corners, const Eigen::Vector3d& u);

/// Uncorrected PolyDEC ("polydec") and Projected PolyDEC ("projected-polydec", face normals).
/// Parameters: lambda (default 1), extras; projected adds the normal policy keys.
std::unique_ptr<Discretization> make_polydec();
std::unique_ptr<Discretization> make_projected_polydec();

}  // namespace corrlap
