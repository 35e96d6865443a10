#pragma once
// The PETSc side of DistributedFem (internal: only distributed/ sees PETSc's headers), and the
// error check of the PETSc calls made here (the backend's).
#include <petscmat.h>

#include <corrlap/backends/detail/petsc_objects.hpp>
#include <corrlap/backends/petsc.hpp>

#include "../distributed_fem.hpp"

namespace corrlap {

struct DistributedFem::Impl {
  detail::PetscMatOwner L, M;
};

namespace detail {
/// PETSc calls of distributed/ fail like the backend's (backends/petsc.hpp).
inline void petsc_check(PetscErrorCode code, const char* call) { check_petsc_call(code, call); }
}  // namespace detail

}  // namespace corrlap
