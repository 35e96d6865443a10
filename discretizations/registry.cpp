#include "registry.hpp"

#include "corrected_fem.hpp"
#include "interpolated_corrected.hpp"
#include "polydec.hpp"

namespace corrlap {

namespace {
void register_builtin_discretizations(DiscretizationRegistry& r) {
  (void)r;  // each method's file pair adds one line here: r.add("fem", "...", [] { ... });
  r.add("fem", "corrected FEM, face normals (spec §4)", make_corrected_fem);
  r.add("polydec", "PolyDEC of de Goes et al., uncorrected (spec §2)", make_polydec);
  r.add("projected-polydec", "Projected PolyDEC, face normals (spec §2.5)", make_projected_polydec);
  r.add("interpolated", "interpolated corrected calculus, vertex normals (spec §3)", make_interpolated_corrected);
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

}  // namespace corrlap
