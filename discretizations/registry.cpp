#include "registry.hpp"

#include <sstream>

#include "corrected_fem.hpp"
#include "cotan.hpp"
#include "heat_kernel.hpp"
#include "interpolated_corrected.hpp"
#include "polydec.hpp"
#include "virtual_refinement.hpp"

namespace corrlap {

namespace {
void register_builtin_discretizations(DiscretizationRegistry& r) {
  r.add("fem", "corrected FEM, face normals (docs/math.md §4)", make_corrected_fem);
  r.add("polydec", "PolyDEC of de Goes et al., uncorrected (docs/math.md §2)", make_polydec);
  r.add("projected-polydec", "Projected PolyDEC, face normals (docs/math.md §2.5)", make_projected_polydec);
  r.add("interpolated", "interpolated corrected calculus, vertex normals (docs/math.md §3)",
        make_interpolated_corrected);
  r.add("vrm", "virtual refinement of Bunge et al., uncorrected baseline (docs/math.md §5.1)", make_vrm);
  r.add("corrected-vrm", "corrected virtual refinement, vertex normals (docs/math.md §5.2)", make_corrected_vrm);
  r.add("heat-kernel", "heat-kernel Laplacian of Caissard et al., face normals (docs/math.md §6)", make_heat_kernel);
  r.add("cotan", "cotan Laplacian on the quads split into triangles", make_cotan);
}
}  // namespace

DiscretizationRegistry& discretization_registry() {
  static DiscretizationRegistry registry = [] {
    DiscretizationRegistry r("discretization");
    register_builtin_discretizations(r);
    return r;
  }();
  return registry;
}

std::unique_ptr<Discretization> make_discretization(const std::string& name) {
  return discretization_registry().create(name);
}

std::string method_parameters_markdown() {
  // "|" inside a cell would end it: Markdown tables escape it.
  const auto cell = [](const std::string& text) {
    std::string out;
    for (const char c : text) out += c == '|' ? std::string("\\|") : std::string(1, c);
    return out;
  };
  std::ostringstream os;
  os << "| method | parameter | type | default | allowed | meaning | docs/math.md |\n";
  os << "|---|---|---|---|---|---|---|\n";
  for (const std::string& name : discretization_registry().names())
    for (const Parameter& p : make_discretization(name)->parameters().items())
      os << "| `" << name << "` | `" << p.name << "` | " << to_string(p.type) << " | " << cell(p.default_text())
         << " | " << cell(p.allowed_text()) << " | " << cell(p.doc) << " | " << p.math << " |\n";
  return os.str();
}

}  // namespace corrlap
