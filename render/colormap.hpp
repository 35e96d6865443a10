#pragma once
// Colour maps for scalar fields on surfaces: a sequential one for one-signed quantities (distances,
// displacements) and a diverging one, white at zero, for signed ones (mean curvature).
#include <Eigen/Core>
#include <string>

namespace corrlap {

enum class Colormap {
  Sequential,  ///< dark violet -> blue -> green -> yellow, monotone in lightness
  Diverging,   ///< blue -> light grey (the middle of the range) -> red
};

/// "sequential" or "diverging"; InputError otherwise.
Colormap parse_colormap(const std::string& name);
std::string to_string(Colormap map);

/// Colour (components in [0, 1]) at t in [0, 1]; t outside is clamped, NaN gives mid grey.
Eigen::Vector3d colormap_rgb(Colormap map, double t);

}  // namespace corrlap
