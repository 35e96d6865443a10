#pragma once
// Pictures written by the commands: the scalar a user names, and the before/after pair of
// `regularize` drawn with one view and one colour range.
#include <CLI/CLI.hpp>
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/render/render_mesh.hpp>
#include <corrlap/render/view_page.hpp>
#include <optional>
#include <string>
#include <vector>

namespace corrlap::cli {

/// The finite number that is the whole of `text` ("0.9", "1e3"), or none (empty, trailing
/// characters, NaN, infinite).
std::optional<double> whole_number(const std::string& text);

/// `count` comma-separated finite numbers of an option's text ("1,-1.4,0.9"); InputError quoting
/// the text and the option otherwise.
std::vector<double> parse_numbers(const std::string& text, const std::string& option, std::size_t count);

/// --view and --up of `render` and `view`: the direction from the object towards the viewer and the
/// one drawn upwards, each "x,y,z"; not given: the library's defaults stay.
struct ViewDirectionOptions {
  std::string view, up;
  void add_options(CLI::App& command);
  /// Parsed into `direction` and `upwards` where given; InputError naming the option otherwise.
  void apply(Eigen::Vector3d& direction, Eigen::Vector3d& upwards) const;
};

/// The scalar `name` of a mesh file's attributes (vertex scalars first, then face scalars); "auto":
/// H if present, else the first vertex scalar, else none; "none": none. InputError listing the
/// scalars the file has when `name` is not among them.
std::optional<ScalarField> select_scalar(const MeshAttributes& attributes, const std::string& name,
                                         const std::string& file);

/// DIR/before.png and DIR/after.png: the two surfaces from the same direction, coloured by
/// `name` (vertex scalars before and after, or grey when empty) on one colour range. Returns the
/// seconds spent.
double render_before_after(const std::string& dir, const SurfelMesh& before, const SurfelMesh& after,
                           const std::string& name, const Eigen::VectorXd& scalar_before,
                           const Eigen::VectorXd& scalar_after);

/// A mesh file as a surface of a page (render/view_page.hpp): its PLY scalars become its fields.
ViewSurface read_view_surface(const std::string& file, const std::string& name);

/// Whether the page `file` (view.html beside a command's pictures) can be written: in a build
/// without the viewer, false and a note on stderr; the command's other outputs stand.
bool can_write_view(const std::string& file);

/// write_view_page, except that surfaces the page refuses (too large for a browser) give a note on
/// stderr instead of an error: the page is an extra, the command's other outputs stand.
void write_view_beside(const std::string& file, const std::vector<ViewSurface>& surfaces, const ViewOptions& options);

}  // namespace corrlap::cli
