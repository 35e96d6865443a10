#pragma once
// Triangle kernels shared by the cotan Laplacian (cotan.cpp) and the virtual refinement fans
// (virtual_refinement.cpp): area, 1/2-cot stiffness and mixed-Voronoi mass (docs/math.md §5.1 steps 3-4).
#include <Eigen/Core>

namespace corrlap {

/// Area of a triangle from its three edge lengths (Heron, in the cancellation-free form of
/// Kahan; 0 when the lengths violate the triangle inequality through round-off).
double heron_area(double l0, double l1, double l2);

/// Positive cotan stiffness of a triangle from its lengths (docs/math.md §5.1 step 3): l_k is the length
/// of the side opposite to local vertex k, gamma_k = (l_i^2 + l_j^2 - l_k^2) / (8 A) = cot(theta_k)/2,
/// K[i][j] = -gamma_k, K[i][i] = gamma_j + gamma_k. Returns false (K = 0) when A <= DBL_MIN
/// (pmp skips such triangles).
bool cotan_triangle_stiffness(double l0, double l1, double l2, Eigen::Matrix3d& K);

/// pmp's lumped mixed-Voronoi mass of a triangle (docs/math.md §5.1 step 4); sums to the triangle area.
Eigen::Vector3d mixed_voronoi_triangle_mass(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1,
                                            const Eigen::Vector3d& x2);

}  // namespace corrlap
