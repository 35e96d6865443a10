#pragma once
// The part of choose_front_end's request (pipeline/front_end.hpp) that comes from the options every
// computing command shares: one place, so that solve, eigs and regularize describe their input alike.
#include <corrlap/pipeline/front_end.hpp>

#include "method_options.hpp"
#include "normal_options.hpp"
#include "solver_options.hpp"
#include "surface_source.hpp"

namespace corrlap::cli {

/// `task`, the kind of surface input, the normals' source, the method with its given parameters,
/// and the solver's name (--solver, else the default linear solver). The task's own fields
/// (rhs_from_test_function, serial_only_regularization) are left to the command.
FrontEndRequest front_end_request(FrontEndRequest::Task task, const SurfaceSource& source, const NormalOptions& normals,
                                  const MethodOptions& method, const SolverOptions& solver);

}  // namespace corrlap::cli
