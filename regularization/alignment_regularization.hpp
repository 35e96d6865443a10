#pragma once
// The paper's comparison baseline [17] (Coeurjolly et al.; the reference's
// DigitalSurfaceRegularization, docs/math.md §9.1): pointels moved so that the surfel edges become
// orthogonal to given normals, by the reference's gradient descent, or by a direct sparse solve of
// the same quadratic energy.
#include <Eigen/Core>
#include <corrlap/core/linear_solver.hpp>
#include <corrlap/core/surfel_mesh.hpp>

namespace corrlap {

struct AlignmentParams {
  double alpha = 0.001;  ///< data attachment
  double beta = 1.0;     ///< alignment of the edges with the face normals
  double gamma = 0.05;   ///< fairness (distance to the mean of the edge neighbours)
  int max_iterations = 200;
  double dt = 1.0;        ///< initial step
  double epsilon = 1e-4;  ///< stop when the step falls below it
  bool clamp = false;     ///< keep every coordinate within 0.5 voxel of its input value
};

struct AlignmentResult {
  Eigen::MatrixX3d positions;                       ///< #V x 3, world units (the input's)
  double energy_initial = 0.0, energy_final = 0.0;  ///< docs/math.md §9.1's E, grid units
  int iterations = 0;
};

/// docs/math.md §9.1's energy E at positions q (#V x 3, grid units), for the input p (grid units)
/// and unit face normals (#F x 3).
double alignment_energy(const SurfelMesh& mesh, const Eigen::MatrixX3d& face_normals, const Eigen::MatrixX3d& p,
                        const Eigen::MatrixX3d& q, const AlignmentParams& params = {});

/// The reference's descent (docs/math.md §9.1, bit for bit in its quirks): its gradient (the data
/// term's sign flipped, the alignment term on the first endpoint of each edge divided by the
/// pointel's surfel count, the fairness neighbours held fixed), the step adapted by 0.5 / 1.1, the
/// loop stopped at max_iterations or when the step falls below epsilon. energy_final is the energy
/// of the last evaluation, as the reference returns it. Works in grid units (positions / h).
/// Throws InputError for mismatched normals, an open surface or a parameter that is not finite
/// and positive (alpha, dt, epsilon; beta, gamma may be 0); NumericalError when the result fails
/// check_solution (solution_check.hpp), as alignment_minimizer.
AlignmentResult alignment_regularization(const SurfelMesh& mesh, const Eigen::MatrixX3d& face_normals,
                                         const AlignmentParams& params = {});

/// The exact minimizer of alignment_energy: E is quadratic in the 3 #V coordinates, so its minimum
/// solves H q = alpha p with the sparse SPD
///   H = alpha I + beta sum over surfel edges (a, b) of (e_a - e_b)(e_a - e_b)^T (x) n n^T
///       + gamma ((I - W)^T (I - W)) (x) I_3,
/// W the averaging over edge neighbours; one factorization and solve by `solver`. Not the
/// reference's result: its descent direction is not E's gradient (docs/math.md §9.1), so it
/// stops elsewhere, at a higher E. iterations is 0; positions in world units.
AlignmentResult alignment_minimizer(const SurfelMesh& mesh, const Eigen::MatrixX3d& face_normals, LinearSolver& solver,
                                    const AlignmentParams& params = {});

}  // namespace corrlap
