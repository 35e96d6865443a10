#pragma once
// Input checks shared by the heat kernel's matrix (heat_kernel.cpp) and its lattice form
// (heat_kernel_lattice.cpp): the same errors for the same bad inputs. Internal header.
#include <Eigen/Core>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <sstream>
#include <string>

namespace corrlap::detail {

/// Points (finite, at least one), t and the cut-off (positive, finite).
inline void check_heat_kernel_inputs(const Eigen::MatrixX3d& points, double t, double cutoff) {
  if (points.rows() == 0) throw InputError("heat kernel: no point");
  if (!points.allFinite()) throw InputError("heat kernel: non-finite point position");
  if (!(t > 0.0) || !std::isfinite(t)) throw InputError("heat kernel: t must be a positive number");
  if (!(cutoff > 0.0) || !std::isfinite(cutoff)) throw InputError("heat kernel: cutoff must be a positive number");
}

/// One positive, finite measure per point.
inline void check_heat_kernel_measures(const Eigen::VectorXd& mu, Eigen::Index points) {
  if (mu.size() != points)
    throw InputError("heat kernel: " + std::to_string(mu.size()) + " measures for " + std::to_string(points) +
                     " points");
  for (Eigen::Index i = 0; i < points; ++i)
    if (!std::isfinite(mu[i]) || !(mu[i] > 0.0)) {
      std::ostringstream os;
      os << "heat kernel: measure of point " << i << " is " << mu[i] << " (must be positive)";
      throw InputError(os.str());
    }
}

}  // namespace corrlap::detail
