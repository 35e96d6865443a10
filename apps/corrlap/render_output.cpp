#include "render_output.hpp"

#include <chrono>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/core/polygon_mesh.hpp>
#include <iostream>
#include <sstream>

namespace corrlap::cli {

std::optional<double> whole_number(const std::string& text) {
  std::size_t used = 0;
  double x = 0.0;
  try {
    x = std::stod(text, &used);
  } catch (const std::exception&) {
    return std::nullopt;
  }
  if (used != text.size() || !std::isfinite(x)) return std::nullopt;
  return x;
}

std::vector<double> parse_numbers(const std::string& text, const std::string& option, std::size_t count) {
  std::vector<double> v;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    const std::optional<double> x = whole_number(item);
    if (!x) throw InputError(option + " '" + text + "': '" + item + "' is not a number");
    v.push_back(*x);
  }
  if (v.size() != count)
    throw InputError(option + " '" + text + "': expected " + std::to_string(count) + " comma-separated numbers");
  return v;
}

void ViewDirectionOptions::add_options(CLI::App& command) {
  command.add_option("--view", view, "direction from the object towards the viewer, x,y,z (default 1,-1.4,0.9)");
  command.add_option("--up", up, "direction drawn upwards, x,y,z (default 0,0,1)");
}

void ViewDirectionOptions::apply(Eigen::Vector3d& direction, Eigen::Vector3d& upwards) const {
  if (!view.empty()) {
    const std::vector<double> v = parse_numbers(view, "--view", 3);
    direction = Eigen::Vector3d(v[0], v[1], v[2]);
  }
  if (!up.empty()) {
    const std::vector<double> v = parse_numbers(up, "--up", 3);
    upwards = Eigen::Vector3d(v[0], v[1], v[2]);
  }
}

std::optional<ScalarField> select_scalar(const MeshAttributes& attributes, const std::string& name,
                                         const std::string& file) {
  if (name == "none") return std::nullopt;
  const auto vertex = [&](const std::string& n) { return ScalarField{n, attributes.vertex_scalars.at(n), false}; };
  if (name == "auto") {
    if (attributes.vertex_scalars.count("H")) return vertex("H");
    if (!attributes.vertex_scalars.empty()) return vertex(attributes.vertex_scalars.begin()->first);
    return std::nullopt;
  }
  if (attributes.vertex_scalars.count(name)) return vertex(name);
  if (attributes.face_scalars.count(name)) return ScalarField{name, attributes.face_scalars.at(name), true};
  std::string names;
  for (const auto& [n, v] : attributes.vertex_scalars) names += " " + n;
  for (const auto& [n, v] : attributes.face_scalars) names += " " + n + "(face)";
  throw InputError(file + " has no scalar '" + name + "'" +
                   (names.empty() ? std::string(" (it has none; only PLY files carry scalars)") : "; it has:" + names));
}

double render_before_after(const std::string& dir, const SurfelMesh& before, const SurfelMesh& after,
                           const std::string& name, const Eigen::VectorXd& scalar_before,
                           const Eigen::VectorXd& scalar_after) {
  const auto t0 = std::chrono::steady_clock::now();
  RenderOptions o;
  std::optional<ScalarField> b, a;
  if (scalar_before.size() > 0) {
    b = ScalarField{name, scalar_before, false};
    a = ScalarField{name, scalar_after, false};
    // One range for both pictures: the automatic range of the values after (the smooth surface's
    // values; before, the staircase's are noisier and would widen it).
    const ColourScale scale = colour_scale(*a, o);
    o.range_min = scale.min;
    o.range_max = scale.max;
    o.colormap = scale.map;
  }
  write_png(dir + "/before.png", render_mesh(to_polygon_mesh(before), b ? &*b : nullptr, o));
  write_png(dir + "/after.png", render_mesh(to_polygon_mesh(after), a ? &*a : nullptr, o));
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

ViewSurface read_view_surface(const std::string& file, const std::string& name) {
  MeshAttributes attributes;
  ViewSurface s;
  s.name = name;
  s.mesh = read_mesh(file, &attributes);
  for (auto& [n, v] : attributes.vertex_scalars) s.fields.push_back({n, std::move(v), false});
  // A file may have a vertex and a face scalar of one name (corrlap curvature writes H at both): the
  // face one is told apart.
  for (auto& [n, v] : attributes.face_scalars)
    s.fields.push_back({attributes.vertex_scalars.count(n) ? n + " (faces)" : n, std::move(v), true});
  return s;
}

bool can_write_view(const std::string& file) {
  if (has_viewer()) return true;
  std::cerr << "note: " << file << " not written: this build has no viewer (it needs node and npm at build time)\n";
  return false;
}

void write_view_beside(const std::string& file, const std::vector<ViewSurface>& surfaces, const ViewOptions& options) {
  try {
    write_view_page(file, surfaces, options);
  } catch (const IoError&) {
    throw;  // the folder the other outputs went to cannot take it either: a real failure
  } catch (const InputError& e) {
    std::cerr << "note: " << file << " not written: " << e.what() << "\n";
  }
}

}  // namespace corrlap::cli
