#include "distributed_regularization.hpp"

#include <mpi.h>
#include <petscmat.h>

#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/core/linear_solver.hpp>
#include <corrlap/regularization/laplacian_regularization.hpp>
#include <limits>
#include <string>

#include "detail/owned_vectors.hpp"
#include "detail/petsc_matrices.hpp"

namespace corrlap {

namespace {

using detail::global_max;
using detail::global_sum;
using detail::owned_vector;
using detail::petsc_check;
using detail::PetscMatOwner;
using detail::PetscVecOwner;

// A X, column by column, at the owned rows.
Eigen::MatrixXd product(Mat A, const DistributedSurface& s, const Eigen::MatrixXd& X) {
  Eigen::MatrixXd Y(X.rows(), X.cols());
  for (Eigen::Index j = 0; j < X.cols(); ++j) Y.col(j) = detail::product(A, s, X.col(j));
  return Y;
}

// The column-wise inner products over the ranks.
Eigen::VectorXd dots(const Eigen::MatrixXd& X, const Eigen::MatrixXd& Y) {
  Eigen::VectorXd d = (X.array() * Y.array()).colwise().sum().transpose();
  MPI_Allreduce(MPI_IN_PLACE, d.data(), int(d.size()), MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  return d;
}

// The same InputError on every rank when any rank's check fails.
void check_everywhere(bool ok_here, const std::string& message, const char* option = "") {
  int bad = ok_here ? 0 : 1;
  MPI_Allreduce(MPI_IN_PLACE, &bad, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  if (bad) throw InputError(message, option);
}

}  // namespace

DistributedRegularization distributed_regularize_positions(const DistributedSurface& s, const DistributedFem& fem,
                                                           const Eigen::MatrixX3d& p, const Eigen::MatrixX3d& normals,
                                                           const Eigen::VectorXd& H, double alpha,
                                                           PetscLinearSolver& solver, double accuracy,
                                                           const Eigen::MatrixX3d* start) {
  const Eigen::Index n = s.num_owned;
  check_everywhere(p.rows() == n && normals.rows() == n && H.size() == n,
                   "regularization: positions, normals and H need one row per owned vertex");
  check_everywhere(p.allFinite() && normals.allFinite() && H.allFinite(),
                   "regularization: positions, normals and H must be finite");
  check_everywhere(n == 0 || (normals.rowwise().norm().array() - 1.0).abs().maxCoeff() <= 1e-6,
                   "regularization: the normals must be unit vectors");
  check_everywhere(accuracy >= 0.0 && std::isfinite(accuracy),
                   "regularization: the solve accuracy must be a finite number >= 0", "accuracy");
  check_everywhere(!start || (start->rows() == n && start->allFinite()),
                   "regularization: the start positions must be finite, one row per owned vertex", "start");
  const DistributedFem::Impl& ops = fem.impl();

  // M_l = diag(M 1), as lumped_mass.
  const Eigen::VectorXd mass = detail::product(ops.M, s, Eigen::VectorXd::Ones(n));
  check_everywhere(n == 0 || mass.minCoeff() > 0.0,
                   "regularization: a vertex has no area (a row sum of M is not positive)");
  const double area = global_sum(mass.sum());
  const double reach = global_max(n > 0 ? p.cwiseAbs().maxCoeff() : 0.0);
  if (!(alpha > 0.0) || !std::isfinite(alpha))
    throw InputError("regularization: alpha must be a positive number", "alpha");
  if (alpha > max_regularization_alpha(area, reach))
    throw InputError("regularization: alpha = " + std::to_string(alpha) +
                         " is beyond what the solve represents in double precision on this surface",
                     "alpha");
  const Eigen::VectorXd inverse_mass = mass.cwiseInverse();

  // b = alpha M_l p - 2 L (H n).
  const Eigen::MatrixXd Hn = normals.array().colwise() * H.array();
  const Eigen::MatrixXd rhs = alpha * (mass.asDiagonal() * p) - 2.0 * product(ops.L, s, Hn);

  // B = sqrt(alpha) M_l - L, factorized once.
  PetscMatOwner B;
  petsc_check(MatDuplicate(ops.L, MAT_COPY_VALUES, B.out()), "MatDuplicate");
  petsc_check(MatScale(B, -1.0), "MatScale");
  {
    PetscVecOwner diagonal;
    owned_vector(s, std::sqrt(alpha) * mass, diagonal);
    petsc_check(MatDiagonalSet(B, diagonal, ADD_VALUES), "MatDiagonalSet");
  }
  petsc_check(MatSetOption(B, MAT_SYMMETRIC, PETSC_TRUE), "MatSetOption");
  solver.factorize_distributed(detail::PetscDistributedMatrix{B});

  const auto multiply = [&](const Eigen::MatrixXd& X) -> Eigen::MatrixXd {
    return product(ops.L, s, Eigen::MatrixXd(inverse_mass.asDiagonal() * product(ops.L, s, X))) +
           alpha * (mass.asDiagonal() * X);
  };
  // P^{-1} = B^{-1} M_l B^{-1}.
  const auto precondition = [&](const Eigen::MatrixXd& R) -> Eigen::MatrixXd {
    return solver.solve_distributed(mass.asDiagonal() * solver.solve_distributed(R));
  };
  // The header's bound, sqrt(2 r^T P^{-1} r / (alpha area)), worst column, from r^T z.
  const auto bound_of = [&](const Eigen::VectorXd& rz) {
    return std::sqrt(2.0 * std::max(rz.maxCoeff(), 0.0) / (alpha * area));
  };
  const Eigen::VectorXd rhs_norms = dots(rhs, rhs).cwiseSqrt().cwiseMax(std::numeric_limits<double>::min());
  const auto relative = [&](const Eigen::MatrixXd& R) {
    return (dots(R, R).cwiseSqrt().array() / rhs_norms.array()).maxCoeff();
  };

  // Block CG, the three coordinates in step (one product and one preconditioning per iteration,
  // column-wise scalars), restarted from the true residual (at most 3 passes) against the drift
  // of its recurrence, as the serial solve does.
  constexpr int kMaxIterations = 1000;
  DistributedRegularization out;
  // Not from p when no start is given: L p is the staircase's Laplacian, so |b - A p| is orders of
  // magnitude above |b|.
  Eigen::MatrixXd q = Eigen::MatrixXd::Zero(n, 3), R = rhs;
  if (start) {
    q = *start;
    R = rhs - multiply(q);
  }
  double normwise = relative(R), bound = std::numeric_limits<double>::infinity();
  const auto done = [&] { return normwise <= 1e-10 || (accuracy > 0.0 && bound <= accuracy); };
  for (int pass = 0; pass < 3 && !done(); ++pass) {
    Eigen::MatrixXd Z = precondition(R), D = Z;
    Eigen::VectorXd rz = dots(R, Z);
    bound = bound_of(rz);
    // Each pass aims at 1e-11 of b on its recurrence (or half the accuracy): the true residual
    // below decides.
    for (int k = 0; k < kMaxIterations; ++k) {
      const bool small = relative(R) <= 1e-11 || (accuracy > 0.0 && bound <= 0.5 * accuracy);
      if (small) break;
      const Eigen::MatrixXd AD = multiply(D);
      const Eigen::VectorXd dAd = dots(D, AD);
      for (Eigen::Index j = 0; j < 3; ++j) {
        if (!(dAd[j] > 0.0)) continue;  // this coordinate has converged (D = 0)
        const double step = rz[j] / dAd[j];
        q.col(j) += step * D.col(j);
        R.col(j) -= step * AD.col(j);
      }
      Z = precondition(R);
      const Eigen::VectorXd rz_next = dots(R, Z);
      for (Eigen::Index j = 0; j < 3; ++j) D.col(j) = Z.col(j) + (rz[j] > 0.0 ? rz_next[j] / rz[j] : 0.0) * D.col(j);
      rz = rz_next;
      bound = bound_of(rz);
      ++out.iterations;
    }
    R = rhs - multiply(q);  // the true residual
    normwise = relative(R);
    bound = bound_of(dots(R, precondition(R)));
  }
  out.positions = q;
  out.residual = normwise;
  out.error_bound = bound;
  if (!done())
    throw SolverError(SolverStatus::NoConvergence, "regularization: CG stopped at a relative residual of " +
                                                       std::to_string(normwise) + " and an error bound of " +
                                                       std::to_string(bound) + " after " +
                                                       std::to_string(out.iterations) + " iterations");
  return out;
}

double distributed_attachment_bias(const DistributedSurface& s, const Eigen::MatrixX3d& staircase,
                                   const Eigen::MatrixX3d& result, const Eigen::MatrixX3d& normals,
                                   const Eigen::VectorXd& mass, double step, int rounds) {
  const Eigen::Index n = s.num_owned;
  check_everywhere(staircase.rows() == n && result.rows() == n && normals.rows() == n && mass.size() == n,
                   "attachment_bias: staircase, result, normals and mass need one row per owned vertex");
  if (!(step > 0.0) || !std::isfinite(step)) throw InputError("attachment_bias: the step must be a positive number");
  if (rounds < 0) throw InputError("attachment_bias: the number of rounds must be >= 0");
  if (s.num_vertices == 0) return 0.0;
  // E: for every face edge (a, b), 1 at (a, b) and at (b, a), summed over the faces.
  std::vector<PetscInt> i, j;
  const SurfelMesh& mesh = s.mesh;
  i.reserve(8 * std::size_t(mesh.num_faces()));
  j.reserve(8 * std::size_t(mesh.num_faces()));
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int k = 0; k < 4; ++k) {
      const PetscInt a = PetscInt(s.rows[std::size_t(mesh.faces(f, k))]);
      const PetscInt b = PetscInt(s.rows[std::size_t(mesh.faces(f, (k + 1) % 4))]);
      i.insert(i.end(), {a, b});
      j.insert(j.end(), {b, a});
    }
  PetscMatOwner E;
  detail::coo_matrix(s, i, j, std::vector<PetscScalar>(i.size(), 1.0), E);
  const Eigen::VectorXd count = Eigen::VectorXd::Ones(n) + detail::product(E, s, Eigen::VectorXd::Ones(n));
  Eigen::VectorXd bias = ((staircase - result).cwiseProduct(normals)).rowwise().sum() / step;
  for (int round = 0; round < rounds; ++round) bias = (bias + detail::product(E, s, bias)).cwiseQuotient(count);
  const double total = global_sum(mass.sum());
  if (!(total > 0.0)) throw InputError("attachment_bias: the masses must sum to a positive number");
  return global_sum(bias.cwiseAbs().dot(mass)) / total;
}

}  // namespace corrlap
