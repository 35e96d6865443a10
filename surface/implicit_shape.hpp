#pragma once
// Implicit shapes {P <= 0} (docs/math.md §1.1) and their Gauss digitization (docs/math.md §1.2).
#include <Eigen/Core>
#include <corrlap/core/voxel_grid.hpp>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "polynomial.hpp"

namespace corrlap {

/// The shape {x : P(x - center) <= 0}. grad P points outward.
struct ImplicitShape {
  std::string name;                                  ///< "sphere1", ... or the polynomial text
  Polynomial polynomial;                             ///< P
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  ///< translation of the shape

  double value(const Eigen::Vector3d& x) const;
  Eigen::Vector3d gradient(const Eigen::Vector3d& x) const;
  bool inside(const Eigen::Vector3d& x) const { return value(x) <= 0.0; }
  /// Radius r when P is exactly x^2+y^2+z^2-r^2 (true normals are then radial), else 0.
  double sphere_radius() const;
};

/// Named polynomials of docs/math.md §1.1, in the reference's order: (name, polynomial text).
const std::vector<std::pair<std::string, std::string>>& named_shapes();

/// A named shape of docs/math.md §1.1 or, for any other text, the parsed polynomial.
/// Throws InputError with the parse error or the list of names.
ImplicitShape make_implicit_shape(std::string_view name_or_polynomial,
                                  const Eigen::Vector3d& center = Eigen::Vector3d::Zero());

/// Parameters of the reference's digitization domain (docs/math.md §1.2; defaults -10, 10, 5).
struct DigitizationParams {
  double h = 1.0;
  double min_aabb = -10.0;
  double max_aabb = 10.0;
  int offset = 5;
};

/// Digital box [z_min, z_max]^3 of docs/math.md §1.2: z_min = floor((a - o h)/h), z_max = ceil((b + o h)/h).
void digitization_box(const DigitizationParams& params, Eigen::Vector3i& lower, Eigen::Vector3i& upper);

/// Gauss digitization (docs/math.md §1.2): voxel z is inside iff P(z*h - center) <= 0.
/// Blocks whose interval bound proves them all-inside or all-outside are filled without
/// evaluating P per voxel; the result is identical to the voxel-by-voxel definition.
VoxelGrid digitize(const ImplicitShape& shape, const DigitizationParams& params);

}  // namespace corrlap
