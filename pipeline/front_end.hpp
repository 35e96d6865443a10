#pragma once
// Which front end computes a command (docs/distributed.md): the serial one, where every rank builds
// the whole grid, surface and operators and only the solve is shared, or the distributed one, where
// each rank builds its slab's share. One decision for every caller: the CLI and the Python module
// describe their command in a FrontEndRequest and run what this returns.
#include <corrlap/core/config.hpp>
#include <string>

namespace corrlap {

enum class FrontEnd { Serial, Distributed };

/// "serial" or "distributed", as the CLI reports it.
std::string to_string(FrontEnd front_end);

/// What a command asks for, in the terms the choice depends on.
struct FrontEndRequest {
  enum class Task { Poisson, Heat, Eigen, Regularize };
  Task task = Task::Poisson;
  bool implicit_shape = false;     ///< the surface digitizes a shape (--shape, --polynomial), not a file
  bool volume_file = false;        ///< the surface is read from a volume file (--volume)
  std::string normals = "auto";    ///< the normals' source: auto, true, ii, trivial, convolved
  bool normals_from_file = false;  ///< face or vertex normals read from a file
  std::string method = "fem";
  Config method_parameters;            ///< the method's parameters that were given (any takes the serial one)
  std::string solver;                  ///< the solver's name: the linear solver, or eigs's eigen solver
  bool rhs_from_test_function = true;  ///< Poisson: b from a test function, not from a file
  /// Regularize: what only the serial regularization does (principal curvature edits, the
  /// unattached solve alpha0 = 0, the alignment baseline, every label of a volume).
  bool serial_only_regularization = false;
};

/// The distributed front end exactly when it computes the command's own result, in a build with
/// PETSc (-DCORRLAP_WITH_PETSC=ON): the digitization of an implicit shape or a volume file, with
/// true normals (shapes) or II normals (`auto` means true for a shape, II for a volume), the fem
/// method with its default parameters (consistent mass), and
///  - Poisson: a test function for b and the `petsc` solver, with any of its options;
///  - Eigen: the `slepc` eigen solver, with any of its options;
///  - Regularize: the `petsc` solver (a direct one: MUMPS by default), without what only the serial
///    regularization does (FrontEndRequest::serial_only_regularization).
/// The heat system, meshes, other normals and methods, and every other solver take the serial
/// front end. What the distributed one can only refuse once it reads the input or builds the
/// surface (a degenerate voxel-to-physical map, pinched voxels, II parameters it does not
/// distribute, normals the serial method would clamp) is refused on every rank with an InputError
/// (distributed/distributed_problem.hpp), and the caller then runs the serial one.
FrontEnd choose_front_end(const FrontEndRequest& request);

}  // namespace corrlap
