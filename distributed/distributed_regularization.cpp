#include "distributed_regularization.hpp"

#include <mpi.h>
#include <petscmat.h>

#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/core/linear_solver.hpp>
#include <corrlap/regularization/laplacian_regularization.hpp>
#include <string>
#include <vector>

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

  // |L| for the backward error, assembled from L's entries like L.
  PetscMatOwner absL;
  {
    std::vector<PetscInt> i, j;
    std::vector<PetscScalar> values;
    for (const DistributedFem::Entry& e : fem.owned_entries(DistributedFem::Which::L)) {
      i.push_back(PetscInt(e.row));
      j.push_back(PetscInt(e.column));
      values.push_back(std::abs(e.value));
    }
    detail::coo_matrix(s, i, j, values, absL);
  }
  // The serial solve's iteration (solve_preconditioned) on this rank's rows, its sums over the ranks.
  PreconditionedSystem system;
  system.rows = n;
  system.total_rows = s.num_vertices;
  system.alpha = alpha;
  system.area = area;
  system.multiply = [&](const Eigen::MatrixXd& X) -> Eigen::MatrixXd {
    return product(ops.L, s, Eigen::MatrixXd(inverse_mass.asDiagonal() * product(ops.L, s, X))) +
           alpha * (mass.asDiagonal() * X);
  };
  // P^{-1} = B^{-1} M_l B^{-1}.
  system.precondition = [&](const Eigen::MatrixXd& R) -> Eigen::MatrixXd {
    return solver.solve_distributed(mass.asDiagonal() * solver.solve_distributed(R));
  };
  system.absolute_multiply = [&](const Eigen::MatrixXd& X) -> Eigen::MatrixXd {
    return product(absL, s, Eigen::MatrixXd(inverse_mass.asDiagonal() * product(absL, s, X))) +
           alpha * (mass.asDiagonal() * X);
  };
  system.sum_over_parts = [](Eigen::ArrayXd& sums) {
    MPI_Allreduce(MPI_IN_PLACE, sums.data(), int(sums.size()), MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  };
  system.max_over_parts = [](double x) { return global_max(x); };
  SolverReport report;
  DistributedRegularization out;
  const Eigen::MatrixXd start_columns = start ? Eigen::MatrixXd(*start) : Eigen::MatrixXd();
  out.positions =
      solve_preconditioned(system, rhs, start ? &start_columns : nullptr, accuracy, &report, &out.error_bound);
  out.iterations = report.iterations;
  out.residual = report.residual;
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

RegularizationEnergy distributed_regularization_energy(const DistributedSurface& s, const DistributedFem& fem,
                                                       const Eigen::MatrixX3d& p, const Eigen::MatrixX3d& normals,
                                                       const Eigen::VectorXd& H, const Eigen::MatrixX3d& q) {
  const Eigen::Index n = s.num_owned;
  check_everywhere(p.rows() == n && normals.rows() == n && H.size() == n && q.rows() == n,
                   "regularization energy: p, q, normals and H need one row per owned vertex");
  const DistributedFem::Impl& ops = fem.impl();
  const Eigen::VectorXd mass = detail::product(ops.M, s, Eigen::VectorXd::Ones(n));
  const Eigen::MatrixXd Hn = normals.array().colwise() * H.array();
  const Eigen::MatrixXd residual = mass.cwiseInverse().asDiagonal() * product(ops.L, s, Eigen::MatrixXd(q)) + 2.0 * Hn;
  RegularizationEnergy e;
  e.laplacian = global_sum((mass.asDiagonal() * residual.cwiseAbs2()).sum());
  e.attachment = global_sum((mass.asDiagonal() * (q - p).cwiseAbs2()).sum());
  return e;
}

}  // namespace corrlap
