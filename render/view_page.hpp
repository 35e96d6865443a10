#pragma once
// An interactive page of surfaces: one self-contained HTML file (no server, no network when it is
// opened) that a browser turns, zooms and colours by the surfaces' scalars with the maps and the
// automatic ranges of the PNG pictures (render_mesh.hpp). Several surfaces overlaid or side by
// side, flat or smooth shading, wireframe, the value under the cursor. The page's script (three.js
// and viewer/src/) is compiled into the library at build time; the format: viewer/README.md.
#include <corrlap/core/polygon_mesh.hpp>
#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include "render_mesh.hpp"

namespace corrlap {

/// One surface of a page: its polygons (#V positions, #F faces of 3 to 255 corners) and the scalars
/// to colour it by (each #V or #F values, NaN where undefined).
struct ViewSurface {
  std::string name;
  PolygonMesh mesh;
  std::vector<ScalarField> fields;
  bool visible = true;  ///< shown when the page opens
};

struct ViewOptions {
  std::string title = "corrlap view";
  /// The field shown first: a field's name, "auto" (H if a surface has it, else the first field of
  /// the first surface with fields, else none) or "none" (grey surfaces).
  std::string initial_field = "auto";
  /// The colour scale of a field by name; absent: colour_scale (render_mesh.hpp) of the finite
  /// values of every surface's field of that name together, one range for all of them.
  std::map<std::string, ColourScale> scales;
  /// The first view: along -view_direction with `up` upwards, as render_mesh.
  Eigen::Vector3d view_direction{1.0, -1.4, 0.9};
  Eigen::Vector3d up{0.0, 0.0, 1.0};
  /// "side": the visible surfaces side by side along the screen's right axis (staircase beside
  /// result); "overlay": where they are.
  std::string layout = "side";
  /// The largest geometry (base64 text) a page may hold: a browser keeps it in one JavaScript string,
  /// which V8 limits to about 512 M characters, and the script needs some of that.
  std::size_t max_encoded_bytes = std::size_t(500) << 20;
  bool compress = true;  ///< zlib on the geometry (ignored in a build without zlib)
};

/// True when this build has the page's script (built with node and npm, cmake/CorrlapViewer.cmake).
bool has_viewer();
/// Throws Error saying how to get the viewer when the build has none.
void check_viewer();

/// The page. Throws InputError on no surface, an empty one, positions that are not finite or not
/// representable as float, a face with fewer than 3 or more than 255 corners or a missing vertex,
/// a field of the wrong size, an unknown initial field or layout, or a page too large for a browser (its
/// geometry over options.max_encoded_bytes once encoded); Error when the build has no viewer (has_viewer()).
std::string view_page(const std::vector<ViewSurface>& surfaces, const ViewOptions& options = {});

/// view_page written to `path`, which appears complete or not at all. Throws as view_page, and
/// IoError when the file cannot be written.
void write_view_page(const std::string& path, const std::vector<ViewSurface>& surfaces,
                     const ViewOptions& options = {});

}  // namespace corrlap
