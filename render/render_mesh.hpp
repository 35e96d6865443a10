#pragma once
// A picture of a surface: orthographic view, flat shading by a key light, a fill light and an ambient term,
// optional colouring by a scalar field with a colour-bar legend. Deterministic (the same image,
// byte for byte, for the same input on any machine): a z-buffer with ties kept by the first face,
// no threads, no GPU (speed: bench/RESULTS.md, "bench_render").
#include <Eigen/Core>
#include <corrlap/core/polygon_mesh.hpp>
#include <optional>
#include <string>

#include "colormap.hpp"
#include "image.hpp"

namespace corrlap {

/// A scalar per vertex (#V) or per face (#F) to colour the surface with.
struct ScalarField {
  std::string name;  ///< the legend's title
  Eigen::VectorXd values;
  bool per_face = false;
};

struct RenderOptions {
  int width = 800, height = 800;                   ///< pixels of the output, legend included
  Eigen::Vector3d view_direction{1.0, -1.4, 0.9};  ///< from the object towards the viewer
  Eigen::Vector3d up{0.0, 0.0, 1.0};               ///< drawn upwards (its part orthogonal to the view)
  int supersampling = 2;                           ///< s x s samples per pixel, averaged (1..4)
  /// Colour range of the scalar; absent: a robust automatic one (the 2nd-98th percentiles, or
  /// symmetric about 0 by the 98th percentile of |s| when the field takes both signs).
  std::optional<double> range_min, range_max;
  std::optional<Colormap> colormap;  ///< absent: diverging when the range contains 0 inside, else sequential
  bool legend = true;                ///< colour bar with the range and the scalar's name (when coloured)
};

/// The colour range and map render_mesh uses for `field` under `options` (for a common range of
/// several pictures, e.g. before and after a regularization). Throws InputError on a NaN value or
/// an empty range (min >= max) given explicitly.
struct ColourScale {
  double min = 0, max = 1;
  Colormap map = Colormap::Sequential;
};
ColourScale colour_scale(const ScalarField& field, const RenderOptions& options);

/// Renders `mesh` (any polygons, fanned into triangles) seen along -view_direction, scaled to fill
/// the picture. `field` (optional) colours it; without it the surface is light grey. Throws
/// InputError on an empty mesh, non-finite positions, a face with a missing vertex, a scalar of the
/// wrong size or with NaN, a zero view direction, sizes outside [16, 8192] pixels or more than 2^26
/// samples (width x height x supersampling^2; 20 bytes each).
Image render_mesh(const PolygonMesh& mesh, const ScalarField* field = nullptr, const RenderOptions& options = {});

}  // namespace corrlap
