#pragma once
// The PETSc side of the petsc and slepc backends that the distributed front end (distributed/)
// shares with them: the owner of PETSc objects and the handle through which a matrix that is
// already spread over the ranks reaches the backends. Internal (never installed), so PETSc's
// headers stay out of every public header.
#include <petscmat.h>

#include <corrlap/backends/petsc.hpp>

namespace corrlap::detail {

/// False after PETSc is finalized: objects destroyed later (statics) must not call it.
bool petsc_alive();

/// A PETSc object destroyed with its owner, and never after PETSc is finalized. The one owner of
/// PETSc objects in backends/ and distributed/: no manual destroy calls on any exit path.
template <class T, PetscErrorCode (*destroy)(T*)>
class PetscOwned {
 public:
  PetscOwned() = default;
  PetscOwned(const PetscOwned&) = delete;
  PetscOwned& operator=(const PetscOwned&) = delete;
  ~PetscOwned() { reset(); }
  void reset() {
    if (handle_ != nullptr && petsc_alive()) destroy(&handle_);
    handle_ = nullptr;
  }
  /// For the Create calls: the old object is destroyed first.
  T* out() {
    reset();
    return &handle_;
  }
  /// Another owner of `handle` (PETSc's reference count): each owner destroys its own reference.
  void share(T handle) {
    if (handle != nullptr)
      check_petsc_call(PetscObjectReference(reinterpret_cast<PetscObject>(handle)), "PetscObjectReference");
    reset();
    handle_ = handle;
  }
  operator T() const { return handle_; }
  explicit operator bool() const { return handle_ != nullptr; }

 private:
  T handle_ = nullptr;
};
using PetscMatOwner = PetscOwned<Mat, MatDestroy>;
using PetscVecOwner = PetscOwned<Vec, VecDestroy>;

/// A square symmetric AIJ matrix on PETSC_COMM_WORLD whose rows are already spread over the ranks
/// in contiguous blocks, rank after rank (the distributed front end's L and M): the backends'
/// distributed entry points (PetscLinearSolver::factorize_distributed,
/// SlepcEigenSolver::solve_distributed) take it as it is, without gathering it.
struct PetscDistributedMatrix {
  Mat mat = nullptr;
};

}  // namespace corrlap::detail
