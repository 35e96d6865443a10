// corrlap render: a PNG picture of a mesh file, shaded and coloured by one of its scalars
// (render/render_mesh.hpp). Headless and deterministic.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/io/output_folder.hpp>
#include <corrlap/render/render_mesh.hpp>
#include <iostream>
#include <sstream>

#include "command.hpp"
#include "render_output.hpp"

namespace corrlap::cli {
namespace {

struct RenderArgs {
  std::string mesh, scalar = "auto", size, range, colormap, out;
  ViewDirectionOptions directions;
  int supersampling = 2;
  bool no_legend = false;
};

void run(const RenderArgs& a) {
  RenderOptions o;
  o.supersampling = a.supersampling;
  o.legend = !a.no_legend;
  a.directions.apply(o.view_direction, o.up);
  if (!a.size.empty()) {
    // Each part judged, the message quoting the whole text the user gave.
    const auto pixels = [&](const std::string& part) {
      const std::optional<double> v = whole_number(part);
      if (!v || *v != std::floor(*v))
        throw InputError("--size '" + a.size + "': expected WIDTHxHEIGHT or WIDTH in whole pixels, e.g. 800x600");
      return int(std::clamp(*v, -1.0, 1e6));
    };
    const std::size_t x = a.size.find('x');
    o.width = pixels(a.size.substr(0, x));
    o.height = x == std::string::npos ? o.width : pixels(a.size.substr(x + 1));
  }
  if (!a.range.empty()) {
    const auto r = parse_numbers(a.range, "--range", 2);
    o.range_min = r[0];
    o.range_max = r[1];
  }
  if (!a.colormap.empty()) o.colormap = parse_colormap(a.colormap);

  StagedFile out(a.out);  // checked before the computation
  const auto t0 = std::chrono::steady_clock::now();
  MeshAttributes attributes;
  const PolygonMesh mesh = read_mesh(a.mesh, &attributes);
  const std::optional<ScalarField> field = select_scalar(attributes, a.scalar, a.mesh);
  const auto t1 = std::chrono::steady_clock::now();
  const Image image = render_mesh(mesh, field ? &*field : nullptr, o);
  const auto t2 = std::chrono::steady_clock::now();
  write_png(out.path(), image);
  out.commit();
  std::cerr << "render: " << mesh.faces.size() << " faces" << (field ? ", coloured by '" + field->name + "'" : "")
            << ", " << image.width << " x " << image.height << " in " << std::chrono::duration<double>(t2 - t1).count()
            << " s (read " << std::chrono::duration<double>(t1 - t0).count() << " s)\n  wrote " << a.out << "\n";
}

RegisterCommand reg(43, "render", [](CLI::App& app) {
  auto args = std::make_shared<RenderArgs>();
  auto* cmd = app.add_subcommand("render", "a PNG picture of a mesh (OBJ, PLY, OFF), coloured by a PLY scalar");
  cmd->add_option("mesh", args->mesh, "mesh file")->required()->check(CLI::ExistingFile);
  cmd->add_option("--scalar", args->scalar,
                  "vertex or face scalar of a PLY file to colour by; auto: H if present, else the first vertex "
                  "scalar, else none; none: grey")
      ->capture_default_str();
  args->directions.add_options(*cmd);
  cmd->add_option("--size", args->size, "picture size in pixels, W or WxH (default 800x800; legend included)");
  cmd->add_option("--range", args->range,
                  "colour range MIN,MAX (default: the 2nd-98th percentiles, symmetric about 0 for signed fields)");
  cmd->add_option("--colormap", args->colormap,
                  "sequential | diverging (default: diverging when the range contains 0, else sequential)")
      ->check(CLI::IsMember({"sequential", "diverging"}));
  cmd->add_option("--supersampling", args->supersampling, "s x s samples per pixel (1..4)")
      ->check(CLI::Range(1, 4))
      ->capture_default_str();
  cmd->add_flag("--no-legend", args->no_legend, "no colour bar");
  cmd->add_option("--out", args->out, "output PNG file")->required();
  cmd->callback([args] { run(*args); });
});

}  // namespace
}  // namespace corrlap::cli
