#include "registry.hpp"

namespace corrlap {

namespace {
void register_builtin_discretizations(DiscretizationRegistry& r) {
  (void)r;  // each method's file pair adds one line here: r.add("fem", "...", [] { ... });
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
