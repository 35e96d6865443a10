#pragma once
// The regularization's solve (docs/math.md §9.2) on a DistributedFem: the normal equations
//     (L M_l^{-1} L + alpha M_l) p' = alpha M_l p - 2 L (H n)
// by CG preconditioned with P = B M_l^{-1} B, B = sqrt(alpha) M_l - L, as
// regularize_positions_preconditioned (regularization/laplacian_regularization.hpp), with B
// factorized by the petsc backend (MUMPS's Cholesky) and every vector held per rank.
#include <Eigen/Core>
#include <corrlap/backends/petsc.hpp>
#include <corrlap/regularization/attachment_bias.hpp>
#include <corrlap/regularization/laplacian_regularization.hpp>

#include "distributed_fem.hpp"
#include "distributed_surface.hpp"

namespace corrlap {

struct DistributedRegularization {
  Eigen::MatrixX3d positions;  ///< num_owned x 3: p' at this rank's owned vertices
  int iterations = 0;          ///< CG iterations, all passes
  double residual = 0.0;       ///< |b - A p'| / |b| of the normal equations, worst coordinate
  /// The bound on each coordinate's error, |p' - exact|_{M_l} / sqrt(area) (world units), as
  /// regularize_positions_preconditioned's `error_bound`.
  double error_bound = 0.0;
};

/// regularize_positions_preconditioned(L, M, p, normals, H, alpha, solver, report, accuracy) on the
/// distributed operators: p, normals (unit) and H at the owned vertices (#owned rows). With
/// accuracy 0, CG runs to a relative residual of 1e-10 (refining from the true residual, at most 3
/// passes); with accuracy > 0 (world units), until the error bound is below it. `solver` must be a
/// direct petsc solver (a fixed preconditioner: pc_type cholesky or lu); it factorizes B. Throws
/// InputError (every rank) on mismatched sizes, non-finite input, alpha <= 0 or above
/// max_regularization_alpha, a vertex without area; SolverError from the solver (B not positive
/// definite: L not negative semi-definite) or when CG stops short. CG starts from `start` (#owned
/// x 3, finite: e.g. an earlier trial's positions) when given, else from 0. Collective.
DistributedRegularization distributed_regularize_positions(const DistributedSurface& surface, const DistributedFem& fem,
                                                           const Eigen::MatrixX3d& p, const Eigen::MatrixX3d& normals,
                                                           const Eigen::VectorXd& H, double alpha,
                                                           PetscLinearSolver& solver, double accuracy = 0.0,
                                                           const Eigen::MatrixX3d* start = nullptr);

/// attachment_bias(faces, staircase, result, normals, mass, step, rounds) of the whole surface
/// (docs/math.md §9.4), from the owned vertices' rows of each rank (#owned each; mass: the row
/// sums of M). The averaging rounds are products with the edge-count matrix of the faces,
/// assembled like L; the same sums in another order, so equal to rounding. Throws InputError
/// (every rank) as attachment_bias. Collective.
double distributed_attachment_bias(const DistributedSurface& surface, const Eigen::MatrixX3d& staircase,
                                   const Eigen::MatrixX3d& result, const Eigen::MatrixX3d& normals,
                                   const Eigen::VectorXd& mass, double step, int rounds = kAttachmentBiasRounds);

/// regularization_energy(L, M, p, normals, H, q) of the whole surface (docs/math.md §9.2's two
/// terms), from the owned vertices' rows of each rank. Collective.
RegularizationEnergy distributed_regularization_energy(const DistributedSurface& surface, const DistributedFem& fem,
                                                       const Eigen::MatrixX3d& p, const Eigen::MatrixX3d& normals,
                                                       const Eigen::VectorXd& H, const Eigen::MatrixX3d& q);

}  // namespace corrlap
