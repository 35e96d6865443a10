#pragma once
// Vectors of the rows a rank owns (DistributedSurface::rows), moved between Eigen and PETSc, and
// the sums over the ranks of distributed/'s solves (internal).
#include <mpi.h>
#include <petscmat.h>

#include <Eigen/Core>
#include <algorithm>

#include "../distributed_surface.hpp"
#include "petsc_matrices.hpp"

namespace corrlap::detail {

/// A PETSc vector of the rows owned here with the given values (#owned).
inline void owned_vector(const DistributedSurface& s, const Eigen::VectorXd& values, PetscVecOwner& v) {
  petsc_check(VecCreateMPI(PETSC_COMM_WORLD, s.num_owned, PetscInt(s.num_vertices), v.out()), "VecCreateMPI");
  PetscScalar* local = nullptr;
  petsc_check(VecGetArray(v, &local), "VecGetArray");
  std::copy(values.data(), values.data() + values.size(), local);
  petsc_check(VecRestoreArray(v, &local), "VecRestoreArray");
}

/// The values of the rows owned here.
inline Eigen::VectorXd owned_values(Vec v) {
  PetscInt n = 0;
  petsc_check(VecGetLocalSize(v, &n), "VecGetLocalSize");
  const PetscScalar* local = nullptr;
  petsc_check(VecGetArrayRead(v, &local), "VecGetArrayRead");
  Eigen::VectorXd values = Eigen::Map<const Eigen::VectorXd>(local, n);
  petsc_check(VecRestoreArrayRead(v, &local), "VecRestoreArrayRead");
  return values;
}

/// A x at the owned rows, x given at the owned rows. Collective.
inline Eigen::VectorXd product(Mat A, const DistributedSurface& s, const Eigen::VectorXd& x) {
  PetscVecOwner in, out;
  owned_vector(s, x, in);
  petsc_check(VecDuplicate(in, out.out()), "VecDuplicate");
  petsc_check(MatMult(A, in, out), "MatMult");
  return owned_values(out);
}

/// Sums and maxima over the ranks. Collective.
inline double global_sum(double x) {
  MPI_Allreduce(MPI_IN_PLACE, &x, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  return x;
}
inline double global_max(double x) {
  MPI_Allreduce(MPI_IN_PLACE, &x, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  return x;
}

}  // namespace corrlap::detail
