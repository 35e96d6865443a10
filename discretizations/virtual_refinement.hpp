#pragma once
// Virtual refinement (paper §2.3; docs/math.md §5): every quad is refined into a fan of four triangles
// around a virtual point p = sum_k w_k x_k, triangle stiffness/mass are assembled on the fan and
// restricted back to the quad with the prolongation P_f = [I_4; w^T] (K_f = P^T K_fan P).
//   - "vrm": the uncorrected baseline of Bunge et al. (pmp-library laplace.cpp, docs/math.md §5.1);
//   - "corrected-vrm": the corrected variant of the paper with vertex normals (docs/math.md §5.2).
// The local kernels below are pure functions of the corners (and normals): they are testable
// without a mesh. Positive stiffness K (the global L is -sum K_f, docs/math.md §0).
#include <Eigen/Core>
#include <corrlap/core/discretization.hpp>
#include <memory>

#include "triangle_kernels.hpp"

namespace corrlap {

using QuadPositions = Eigen::Matrix<double, 4, 3, Eigen::RowMajor>;  ///< corner k in row k

// ----------------------------------------------------------------- uncorrected VRM (docs/math.md §5.1)

/// Weights of the virtual vertex of a quad: minimizer of sum_k ||(x_k - p) x d_k||^2, p = sum w_j x_j,
/// sum w_j = 1, as the least-squares / minimum-norm solution of pmp's 5x4 system (complete
/// orthogonal decomposition). The corners are centred first (the minimizer is translation
/// invariant; centring only improves the conditioning). Surfels give w = (1/4, 1/4, 1/4, 1/4).
Eigen::Vector4d vrm_virtual_weights(const QuadPositions& X);

/// Local result of a virtual-refinement kernel.
struct VrmLocal {
  Eigen::Matrix4d K = Eigen::Matrix4d::Zero();          ///< positive stiffness P^T K_fan P
  Eigen::Matrix4d M = Eigen::Matrix4d::Zero();          ///< mass (diagonal when lumped)
  Eigen::Vector4d w = Eigen::Vector4d::Constant(0.25);  ///< virtual-point weights
  int skipped_triangles = 0;                            ///< fan triangles with A <= DBL_MIN (ignored)
};

/// Uncorrected VRM of one quad (docs/math.md §5.1): K_f = P^T K_fan P, M_f = diag(row sums of P^T M_fan P).
/// Surfel closed form: K_f = I - 11^T/4, M_f = h^2/4 I.
VrmLocal vrm_local(const QuadPositions& X);

// ------------------------------------------------------------------- corrected VRM (docs/math.md §5.2)

/// Options of the virtual-point minimizer (docs/math.md §5.2; defaults are docs/math.md's).
struct VirtualPointOptions {
  int max_iterations = 50;
  double gradient_tolerance = 1e-12;  ///< on |grad E/h^4|
  double clamp = 1e-6;                ///< (s0, t0) stays in [clamp, 1 - clamp]^2
};

/// Outcome of the minimizer.
struct VirtualPoint {
  double s = 0.5, t = 0.5;
  int iterations = 0;
  bool converged = false;
  double gradient_norm = 0.0;  ///< |grad E/h^4| at the returned point
  double energy = 0.0;         ///< E/h^4
};

/// Areas of the four parameter-fan triangles weighted by U(s,t) = sum_k phi_k(s,t) uz_k, i.e.
/// A_i / (parallelogram area) of docs/math.md §5.2, by the exact edge-midpoint rule. Optional gradient
/// (4x2: dA_i/ds, dA_i/dt) and Hessians (Hs[i] 2x2).
Eigen::Vector4d corrected_fan_areas(const Eigen::Vector4d& uz, double s, double t,
                                    Eigen::Matrix<double, 4, 2>* gradient = nullptr,
                                    Eigen::Matrix2d* hessians = nullptr);

/// Energy E/h^4 = sum_i (A_i/h^2)^2 with analytic gradient and Hessian.
double corrected_fan_energy(const Eigen::Vector4d& uz, double s, double t, Eigen::Vector2d* gradient = nullptr,
                            Eigen::Matrix2d* hessian = nullptr);

/// Minimizes the energy (docs/math.md §5.2): Newton from (1/2, 1/2) with backtracking, gradient steps of
/// size 1/mean(uz)^2 when the Hessian is not positive definite, clamped to the box.
/// Converged when |grad| < tolerance, or when the point is stationary up to round-off (no
/// decrease of E is representable and |grad| < 1e-9), or when it sits on the clamp box with the
/// gradient pushing outward there (constrained minimum; only possible with inconsistent normals).
VirtualPoint minimize_virtual_point(const Eigen::Vector4d& uz, const VirtualPointOptions& options = {});

/// Corrected VRM of one quad (docs/math.md §5.2). U holds the four unit vertex normals (row k = corner k),
/// n the outward unit trivial normal; the parametric area is |(x1-x0) x (x3-x0)| (h^2 on surfels).
/// Corrected lengths |e x u_T| with u_T = normalize(u_i + u_{i+1} + u_p), 1/2 cot stiffness on them,
/// lumped barycentric triangle mass A_i/3, M_f = P^T M_fan P (full 4x4) or its row-sum lumping.
struct CorrectedVrmLocal : VrmLocal {
  VirtualPoint point;
  Eigen::Vector4d areas = Eigen::Vector4d::Zero();  ///< A_i (world units)
};
CorrectedVrmLocal corrected_vrm_local(const QuadPositions& X, const QuadPositions& U, const Eigen::Vector3d& n,
                                      bool lumped_mass = false, const VirtualPointOptions& options = {});

/// The registered discretizations. "vrm": no parameters. "corrected-vrm": mass = full | lumped,
/// max_iterations, gradient_tolerance, and the normal policy keys (orientation also decides what
/// a non-convergent minimizer does: error throws NumericalError, warn/clamp report it).
std::unique_ptr<Discretization> make_vrm();
std::unique_ptr<Discretization> make_corrected_vrm();

}  // namespace corrlap
