#pragma once
// A picture of a surface: orthographic view, flat shading by a key light, a fill light and an ambient term,
// optional colouring by a scalar field with a colour-bar legend. Deterministic (the same image,
// byte for byte, for the same input on any machine): a z-buffer with ties kept by the first face,
// no threads, no GPU (speed: bench/RESULTS.md, "bench_render").
#include <Eigen/Core>
#include <corrlap/core/polygon_mesh.hpp>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

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
/// samples (width x height x supersampling^2; 28 bytes each).
Image render_mesh(const PolygonMesh& mesh, const ScalarField* field = nullptr, const RenderOptions& options = {});

/// render_mesh in pieces, for a surface drawn by processes that each hold some of its faces
/// (distributed/distributed_render.hpp): each draws its faces into samples in the frame of the whole
/// surface, the samples are merged, and one process makes the picture. render_mesh is these pieces
/// on the whole mesh, so merged pieces give its picture byte for byte.

/// Where a surface lies on screen: its extent along the view's right and up axes. The picture is
/// fitted to it. Pieces merge their extents by the smallest lo and the largest hi.
struct ScreenExtent {
  double lo_x = 0, hi_x = 0, lo_y = 0, hi_y = 0;
};
ScreenExtent screen_extent(const Eigen::MatrixX3d& positions, const RenderOptions& options);

/// What colour_scale reads from a field: the values at the 2nd and 98th percentiles, and the 98th
/// percentile of the magnitudes (the q-th percentile of n values: the one of rank floor(q (n - 1))
/// in increasing order, from 0). Throws InputError on no value or a NaN.
struct FieldPercentiles {
  double low = 0, high = 0, magnitude_high = 0;
};
FieldPercentiles field_percentiles(const ScalarField& field);
/// colour_scale(field, options) from the field's percentiles.
ColourScale colour_scale(const FieldPercentiles& percentiles, const RenderOptions& options);

/// The supersamples of a picture's plot area (width x height, row-major): for each, the depth of the
/// nearest face drawn (larger is nearer; -inf where none is), that face's id (kNoFace where none
/// is) and its colour (3 floats; white where none is).
struct RenderSamples {
  static constexpr std::int64_t kNoFace = std::numeric_limits<std::int64_t>::max();
  int width = 0, height = 0;
  std::vector<double> depth;
  std::vector<std::int64_t> face;
  std::vector<float> colour;
};

/// Draws `mesh`'s faces, numbered `face_ids` (#F; empty: 0, 1, ...), into samples fitted to
/// `extent` (the whole surface's), coloured by `field` in `scale` (both or neither). At equal depth
/// the lower face id is kept. Throws InputError as render_mesh.
RenderSamples render_samples(const PolygonMesh& mesh, const ScalarField* field, const std::optional<ColourScale>& scale,
                             const ScreenExtent& extent, const RenderOptions& options,
                             const std::vector<std::int64_t>& face_ids = {});

/// Keeps in `into` the nearer of each pair of samples first .. first + count - 1 (at equal depth
/// the lower face id): the samples of two pieces of one surface merged.
void merge_samples(RenderSamples& into, const RenderSamples& other, std::size_t first, std::size_t count);

/// The picture: each pixel the mean of its samples, and the colour bar of `scale` titled `name`
/// (when a scale is given and options.legend).
Image render_picture(const RenderSamples& samples, const std::optional<ColourScale>& scale, const std::string& name,
                     const RenderOptions& options);

}  // namespace corrlap
