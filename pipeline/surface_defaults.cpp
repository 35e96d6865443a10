#include "surface_defaults.hpp"

namespace corrlap {

namespace {
// The options with the surface's curvature radius when none is given. The options are checked
// first, so that a bad size is reported as such rather than through the radius made from it.
RegularizationOptions with_surface_defaults(const LoadedSurface& surface, RegularizationOptions options) {
  check_regularization_options(surface.mesh, options);
  if (!options.curvature_radius) options.curvature_radius = default_curvature_radius(surface, options.size);
  // The automatic alpha0's bias test is calibrated on cubic voxels (docs/math.md §9.4): resampled
  // anisotropic voxels leave terraces as tall as the coarse side, which it would take for detail
  // and keep. Such volumes get the fixed alpha0.
  if (surface.anisotropy > 1.0 + 1e-6) options.alpha0_auto = false;
  return options;
}
}  // namespace

bool voxels_from_file(const LoadedSurface& surface) { return surface.grid.has_value() && !surface.shape; }

double default_curvature_radius(const LoadedSurface& surface, std::optional<double> size) {
  return default_curvature_radius(size ? *size : regularization_size(surface.mesh), surface.mesh.grid_step(),
                                  voxels_from_file(surface));
}

RegularizationCurvature regularization_curvature(const LoadedSurface& surface, const NormalFields& normals,
                                                 const RegularizationOptions& options) {
  return regularization_curvature(surface.mesh, normals, with_surface_defaults(surface, options));
}

RegularizedSurface regularize_surface(const LoadedSurface& surface, const NormalFields& normals,
                                      const RegularizationOptions& options, const RegularizationCurvature* curvature) {
  return regularize_surface(surface.mesh, normals, with_surface_defaults(surface, options), curvature);
}

}  // namespace corrlap
