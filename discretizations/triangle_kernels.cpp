#include "triangle_kernels.hpp"

#include <Eigen/Geometry>
#include <cfloat>
#include <cmath>
#include <utility>

namespace corrlap {

double heron_area(double l0, double l1, double l2) {
  // Kahan's ordering a >= b >= c avoids the cancellation of the textbook formula for needles.
  double a = l0, b = l1, c = l2;
  if (a < b) std::swap(a, b);
  if (b < c) std::swap(b, c);
  if (a < b) std::swap(a, b);
  const double p = (a + (b + c)) * (c - (a - b)) * (c + (a - b)) * (a + (b - c));
  return p > 0.0 ? 0.25 * std::sqrt(p) : 0.0;
}

bool cotan_triangle_stiffness(double l0, double l1, double l2, Eigen::Matrix3d& K) {
  K.setZero();
  const double A = heron_area(l0, l1, l2);
  if (!(A > DBL_MIN)) return false;  // docs/math.md §5.1 step 3: pmp skips the triangle
  const double s0 = l0 * l0, s1 = l1 * l1, s2 = l2 * l2;
  // gamma_k = (l_i^2 + l_j^2 - l_k^2) / (8A) = cot(theta_k) / 2
  const double g0 = (s1 + s2 - s0) / (8.0 * A), g1 = (s0 + s2 - s1) / (8.0 * A), g2 = (s0 + s1 - s2) / (8.0 * A);
  K(0, 1) = K(1, 0) = -g2;
  K(0, 2) = K(2, 0) = -g1;
  K(1, 2) = K(2, 1) = -g0;
  K(0, 0) = g1 + g2;
  K(1, 1) = g0 + g2;
  K(2, 2) = g0 + g1;
  return true;
}

Eigen::Vector3d mixed_voronoi_triangle_mass(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1,
                                            const Eigen::Vector3d& x2) {
  // docs/math.md §5.1 step 4 (pmp): e_i = x_{i+1} - x_i, delta_i = -e_i . e_{i+2} (corner i's dot product).
  const Eigen::Vector3d x[3] = {x0, x1, x2};
  Eigen::Vector3d e[3];
  for (int i = 0; i < 3; ++i) e[i] = x[(i + 1) % 3] - x[i];
  const double area2 = e[0].cross(e[1]).norm();
  Eigen::Vector3d m = Eigen::Vector3d::Zero();
  if (!(area2 > DBL_MIN)) return m;
  double delta[3];
  for (int i = 0; i < 3; ++i) delta[i] = -e[i].dot(e[(i + 2) % 3]);
  const bool any_obtuse = delta[0] < 0.0 || delta[1] < 0.0 || delta[2] < 0.0;
  for (int i = 0; i < 3; ++i) {
    if (delta[i] < 0.0)
      m[i] = 0.25 * area2;
    else if (any_obtuse)
      m[i] = 0.125 * area2;
    else
      m[i] = 0.125 * (e[i].squaredNorm() * delta[(i + 2) % 3] / area2 +
                      e[(i + 2) % 3].squaredNorm() * delta[(i + 1) % 3] / area2);
  }
  return m;
}

}  // namespace corrlap
