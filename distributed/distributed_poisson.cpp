#include "distributed_poisson.hpp"

#include <mpi.h>
#include <petscmat.h>

#include <algorithm>
#include <cmath>

#include "detail/owned_vectors.hpp"
#include "detail/petsc_matrices.hpp"

namespace corrlap {

namespace {

using detail::global_max;
using detail::global_sum;
using detail::owned_values;
using detail::owned_vector;
using detail::petsc_check;
using detail::PetscMatOwner;
using detail::PetscVecOwner;
using detail::product;

}  // namespace

DistributedPoissonResult distributed_solve_poisson(const DistributedSurface& s, const DistributedFem& fem,
                                                   const TestFunction& function, PetscLinearSolver& solver,
                                                   const Eigen::Vector3d& center) {
  const DistributedFem::Impl& ops = fem.impl();
  const Eigen::Index n = s.num_owned;
  const TestFunctionSamples samples = sample_on_unit_sphere(function, s.mesh.positions.topRows(n), center);
  const Eigen::VectorXd& f = samples.f;
  const Eigen::VectorXd& b = samples.laplacian;

  // The pinned vertex is serial vertex 0 (docs/math.md §10.4: g_0 = f(q_0)), on one rank.
  double pin_row = -1.0, pin_value = 0.0;
  for (Eigen::Index v = 0; v < n; ++v)
    if (s.vertex_ids[std::size_t(v)] == 0) pin_row = double(s.row_begin + v), pin_value = f[v];
  pin_row = global_max(pin_row);
  pin_value = global_sum(pin_value);

  // Compatibility projection b_c = b - (1^T M b) / (1^T M 1) (M symmetric: 1^T M b = (M 1)^T b).
  const Eigen::VectorXd m1 = product(ops.M, s, Eigen::VectorXd::Ones(n));
  const double area = global_sum(m1.sum());
  const Eigen::VectorXd bc = b.array() - global_sum(m1.dot(b)) / area;
  const Eigen::VectorXd Mbc = product(ops.M, s, bc);

  // -L g = -M b_c with the pinned row and column eliminated (their column moves to the right-hand
  // side, the row becomes g_pin = f(q_0)): symmetric positive definite.
  PetscMatOwner A;
  petsc_check(MatDuplicate(ops.L, MAT_COPY_VALUES, A.out()), "MatDuplicate");
  petsc_check(MatScale(A, -1.0), "MatScale");
  PetscVecOwner rhs, x;
  owned_vector(s, -Mbc, rhs);
  petsc_check(VecDuplicate(rhs, x.out()), "VecDuplicate");
  // MatZeroRowsColumns reads all of x (0 times garbage can be NaN): zero except the pinned value.
  petsc_check(VecSet(x, 0.0), "VecSet");
  const PetscInt pin = PetscInt(pin_row);
  const bool owner = pin >= s.row_begin && pin < s.row_begin + n;
  if (owner) petsc_check(VecSetValue(x, pin, pin_value, INSERT_VALUES), "VecSetValue");
  petsc_check(VecAssemblyBegin(x), "VecAssemblyBegin");
  petsc_check(VecAssemblyEnd(x), "VecAssemblyEnd");
  petsc_check(MatZeroRowsColumns(A, owner ? 1 : 0, &pin, 1.0, x, rhs), "MatZeroRowsColumns");
  // Flagged symmetric like the petsc backend's matrices (MUMPS's symmetric mode, CG).
  petsc_check(MatSetOption(A, MAT_SYMMETRIC, PETSC_TRUE), "MatSetOption");

  // The backend's one KSP set-up: every option, its reports and failures.
  DistributedPoissonResult result;
  solver.factorize_distributed(detail::PetscDistributedMatrix{A});
  result.g = solver.solve_distributed(owned_values(rhs));
  result.report = solver.info();

  // neumann_residual and poisson_errors of problems.hpp, as sums over the ranks.
  Eigen::VectorXd r = product(ops.L, s, result.g) - Mbc;
  if (owner) r[pin - PetscInt(s.row_begin)] = 0.0;
  result.residual = std::sqrt(global_sum(r.squaredNorm())) / std::max(std::sqrt(global_sum(Mbc.squaredNorm())), 1e-300);
  const double mean_g = global_sum(m1.dot(result.g)) / area, mean_f = global_sum(m1.dot(f)) / area;
  const Eigen::VectorXd e = (result.g.array() - mean_g) - (f.array() - mean_f);
  result.errors.linf = global_max(e.size() > 0 ? e.lpNorm<Eigen::Infinity>() : 0.0);
  result.errors.l2 = std::sqrt(global_sum(e.dot(product(ops.M, s, e))) / area);
  return result;
}

Eigen::VectorXd gather_on_rank0(const DistributedSurface& s, const Eigen::VectorXd& owned) {
  const int count = s.num_owned;
  std::vector<int> counts(std::size_t(s.ranks)), offsets(std::size_t(s.ranks), 0);
  MPI_Gather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
  for (int r = 1; r < s.ranks; ++r) offsets[std::size_t(r)] = offsets[std::size_t(r - 1)] + counts[std::size_t(r - 1)];
  const bool root = s.rank == 0;
  std::vector<std::int64_t> ids(root ? std::size_t(s.num_vertices) : 0);
  std::vector<double> values(root ? std::size_t(s.num_vertices) : 0);
  MPI_Gatherv(s.vertex_ids.data(), count, MPI_INT64_T, ids.data(), counts.data(), offsets.data(), MPI_INT64_T, 0,
              MPI_COMM_WORLD);
  MPI_Gatherv(owned.data(), count, MPI_DOUBLE, values.data(), counts.data(), offsets.data(), MPI_DOUBLE, 0,
              MPI_COMM_WORLD);
  Eigen::VectorXd whole(root ? s.num_vertices : 0);
  for (std::size_t k = 0; k < ids.size(); ++k) whole[Eigen::Index(ids[k])] = values[k];
  return whole;
}

}  // namespace corrlap
