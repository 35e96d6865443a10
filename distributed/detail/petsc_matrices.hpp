#pragma once
// The PETSc side of DistributedFem (internal: only distributed/ sees PETSc's headers), and the
// error check of the PETSc calls made here (the backend's).
#include <petscmat.h>

#include <corrlap/backends/detail/petsc_objects.hpp>
#include <corrlap/backends/petsc.hpp>
#include <vector>

#include "../distributed_fem.hpp"
#include "../distributed_surface.hpp"

namespace corrlap {

struct DistributedFem::Impl {
  detail::PetscMatOwner L, M;
};

namespace detail {
/// PETSc calls of distributed/ fail like the backend's (backends/petsc.hpp).
inline void petsc_check(PetscErrorCode code, const char* call) { check_petsc_call(code, call); }

/// A symmetric MPIAIJ matrix (#V by #V, rank-major rows, the rank's owned rows here) from triplets
/// i, j, values of any rows: COO assembly, PETSc sums repeated (i, j) and sends the entries of
/// other ranks' rows to them. Collective.
void coo_matrix(const DistributedSurface& s, const std::vector<PetscInt>& i, const std::vector<PetscInt>& j,
                const std::vector<PetscScalar>& values, PetscMatOwner& A);
}  // namespace detail

}  // namespace corrlap
