// corrlap view: one HTML page of mesh files to turn around in a browser, coloured by their scalars
// (render/view_page.hpp). Self-contained: no server and no network when it is opened.
#include <chrono>
#include <corrlap/core/error.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/io/output_folder.hpp>
#include <corrlap/render/view_page.hpp>
#include <filesystem>
#include <iostream>
#include <set>

#include "command.hpp"
#include "render_output.hpp"

namespace corrlap::cli {
namespace {

struct ViewArgs {
  std::vector<std::string> meshes;
  std::string scalar = "auto", title, layout = ViewOptions{}.layout, out;
  ViewDirectionOptions directions;
};

// The file names without their folders and extensions, or the paths as given when two would be equal.
std::vector<std::string> surface_names(const std::vector<std::string>& files) {
  std::vector<std::string> names;
  std::set<std::string> seen;
  bool distinct = true;
  for (const std::string& f : files) {
    names.push_back(std::filesystem::path(f).stem().string());
    distinct = seen.insert(names.back()).second && distinct;
  }
  return distinct ? names : files;
}

void run(const ViewArgs& a) {
  StagedFile out(a.out);  // checked before the meshes are read, as the options
  check_viewer();
  const std::vector<std::string> names = surface_names(a.meshes);
  ViewOptions o;
  o.title = !a.title.empty() ? a.title : "corrlap view: " + names.front() + (names.size() > 1 ? ", ..." : "");
  o.initial_field = a.scalar;
  o.layout = a.layout;
  a.directions.apply(o.view_direction, o.up);
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<ViewSurface> surfaces;
  std::size_t faces = 0;
  for (std::size_t i = 0; i < a.meshes.size(); ++i) {
    surfaces.push_back(read_view_surface(a.meshes[i], names[i]));
    faces += surfaces.back().mesh.faces.size();
  }
  const auto t1 = std::chrono::steady_clock::now();
  write_view_page(out.path(), surfaces, o);
  out.commit();
  std::cerr << "view: " << surfaces.size() << (surfaces.size() == 1 ? " surface, " : " surfaces, ") << faces
            << " faces in " << std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count()
            << " s (read " << std::chrono::duration<double>(t1 - t0).count() << " s)\n  wrote " << a.out << " ("
            << (std::filesystem::file_size(a.out) >> 10) << " KB; open it in a browser)\n";
}

RegisterCommand reg(43, "view", [](CLI::App& app) {
  auto args = std::make_shared<ViewArgs>();
  auto* cmd = app.add_subcommand(
      "view", "an HTML page of meshes (OBJ, PLY, OFF) to turn around in a browser, coloured by their PLY scalars");
  cmd->add_option("meshes", args->meshes, "mesh files, shown together (overlaid or side by side)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--scalar", args->scalar,
                  "scalar shown first; auto: H if a mesh has it, else the first scalar, else none; none: grey")
      ->capture_default_str();
  cmd->add_option("--layout", args->layout, "several meshes: side (side by side) or overlay (where they are)")
      ->check(CLI::IsMember({"side", "overlay"}))
      ->capture_default_str();
  args->directions.add_options(*cmd);  // the first view
  cmd->add_option("--title", args->title, "the page's title (default: the first mesh's name)");
  cmd->add_option("--out", args->out, "output HTML file")->required();
  cmd->callback([args] { run(*args); });
});

}  // namespace
}  // namespace corrlap::cli
