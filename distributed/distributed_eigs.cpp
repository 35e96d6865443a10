#include "distributed_eigs.hpp"

#include "detail/petsc_matrices.hpp"

namespace corrlap {

EigenResult distributed_eigs(const DistributedFem& fem, int k, SlepcEigenSolver& solver) {
  const DistributedFem::Impl& ops = fem.impl();
  return solver.solve_distributed(detail::PetscDistributedMatrix{ops.L}, detail::PetscDistributedMatrix{ops.M}, k);
}

}  // namespace corrlap
