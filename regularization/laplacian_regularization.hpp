#pragma once
// The paper's Laplacian regularization (paper §4.1, docs/math.md §9.2): vertex positions p' whose
// Laplacian matches -2 H n, the mean-curvature normal estimated on the staircased surface, while
// staying close to the input positions p.
#include <Eigen/Core>
#include <Eigen/Sparse>
#include <corrlap/core/linear_solver.hpp>
#include <cstdint>
#include <functional>

namespace corrlap {

/// The lumped mass M_l = diag(M 1) (#V x #V, diagonal). Throws InputError when a row sum is not
/// positive (a vertex without area: M_l^{-1} would not exist).
Eigen::SparseMatrix<double> lumped_mass(const Eigen::SparseMatrix<double>& M);

/// The default weight of the attachment term: alpha = alpha0 / h^2 (docs/math.md §9.2, alpha0 = 10),
/// so that both terms scale alike under refinement (L p' ~ h^2 per vertex, p' - p ~ h). alpha0 = 0
/// (no attachment, regularize_positions_unattached) gives 0; a negative or non-finite alpha0 throws.
double regularization_alpha(double h, double alpha0 = 10.0);

/// The largest attachment weight alpha whose system the solve represents in double precision, for
/// a surface of area at most `area` (the sum of M_l) whose coordinates are at most `reach` in
/// absolute value. The right-hand side alpha M_l p is bounded by alpha area reach, and the solvers
/// form inner products of such vectors (their squares) and products with A (a third factor): the
/// bound keeps alpha area reach at or below kMaxAttachmentScale, whose cube stays finite.
double max_regularization_alpha(double area, double reach);
inline constexpr double kMaxAttachmentScale = 1e90;

/// docs/math.md §9.2: the minimizer p' (#V x 3) of |M_l^{-1} L p' + 2 H n|^2_{M_l} + alpha |p' - p|^2_{M_l},
/// from its normal equations
///     (L M_l^{-1} L + alpha M_l) p' = alpha M_l p - 2 L (H n),
/// one factorization of the SPD matrix and three right-hand sides (the coordinates).
/// L, M: #V x #V (L symmetric negative semi-definite, M the mass, lumped here); p, normals: #V x 3
/// (normals unit); H: #V mean curvatures (the unit sphere has H = 1 with outward normals, so that
/// Delta p = -2 H n). Throws InputError on mismatched sizes, non-finite inputs, alpha <= 0 or above
/// max_regularization_alpha; SolverError from the solver. With exact data (L p = -2 M_l H n) it
/// returns p. `report`, if given, receives the relative residual of the normal equations.
Eigen::MatrixX3d regularize_positions(const Eigen::SparseMatrix<double>& L, const Eigen::SparseMatrix<double>& M,
                                      const Eigen::MatrixX3d& p, const Eigen::MatrixX3d& normals,
                                      const Eigen::VectorXd& H, double alpha, LinearSolver& solver,
                                      SolverReport* report = nullptr);

/// The same p' as regularize_positions without forming L M_l^{-1} L, whose two-ring pattern makes
/// its Cholesky factor several times denser than L's. With B = beta M_l - L, beta = sqrt(alpha),
/// the matrix
///     P = B M_l^{-1} B = L M_l^{-1} L + alpha M_l - 2 beta L
/// bounds A = L M_l^{-1} L + alpha M_l spectrally: in the eigenbasis of -L v = lambda M_l v
/// (lambda >= 0) the eigenvalues of P^{-1} A are (lambda^2 + alpha) / (lambda + beta)^2, in [1/2, 1].
/// So CG on A preconditioned by P (two solves with one factorization of B, which has L's pattern)
/// converges in about 15 iterations whatever h. `solver` factorizes B; it must be a direct solver
/// (a fixed preconditioner). Throws as regularize_positions, SolverError NotPositiveDefinite when
/// B is not (L not negative semi-definite: use regularize_positions), NoConvergence from CG.
///
/// How far it iterates: with `accuracy` = 0, to rounding (relative residual 1e-10 or a
/// componentwise backward error of 1e-12). With `accuracy` > 0 (world units), until every
/// coordinate's error is provably below it in the area-weighted RMS sense,
///     |q - p'|_{M_l} / sqrt(area) <= accuracy,   area = sum of M_l,
/// by the bound |e|_{M_l}^2 <= |e|_A^2 / alpha = r^T A^{-1} r / alpha <= 2 r^T P^{-1} r / alpha
/// (A >= alpha M_l, and A >= P / 2 above) on the true residual r = b - A q, or to rounding if that
/// comes first. `report`, if given, receives the CG iterations and the relative residual;
/// `error_bound`, if given, the bound reached (world units; with accuracy 0, computed at the end).
Eigen::MatrixX3d regularize_positions_preconditioned(const Eigen::SparseMatrix<double>& L,
                                                     const Eigen::SparseMatrix<double>& M, const Eigen::MatrixX3d& p,
                                                     const Eigen::MatrixX3d& normals, const Eigen::VectorXd& H,
                                                     double alpha, LinearSolver& solver, SolverReport* report = nullptr,
                                                     double accuracy = 0.0, double* error_bound = nullptr);

/// regularize_positions_preconditioned for several alpha on one surface, e.g. the trials of the
/// automatic alpha0 (docs/math.md §9.4). B's pattern does not depend on alpha, so `solver` analyzes it
/// once and each solve only factorizes; a solve can start from an earlier one's positions, which
/// are closer to its solution than 0 is. L, p and `solver` are kept by reference and must outlive
/// this; `solver` is this object's alone while it lives.
class PreconditionedRegularization {
 public:
  /// Checks the inputs as regularize_positions_preconditioned.
  PreconditionedRegularization(const Eigen::SparseMatrix<double>& L, const Eigen::SparseMatrix<double>& M,
                               const Eigen::MatrixX3d& p, const Eigen::MatrixX3d& normals, const Eigen::VectorXd& H,
                               LinearSolver& solver);
  /// The same system with its curvature term given whole: (L M_l^{-1} L + alpha M_l) q = alpha M_l p + g,
  /// g (#V x 3, finite) in place of -2 L (H n): patch_attachment_bias solves on a patch with the
  /// positions outside it held, where the curvature term has the held vertices' part too.
  PreconditionedRegularization(const Eigen::SparseMatrix<double>& L, const Eigen::SparseMatrix<double>& M,
                               const Eigen::MatrixX3d& p, const Eigen::MatrixX3d& g, LinearSolver& solver);
  /// p' for this alpha, as regularize_positions_preconditioned, with CG started from `start`
  /// (#V x 3, finite) when given, else from 0.
  Eigen::MatrixX3d solve(double alpha, double accuracy = 0.0, SolverReport* report = nullptr,
                         double* error_bound = nullptr, const Eigen::MatrixX3d* start = nullptr);

 private:
  const Eigen::SparseMatrix<double>& L_;
  const Eigen::MatrixX3d& p_;
  Eigen::MatrixX3d curvature_rhs_;
  Eigen::VectorXd mass_, inverse_mass_;
  Eigen::SparseMatrix<double> lumped_mass_;
  LinearSolver& solver_;
  bool analyzed_ = false;
};

/// The iteration of PreconditionedRegularization::solve on A q = b, A = L M_l^{-1} L + alpha M_l, for
/// rows held in one place or split over parts (MPI ranks: distributed/distributed_regularization.hpp).
/// The caller gives the products on its rows; the passes, tolerances and acceptance tests are
/// this one function's, so that every part and the serial solve take the same steps.
struct PreconditionedSystem {
  Eigen::Index rows = 0;        ///< the rows held here
  std::int64_t total_rows = 0;  ///< over all parts (CG's iteration limit is 2 n)
  double alpha = 0.0;
  double area = 0.0;                                                    ///< the sum of M_l over all parts
  std::function<Eigen::MatrixXd(const Eigen::MatrixXd&)> multiply;      ///< A X (rows by k)
  std::function<Eigen::MatrixXd(const Eigen::MatrixXd&)> precondition;  ///< P^{-1} R, P = B M_l^{-1} B
  /// |L| M_l^{-1} |L| X + alpha M_l X for X >= 0: the scale of A q's rounding (the backward error).
  std::function<Eigen::MatrixXd(const Eigen::MatrixXd&)> absolute_multiply;
  /// Sums k per-column partial sums over the parts, in place; absent with one part.
  std::function<void(Eigen::ArrayXd&)> sum_over_parts;
  /// The largest of a value over the parts; absent with one part.
  std::function<double(double)> max_over_parts;
};

/// q with A q = rhs (rows by k) as PreconditionedRegularization::solve stops (its `accuracy`),
/// CG started from `start` when given, else from 0. `report`: the CG iterations, relative residual,
/// status and message; `error_bound`: the bound reached (also with accuracy 0). Throws
/// NumericalError on a non-finite iterate and SolverError NoConvergence after three passes short
/// of the stopping rule, on every part alike.
Eigen::MatrixXd solve_preconditioned(const PreconditionedSystem& system, const Eigen::MatrixXd& rhs,
                                     const Eigen::MatrixXd* start, double accuracy, SolverReport* report,
                                     double* error_bound);

/// docs/math.md §9.3: the same energy without the attachment (alpha = 0, paper Fig. 11), whose
/// minimizers solve L p' = g' (g = -2 M_l H n projected onto the range of L) and are unique up to a
/// translation per connected component of L's graph; each component is placed with its
/// M_l-weighted centroid at the input's. One vertex per component is held while `solver` factorizes
/// -L without it (#V - C by #V - C, SPD for a negative semi-definite L). Throws as
/// regularize_positions (without alpha), and SolverError NotPositiveDefinite when -L is not
/// (the message says so). `report`, if given, receives the relative residual |L p' - g'| / |g'|.
Eigen::MatrixX3d regularize_positions_unattached(const Eigen::SparseMatrix<double>& L,
                                                 const Eigen::SparseMatrix<double>& M, const Eigen::MatrixX3d& p,
                                                 const Eigen::MatrixX3d& normals, const Eigen::VectorXd& H,
                                                 LinearSolver& solver, SolverReport* report = nullptr);

/// The two terms of the energy above at positions q (for reports): the Laplacian term
/// |M_l^{-1} L q + 2 H n|^2_{M_l} and the attachment term |q - p|^2_{M_l} (without alpha).
struct RegularizationEnergy {
  double laplacian = 0.0;
  double attachment = 0.0;
};
RegularizationEnergy regularization_energy(const Eigen::SparseMatrix<double>& L, const Eigen::SparseMatrix<double>& M,
                                           const Eigen::MatrixX3d& p, const Eigen::MatrixX3d& normals,
                                           const Eigen::VectorXd& H, const Eigen::MatrixX3d& q);

}  // namespace corrlap
