#include "front_end.hpp"

namespace corrlap {

std::string to_string(FrontEnd front_end) { return front_end == FrontEnd::Distributed ? "distributed" : "serial"; }

FrontEnd choose_front_end(const FrontEndRequest& r) {
#if defined(CORRLAP_WITH_PETSC)
  // distributed/ assembles the fem method's consistent mass from each face's true normal, which
  // needs no neighbouring voxels: any other normal or method would need a halo around the slab.
  const bool surface_and_operators = r.implicit_shape && (r.normals == "auto" || r.normals == "true") &&
                                     !r.normals_from_file && r.method == "fem" && r.method_parameters.empty();
  const bool problem = (r.task == FrontEndRequest::Task::Poisson && r.rhs_from_test_function && r.solver == "petsc") ||
                       (r.task == FrontEndRequest::Task::Eigen && r.solver == "slepc");
  return surface_and_operators && problem ? FrontEnd::Distributed : FrontEnd::Serial;
#else
  (void)r;
  return FrontEnd::Serial;
#endif
}

}  // namespace corrlap
