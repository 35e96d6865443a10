#pragma once
// The PETSc side of DistributedFem (internal: only distributed/ sees PETSc's headers), and the
// error check of the PETSc calls made here.
#include <petscmat.h>

#include <corrlap/core/linear_solver.hpp>
#include <string>

#include "../distributed_fem.hpp"

namespace corrlap {

struct DistributedFem::Impl {
  Mat L = nullptr, M = nullptr;
  ~Impl() {
    PetscBool finalized = PETSC_FALSE;
    PetscFinalized(&finalized);
    if (finalized == PETSC_FALSE) {
      MatDestroy(&L);
      MatDestroy(&M);
    }
  }
};

namespace detail {
/// Throws SolverError naming the PETSc call that failed.
inline void petsc_check(PetscErrorCode code, const char* call) {
  if (code == 0) return;
  const char* text = nullptr;
  PetscErrorMessage(code, &text, nullptr);
  throw SolverError(SolverStatus::NumericalIssue,
                    std::string("distributed: ") + call + ": " + (text != nullptr ? text : "PETSc error"));
}
}  // namespace detail

}  // namespace corrlap
