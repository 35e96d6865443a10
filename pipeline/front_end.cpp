#include "front_end.hpp"

namespace corrlap {

std::string to_string(FrontEnd front_end) { return front_end == FrontEnd::Distributed ? "distributed" : "serial"; }

FrontEnd choose_front_end(const FrontEndRequest& r) {
#if defined(CORRLAP_WITH_PETSC)
  // distributed/ assembles the fem method's consistent mass from the faces' true normals (shapes
  // only) or II normals (their halo around the slab); other normals and methods are not distributed.
  const bool surface = r.implicit_shape || r.volume_file;
  const bool normals =
      !r.normals_from_file && (r.normals == "auto" || r.normals == "ii" || (r.normals == "true" && r.implicit_shape));
  const bool surface_and_operators = surface && normals && r.method == "fem" && r.method_parameters.empty();
  const bool problem =
      (r.task == FrontEndRequest::Task::Poisson && r.rhs_from_test_function && r.solver == "petsc") ||
      (r.task == FrontEndRequest::Task::Eigen && r.solver == "slepc") ||
      (r.task == FrontEndRequest::Task::Regularize && r.solver == "petsc" && !r.serial_only_regularization);
  return surface_and_operators && problem ? FrontEnd::Distributed : FrontEnd::Serial;
#else
  (void)r;
  return FrontEnd::Serial;
#endif
}

}  // namespace corrlap
