#pragma once
// Corrected FEM (paper §2.2; docs/math.md §4): bilinear quads whose metric is corrected by one unit
// normal per face. Registry name "fem".
#include <Eigen/Core>
#include <corrlap/core/discretization.hpp>
#include <memory>

#include "quad_assembly.hpp"

namespace corrlap {

/// (x, y, z) = (u.e_s, u.e_t, u.nu) in the DGtal frame of docs/math.md §4.2, and the parallelogram area
/// |(x1-x0) x (x3-x0)| used by the mass (docs/math.md §4.4).
struct FemLocalFrame {
  Eigen::Vector3d u_local;
  double area = 0.0;
};
FemLocalFrame corrected_fem_local_frame(const QuadCorners& corners, const Eigen::Vector3d& u);

/// Positive stiffness K_f of docs/math.md §4.3 (DGtal form) from u_local = (x, y, z); L_f = -K_f.
/// Does not depend on h.
Eigen::Matrix4d corrected_fem_local_stiffness(const Eigen::Vector3d& u_local);
/// Consistent mass (area z / 36)[4 2 1 2; ...] (docs/math.md §4.4).
Eigen::Matrix4d corrected_fem_local_mass(double area, double z);
/// Lumped mass (area z / 4) I (docs/math.md §4.4).
Eigen::Matrix4d corrected_fem_local_lumped_mass(double area, double z);

/// The "fem" discretization. Parameters: mass = full | lumped, and the normal policy keys.
std::unique_ptr<Discretization> make_corrected_fem();

}  // namespace corrlap
