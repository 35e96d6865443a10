#include "colormap.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <corrlap/core/error.hpp>

namespace corrlap {

namespace {
// Colour stops, evenly spaced in t, interpolated linearly in RGB.
using Stops = std::array<Eigen::Vector3d, 5>;
const Stops& stops(Colormap map) {
  static const Stops sequential = {Eigen::Vector3d(0.20, 0.05, 0.33), Eigen::Vector3d(0.22, 0.32, 0.56),
                                   Eigen::Vector3d(0.13, 0.56, 0.55), Eigen::Vector3d(0.38, 0.79, 0.38),
                                   Eigen::Vector3d(0.99, 0.91, 0.15)};
  static const Stops diverging = {Eigen::Vector3d(0.17, 0.28, 0.72), Eigen::Vector3d(0.52, 0.66, 0.95),
                                  Eigen::Vector3d(0.88, 0.88, 0.88), Eigen::Vector3d(0.94, 0.55, 0.45),
                                  Eigen::Vector3d(0.70, 0.05, 0.15)};
  return map == Colormap::Sequential ? sequential : diverging;
}
}  // namespace

Colormap parse_colormap(const std::string& name) {
  if (name == "sequential") return Colormap::Sequential;
  if (name == "diverging") return Colormap::Diverging;
  throw InputError("colour map '" + name + "': expected sequential or diverging");
}

std::string to_string(Colormap map) { return map == Colormap::Sequential ? "sequential" : "diverging"; }

Eigen::Vector3d colormap_rgb(Colormap map, double t) {
  if (std::isnan(t)) return Eigen::Vector3d::Constant(0.5);
  const Stops& s = stops(map);
  const double x = std::clamp(t, 0.0, 1.0) * double(s.size() - 1);
  const std::size_t i = std::min<std::size_t>(std::size_t(x), s.size() - 2);
  const double f = x - double(i);
  return (1.0 - f) * s[i] + f * s[i + 1];
}

}  // namespace corrlap
