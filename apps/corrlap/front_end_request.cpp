#include "front_end_request.hpp"

#include <corrlap/core/linear_solver.hpp>

namespace corrlap::cli {

FrontEndRequest front_end_request(FrontEndRequest::Task task, const SurfaceSource& source, const NormalOptions& normals,
                                  const MethodOptions& method, const SolverOptions& solver) {
  FrontEndRequest r;
  r.task = task;
  r.implicit_shape = !source.shape.empty() || !source.polynomial.empty();
  r.volume_file = !source.volume.empty();
  r.normals = normals.source;
  r.normals_from_file = !normals.face_file.empty() || !normals.vertex_file.empty();
  r.method = method.method;
  r.method_parameters = method.config();
  r.solver = solver.config().get_string("solver", kDefaultLinearSolver);
  return r;
}

}  // namespace corrlap::cli
