#pragma once
// Principal-curvature editing (paper §4.3, docs/math.md §8.3 and §9.2): edit the principal
// curvatures of the estimated shape operator, rebuild it as S', integrate dn = S' into new normals
// n' (attached to the old ones), and regularize with n' and H' = tr(S') / 2.
//
// Convention: H is the mean of the principal curvatures, H = (k1 + k2) / 2 (the unit sphere has
// H = 1, Delta p = -2 H n), so H' = tr(S') / 2. The paper writes H' = Tr(S'), the sum; with its
// Delta p = -2 H n that would double the curvature of an unedited surface. k1 <= k2 as in
// corrlap's curvature estimates (paper Fig. 18 names the larger one k1).
#include <Eigen/Core>
#include <corrlap/core/linear_solver.hpp>
#include <corrlap/core/surfel_mesh.hpp>
#include <string>
#include <vector>

namespace corrlap {

/// One edit of one principal curvature.
struct PrincipalCurvatureEdit {
  enum class Kind { None, Scale, Set, Clamp };
  Kind kind = Kind::None;
  double value = 0.0;

  /// "scale:S" (k <- S k), "set:V" (k <- V), "clamp:V" (k <- clamp(k, -V, V), V >= 0); throws
  /// InputError naming the accepted forms otherwise.
  static PrincipalCurvatureEdit parse(const std::string& text);
  double apply(double k) const;
  bool active() const { return kind != Kind::None; }
  std::string describe() const;  ///< the parse() form, or "none"
};

/// S'_v = k1' d1 d1^T + k2' d2 d2^T per vertex (#V), with k' the edited principal curvatures and d
/// the unit principal directions (#V x 3 each). The estimator already removed the normal direction
/// from the eigen-decomposition (docs/math.md §8.3: it adds 1000 mu0 N N^T, the paper K n n^T with
/// K = 1e6; both discard the normal's eigenvalue), so k and d are the two tangent eigenpairs.
std::vector<Eigen::Matrix3d> edited_shape_operators(const Eigen::VectorXd& k1, const Eigen::VectorXd& k2,
                                                    const Eigen::MatrixX3d& d1, const Eigen::MatrixX3d& d2,
                                                    const PrincipalCurvatureEdit& edit1,
                                                    const PrincipalCurvatureEdit& edit2);

/// Unit normals n' (#V x 3) whose differential is S' (corrlap's discretization of "integrate
/// dn = S'", paper §4.3): the least-squares solution over the mesh edges (a, b) of
///     sum_e |n'_b - n'_a - (S'_a + S'_b)/2 (p_b - p_a)|^2 + lambda sum_v h^2 |n'_v - n_v|^2,
/// lambda = attachment / size^2, then normalized. S' is tangent (S' n = 0), so a staircase edge
/// counts by its projection on the tangent plane: the correction of the operators, applied to dn.
/// The normal equations (graph Laplacian + lambda h^2 I, SPD) are solved once for the three
/// coordinates. Throws InputError on sizes or a non-positive attachment, NumericalError when a
/// normal vanishes, SolverError from the solver.
Eigen::MatrixX3d integrate_shape_operator(const SurfelMesh& mesh, const std::vector<Eigen::Matrix3d>& S,
                                          const Eigen::MatrixX3d& normals, double size, double attachment,
                                          LinearSolver& solver);

}  // namespace corrlap
